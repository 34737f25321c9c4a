//! The geometric toolkit no method owns: generalized spheres ([`sphere`]), circles, the absolute
//! sphere Ω, closest points on triangle meshes, small dense linear algebra and the meshes
//! themselves.

pub mod absolute_sphere;
pub mod circle;
pub mod closest;
pub mod linalg;
pub mod mesh;
pub mod sphere;
