//! Why the SQ method cannot run, or stopped (Sec. 5, Sec. 6.3).

use std::fmt;

use crate::progress::Cancelled;
use crate::remeshing::quad_remeshing::QuadRemeshError;

use super::params::ParamError;

/// Why the SQ method cannot run (or stopped).
#[derive(Clone, Debug, PartialEq)]
pub enum SqError {
    /// The reference is a mesh.
    NotBSpline,
    /// A parameter out of range.
    Parameter(ParamError),
    /// S_u × S_v vanishes at a point of G.
    Singular {
        uv: [f64; 2],
    },
    /// H takes both signs (Sec. 6.3): area shares of H > 0 and H < 0, and where the other sign
    /// is strongest inside the patch.
    MeanCurvatureSignChange {
        positive_share: f64,
        negative_share: f64,
        at: Option<[f64; 2]>,
    },
    /// |H| · diag below [`super::radius::MIN_MEAN_CURVATURE`] at a point of G.
    MeanCurvatureNearZero {
        uv: [f64; 2],
        h_diag: f64,
    },
    RadiusBasis(String),
    /// Too few samples for the radius basis.
    RadiusFit {
        samples: usize,
        coefficients: usize,
    },
    /// c_u × c_v vanishes: the spheres do not vary (e.g. a sphere patch's central spheres).
    SingularCentreSurface {
        points: usize,
        total: usize,
    },
    /// No grid quad has real torsal directions to remesh along.
    NoTorsalField,
    /// The quad remeshing failed (Sec. 5.2).
    Remesh(QuadRemeshError),
    /// The final optimization left a face sphere or vertex undefined (NaN) or a vertex without
    /// its spheres' exact intersection (Sec. 5.2).
    FinalOptimization(String),
    Cancelled,
}

impl fmt::Display for SqError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SqError::NotBSpline => {
                f.write_str("SQ meshes need a B-spline reference surface (Sec. 5): load a B-spline .json file or the vault sample")
            }
            SqError::Parameter(e) => e.fmt(f),
            SqError::Singular { uv } => {
                write!(f, "the surface has no normal at (u, v) = ({:.6}, {:.6}) (S_u × S_v = 0)", uv[0], uv[1])
            }
            SqError::MeanCurvatureSignChange { positive_share, negative_share, at } => write!(
                f,
                "the central start needs a mean curvature of one sign (Sec. 6.3), but H > 0 on {:.1} % of the area and H < 0 on \
                 {:.1} %{}. Where H = 0 the central spheres become planes (radius 1/H unbounded), so the sphere congruence \
                 cannot start from them there; choose the starting congruence 'auto' or 'constant' (constant radii) instead.",
                100.0 * positive_share,
                100.0 * negative_share,
                at.map_or(String::new(), |[u, v]| format!(", the other sign strongest at (u, v) = ({u:.3}, {v:.3})"))
            ),
            SqError::MeanCurvatureNearZero { uv, h_diag } => write!(
                f,
                "the mean curvature nearly vanishes at (u, v) = ({:.4}, {:.4}) (|H| · diagonal = {:.2e}): the central sphere \
                 there is almost a plane (Sec. 6.3); choose the starting congruence 'auto' or 'constant' (constant radii) instead.",
                uv[0],
                uv[1],
                h_diag.abs()
            ),
            SqError::RadiusBasis(m) => write!(f, "radius basis: {m}"),
            SqError::RadiusFit { samples, coefficients } => {
                write!(f, "{samples} radius samples cannot determine {coefficients} coefficients: use a finer grid or a smaller radius basis")
            }
            SqError::SingularCentreSurface { points, total } => write!(
                f,
                "the line congruence is undefined at {points} of {total} grid points: the centre surface c = f + r n is \
                 singular there (c_u × c_v = 0), as on a sphere patch, whose central spheres all coincide"
            ),
            SqError::NoTorsalField => f.write_str("no quad of the grid has real torsal directions: there is no cross field to remesh along"),
            SqError::Remesh(e) => write!(f, "quad remeshing along the torsal directions: {e}"),
            SqError::FinalOptimization(m) => write!(f, "final sphere optimization: {m}"),
            SqError::Cancelled => f.write_str("cancelled"),
        }
    }
}

impl std::error::Error for SqError {}

impl From<Cancelled> for SqError {
    fn from(_: Cancelled) -> Self {
        SqError::Cancelled
    }
}

impl From<QuadRemeshError> for SqError {
    fn from(e: QuadRemeshError) -> Self {
        SqError::Remesh(e)
    }
}
