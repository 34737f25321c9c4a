//! B-spline and NURBS geometry (Sec. 5): univariate bases ([`basis`]), tensor-product surfaces
//! with exact derivatives and differential geometry ([`surface`]), and scalar B-spline functions
//! with their least-squares fit ([`function`], the radius function of Eq. 8).

pub mod basis;
pub mod function;
pub mod surface;

pub use basis::{BSplineBasis, BasisError, BasisValues, MAX_DEGREE};
pub use function::{BSplineFunction, FitError, FunctionRow};
pub use surface::{BSplineSurface, SurfaceDerivatives, SurfaceError, SurfaceFrame};
