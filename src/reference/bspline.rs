//! A B-spline reference surface f(u, v) (Sec. 5): its tessellation (a quad grid in (u, v), fine
//! enough that its chords stay within [`TESSELLATION_TOLERANCE`] of the surface, so the app can
//! show it and the mesh methods can run on it), the exact closest point with its (u, v) (Newton
//! on the squared distance, started at the tessellation's closest point and kept in the domain),
//! the exact curvature at the tessellation's vertices, and the ranges of H and K.

// Negated float comparisons are deliberate: they also reject NaN.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::congruence::central_spheres::{CurvatureField, VertexCurvature};
use crate::geometry::bspline::surface::TESSELLATION_TOLERANCE;
use crate::geometry::bspline::{BSplineSurface, SurfaceDerivatives};
use crate::geometry::mesh::PolyMesh;

/// Why a B-spline surface cannot be a reference.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SplineReferenceError {
    /// S_u × S_v vanishes at (u, v) (a pole or a fold): no normal there.
    Singular { uv: [f64; 2] },
}

impl std::fmt::Display for SplineReferenceError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SplineReferenceError::Singular { uv } => write!(
                f,
                "the surface has no normal at (u, v) = ({:.6}, {:.6}) (S_u × S_v = 0: a pole or a collapsed edge); \
                 such surfaces are not supported",
                uv[0], uv[1]
            ),
        }
    }
}

impl std::error::Error for SplineReferenceError {}

/// What the app and the CLI tell about a B-spline reference.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BSplineInfo {
    pub degree: [usize; 2],
    /// Control points along U and V.
    pub control: [usize; 2],
    pub domain: [[f64; 2]; 2],
    pub rational: bool,
    /// Tessellation segments along U and V.
    pub tessellation: [usize; 2],
    /// Ranges of H and K over a fine grid of the domain.
    pub mean_curvature: [f64; 2],
    pub gauss_curvature: [f64; 2],
}

/// A Newton step of the closest-point search that moves the point by less than this (relative to
/// 1 + |S|) is its last: the error after a step of length h is O(h²) (quadratic convergence), so
/// below about √ε the point is exact to rounding.
const CONVERGED_STEP: f64 = 1e-9;

/// The surface with its tessellation's parameters.
#[derive(Clone, Debug)]
pub struct SplineReference {
    pub surface: BSplineSurface,
    /// (u, v) of every tessellation vertex.
    pub uv: Vec<[f64; 2]>,
    /// Segments along U and V.
    pub segments: [usize; 2],
}

impl SplineReference {
    /// The tessellation (quads (i, j), (i+1, j), (i+1, j+1), (i, j+1), counter-clockwise about
    /// S_u × S_v) and its vertices' parameters.
    pub fn new(surface: BSplineSurface) -> Result<(Self, PolyMesh), SplineReferenceError> {
        let segments = surface.tessellation_segments(TESSELLATION_TOLERANCE);
        let (mesh, uv) = surface.tessellate(segments);
        if let Some(p) = uv.iter().find(|p| surface.derivatives(p[0], p[1]).normal().is_none()) {
            return Err(SplineReferenceError::Singular { uv: *p });
        }
        Ok((Self { surface, uv, segments }, mesh))
    }

    /// The closest point of the surface to `p`, from the parameters `start` (Newton on
    /// ½|S − p|², box-constrained to the domain): (u, v), the point and its unit normal.
    ///
    /// Newton converges quadratically: once a Newton step moves the point by less than
    /// [`CONVERGED_STEP`] × (1 + |S|), the point after it is exact to rounding, and the loop ends
    /// there, without another step that could only confirm it (whose halvings, at rounding
    /// level, would each cost an evaluation of the surface).
    pub fn closest_point(&self, p: DVec3, start: [f64; 2]) -> ([f64; 2], DVec3, Option<DVec3>) {
        let s = &self.surface;
        let ((u0, u1), (v0, v1)) = s.domain();
        let mut uv = s.clamp(start);
        let mut d = s.derivatives(uv[0], uv[1]);
        let mut dist2 = (d.s - p).length_squared();
        for _ in 0..30 {
            let r = d.s - p;
            let g = [d.su.dot(r), d.sv.dot(r)];
            let (e, f, gg) = (d.su.dot(d.su), d.su.dot(d.sv), d.sv.dot(d.sv));
            // Newton's Hessian when positive definite, else Gauss–Newton's [[E, F], [F, G]].
            let (a, b, c) = (e + d.suu.dot(r), f + d.suv.dot(r), gg + d.svv.dot(r));
            let newton = a > 0.0 && a * c - b * b > 1e-12 * (e * gg).max(1e-300);
            let (a, b, c) = if newton { (a, b, c) } else { (e, f, gg) };
            // Active bounds: a coordinate at its bound whose descent direction leaves the domain
            // stays there.
            let at_bound = |x: f64, lo: f64, hi: f64, grad: f64| (x <= lo && grad > 0.0) || (x >= hi && grad < 0.0);
            let (fix_u, fix_v) = (at_bound(uv[0], u0, u1, g[0]), at_bound(uv[1], v0, v1, g[1]));
            let step = match (fix_u, fix_v) {
                (true, true) => break,
                (true, false) => [0.0, -g[1] / c],
                (false, true) => [-g[0] / a, 0.0],
                (false, false) => {
                    let det = a * c - b * b;
                    [-(c * g[0] - b * g[1]) / det, -(a * g[1] - b * g[0]) / det]
                }
            };
            if !(step[0].is_finite() && step[1].is_finite()) {
                break;
            }
            let scale = 1.0 + d.s.length();
            // The step's displacement to first order; at rounding level there is nothing to take.
            let predicted = (d.su * step[0] + d.sv * step[1]).length();
            if predicted <= 1e-15 * scale {
                break;
            }
            // Where p is off the surface by D, |S − p|² = D² + e² with e the tangential error:
            // below e ≈ 1e-8 D the distance's rounding hides e², the gradient (S_u · r, S_v · r)
            // still sees it. A trial is taken when the distance falls, or stays within rounding
            // while the gradient falls.
            let gradient2 = |d: &SurfaceDerivatives| {
                let r = d.s - p;
                d.su.dot(r).powi(2) + d.sv.dot(r).powi(2)
            };
            let takes = |dt: &SurfaceDerivatives, d2: f64| d2 < dist2 || (d2 <= dist2 * (1.0 + 1e-13) && gradient2(dt) < g[0] * g[0] + g[1] * g[1]);
            if newton && predicted <= CONVERGED_STEP * scale {
                // Quadratic convergence: this step is the last.
                let trial = s.clamp([uv[0] + step[0], uv[1] + step[1]]);
                let dt = s.derivatives(trial[0], trial[1]);
                if takes(&dt, (dt.s - p).length_squared()) {
                    uv = trial;
                    d = dt;
                }
                break;
            }
            // Halve until the step is taken.
            let mut t = 1.0;
            let mut accepted = None;
            for _ in 0..12 {
                let trial = s.clamp([uv[0] + t * step[0], uv[1] + t * step[1]]);
                let dt = s.derivatives(trial[0], trial[1]);
                let d2 = (dt.s - p).length_squared();
                if takes(&dt, d2) {
                    accepted = Some((trial, dt, d2));
                    break;
                }
                t *= 0.5;
            }
            let Some((trial, dt, d2)) = accepted else { break };
            let moved = (dt.s - d.s).length();
            uv = trial;
            d = dt;
            dist2 = d2;
            if moved <= 1e-15 * scale {
                break;
            }
        }
        (uv, d.s, d.normal())
    }

    /// The exact curvature at the tessellation's vertices, oriented by S_u × S_v.
    pub fn curvature(&self, positions: &[DVec3], boundary: Vec<bool>, diag: f64) -> CurvatureField {
        let vertices = self
            .uv
            .iter()
            .map(|uv| match self.surface.frame(uv[0], uv[1]) {
                Some(f) => VertexCurvature { k1: f.k1, k2: f.k2, mean: f.mean, normal: f.normal, dir1: f.dir1, dir2: f.dir2 },
                None => VertexCurvature { k1: 0.0, k2: 0.0, mean: 0.0, normal: DVec3::Z, dir1: DVec3::X, dir2: DVec3::Y },
            })
            .collect();
        CurvatureField::from_vertex_curvatures(positions, vertices, boundary, diag)
    }

    pub fn info(&self) -> BSplineInfo {
        let s = &self.surface;
        let ((u0, u1), (v0, v1)) = s.domain();
        let (mut h, mut k) = ([f64::INFINITY, f64::NEG_INFINITY], [f64::INFINITY, f64::NEG_INFINITY]);
        const N: usize = 100;
        for i in 0..=N {
            for j in 0..=N {
                let (u, v) = (u0 + (u1 - u0) * i as f64 / N as f64, v0 + (v1 - v0) * j as f64 / N as f64);
                if let Some(f) = s.frame(u, v) {
                    h = [h[0].min(f.mean), h[1].max(f.mean)];
                    k = [k[0].min(f.gauss), k[1].max(f.gauss)];
                }
            }
        }
        BSplineInfo {
            degree: [s.basis_u().degree(), s.basis_v().degree()],
            control: [s.basis_u().count(), s.basis_v().count()],
            domain: [[u0, u1], [v0, v1]],
            rational: s.is_rational(),
            tessellation: self.segments,
            mean_curvature: h,
            gauss_curvature: k,
        }
    }
}
