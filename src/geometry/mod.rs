//! The geometric toolkit no method owns: generalized spheres ([`sphere`]), circles, the absolute
//! sphere Ω, B-spline surfaces and functions ([`bspline`]), closest points on triangle meshes, small dense linear algebra and the meshes
//! themselves.

pub mod absolute_sphere;
pub mod bspline;
pub mod circle;
pub mod closest;
pub mod dual;
pub mod linalg;
pub mod mesh;
pub mod pencil;
pub mod rational_bezier;
pub mod rigid_alignment;
pub mod sphere;
