//! Tensor-product B-spline and NURBS surfaces S(u, v) = Σ N_i(u) M_j(v) w_ij P_ij / Σ N_i M_j w_ij
//! with their partial derivatives up to second order (the rational quotient rule, Piegl & Tiller
//! A4.4), and the differential geometry they give exactly: the unit normal, the fundamental
//! forms, H, K, the principal curvatures and directions, and the derivatives of the normal.
//!
//! Conventions (those of `../shared/data/bsplines/README.md`): n = S_u × S_v / |S_u × S_v|;
//! H = (EN − 2FM + GL) / (2(EG − F²)), so a surface curving towards its normal has H > 0 and the
//! central sphere (Sec. 2.6) has centre f + n/H and radius 1/H; K = (LN − M²)/(EG − F²).

// Negated float comparisons are deliberate: they also reject NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use std::fmt;

use glam::DVec3;

use super::basis::{BSplineBasis, BasisValues};

/// Why control points cannot make a surface with the given bases.
#[derive(Clone, Debug, PartialEq)]
pub enum SurfaceError {
    /// `control.len()` ≠ n_u · n_v (or the weights differ in number).
    ControlCount { found: usize, expected: usize },
    /// Control point `index` (U fastest) has a non-finite coordinate.
    NonFinitePoint { index: usize },
    /// Weight `index` is not a positive finite number.
    Weight { index: usize },
}

impl fmt::Display for SurfaceError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SurfaceError::ControlCount { found, expected } => {
                write!(f, "{found} control points, expected {expected} (n_u · n_v from the knot vectors)")
            }
            SurfaceError::NonFinitePoint { index } => write!(f, "control point {index} is not finite"),
            SurfaceError::Weight { index } => write!(f, "weight {index} is not a positive finite number"),
        }
    }
}

impl std::error::Error for SurfaceError {}

/// A B-spline (NURBS when weighted) surface. Control point (i, j), i along U, is at i + n_u j.
#[derive(Clone, Debug, PartialEq)]
pub struct BSplineSurface {
    u: BSplineBasis,
    v: BSplineBasis,
    control: Vec<DVec3>,
    weights: Vec<f64>,
    rational: bool,
}

/// S and its partial derivatives at a parameter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceDerivatives {
    pub s: DVec3,
    pub su: DVec3,
    pub sv: DVec3,
    pub suu: DVec3,
    pub suv: DVec3,
    pub svv: DVec3,
}

/// The differential geometry at a regular point (S_u × S_v ≠ 0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceFrame {
    pub point: DVec3,
    /// Unit normal S_u × S_v / |S_u × S_v|.
    pub normal: DVec3,
    pub su: DVec3,
    pub sv: DVec3,
    /// ∂n/∂u and ∂n/∂v.
    pub nu: DVec3,
    pub nv: DVec3,
    /// First fundamental form E, F, G and second L, M, N.
    pub first_form: [f64; 3],
    pub second_form: [f64; 3],
    /// Mean and Gaussian curvature.
    pub mean: f64,
    pub gauss: f64,
    /// Principal curvatures k1 ≥ k2 and unit principal directions (tangent vectors).
    pub k1: f64,
    pub k2: f64,
    pub dir1: DVec3,
    pub dir2: DVec3,
}

impl BSplineSurface {
    /// A surface over the bases with control points (U fastest) and weights (all 1: a B-spline).
    pub fn new(u: BSplineBasis, v: BSplineBasis, control: Vec<DVec3>, weights: Vec<f64>) -> Result<Self, SurfaceError> {
        let expected = u.count() * v.count();
        if control.len() != expected || weights.len() != expected {
            return Err(SurfaceError::ControlCount { found: control.len().min(weights.len()), expected });
        }
        if let Some(index) = control.iter().position(|p| !p.is_finite()) {
            return Err(SurfaceError::NonFinitePoint { index });
        }
        if let Some(index) = weights.iter().position(|w| !(w.is_finite() && *w > 0.0)) {
            return Err(SurfaceError::Weight { index });
        }
        let rational = weights.iter().any(|&w| w != 1.0);
        Ok(Self { u, v, control, weights, rational })
    }

    pub fn basis_u(&self) -> &BSplineBasis {
        &self.u
    }

    pub fn basis_v(&self) -> &BSplineBasis {
        &self.v
    }

    /// The control points, U fastest.
    pub fn control_points(&self) -> &[DVec3] {
        &self.control
    }

    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// Whether some weight differs from 1.
    pub fn is_rational(&self) -> bool {
        self.rational
    }

    /// ((u0, u1), (v0, v1)).
    pub fn domain(&self) -> ((f64, f64), (f64, f64)) {
        (self.u.domain(), self.v.domain())
    }

    /// (u, v) clamped to the domain.
    pub fn clamp(&self, uv: [f64; 2]) -> [f64; 2] {
        let ((u0, u1), (v0, v1)) = self.domain();
        [uv[0].clamp(u0, u1), uv[1].clamp(v0, v1)]
    }

    /// The surface moved by −`t` and scaled by 1/`s` (exact: B-splines are affinely invariant).
    pub fn in_frame(&self, t: DVec3, s: f64) -> Self {
        let control = self.control.iter().map(|&p| (p - t) / s).collect();
        Self { control, ..self.clone() }
    }

    /// S(u, v).
    pub fn point(&self, u: f64, v: f64) -> DVec3 {
        self.derivatives(u, v).s
    }

    /// S and its derivatives up to second order at (u, v) (clamped to the domain).
    pub fn derivatives(&self, u: f64, v: f64) -> SurfaceDerivatives {
        self.derivatives_with(&self.u.evaluate(u), &self.v.evaluate(v))
    }

    /// [`Self::derivatives`] from basis values evaluated beforehand (a fixed grid).
    pub fn derivatives_with(&self, bu: &BasisValues, bv: &BasisValues) -> SurfaceDerivatives {
        let nu = self.u.count();
        // Homogeneous sums A_kl = Σ ∂^k N ∂^l M w P and w_kl = Σ ∂^k N ∂^l M w, k + l ≤ 2.
        let mut a = [[DVec3::ZERO; 3]; 3];
        let mut w = [[0.0; 3]; 3];
        for jb in 0..bv.count {
            let j = bv.first + jb;
            for ib in 0..bu.count {
                let idx = bu.first + ib + nu * j;
                let (p, wt) = (self.control[idx], self.weights[idx]);
                for k in 0..3 {
                    for l in 0..3 - k {
                        let c = bu.values[k][ib] * bv.values[l][jb] * wt;
                        a[k][l] += c * p;
                        w[k][l] += c;
                    }
                }
            }
        }
        // Quotient rule (A4.4) for k + l ≤ 2.
        let w0 = w[0][0];
        let s = a[0][0] / w0;
        let su = (a[1][0] - w[1][0] * s) / w0;
        let sv = (a[0][1] - w[0][1] * s) / w0;
        let suu = (a[2][0] - 2.0 * w[1][0] * su - w[2][0] * s) / w0;
        let svv = (a[0][2] - 2.0 * w[0][1] * sv - w[0][2] * s) / w0;
        let suv = (a[1][1] - w[1][0] * sv - w[0][1] * su - w[1][1] * s) / w0;
        SurfaceDerivatives { s, su, sv, suu, suv, svv }
    }

    /// The differential geometry at (u, v); None where S_u × S_v vanishes.
    pub fn frame(&self, u: f64, v: f64) -> Option<SurfaceFrame> {
        self.derivatives(u, v).frame()
    }
}

impl SurfaceDerivatives {
    /// Unit normal S_u × S_v / |S_u × S_v|, None where it vanishes.
    pub fn normal(&self) -> Option<DVec3> {
        self.su.cross(self.sv).try_normalize()
    }

    /// The differential geometry; None at a singular point.
    pub fn frame(&self) -> Option<SurfaceFrame> {
        let big_n = self.su.cross(self.sv);
        let len = big_n.length();
        let n = big_n.try_normalize()?;
        if !(len > 0.0) {
            return None;
        }
        let (e, f, g) = (self.su.dot(self.su), self.su.dot(self.sv), self.sv.dot(self.sv));
        let (l, m, nn) = (self.suu.dot(n), self.suv.dot(n), self.svv.dot(n));
        let det = e * g - f * f;
        let mean = (e * nn - 2.0 * f * m + g * l) / (2.0 * det);
        let gauss = (l * nn - m * m) / det;
        let disc = (mean * mean - gauss).max(0.0).sqrt();
        let (k1, k2) = (mean + disc, mean - disc);
        // ∂(N/|N|) = (∂N − n⟨n, ∂N⟩)/|N| with N = S_u × S_v.
        let big_nu = self.suu.cross(self.sv) + self.su.cross(self.suv);
        let big_nv = self.suv.cross(self.sv) + self.su.cross(self.svv);
        let nu = (big_nu - n * n.dot(big_nu)) / len;
        let nv = (big_nv - n * n.dot(big_nv)) / len;
        let dir1 = self.principal_direction(k1, [e, f, g], [l, m, nn], n);
        let dir2 = n.cross(dir1);
        Some(SurfaceFrame {
            point: self.s,
            normal: n,
            su: self.su,
            sv: self.sv,
            nu,
            nv,
            first_form: [e, f, g],
            second_form: [l, m, nn],
            mean,
            gauss,
            k1,
            k2,
            dir1,
            dir2,
        })
    }

    /// The unit tangent direction of principal curvature `k`: (du, dv) in the kernel of
    /// II − k I, from the better-conditioned of its two rows; S_u's direction at an umbilic.
    fn principal_direction(&self, k: f64, [e, f, g]: [f64; 3], [l, m, n]: [f64; 3], normal: DVec3) -> DVec3 {
        let (a, b, c) = (l - k * e, m - k * f, n - k * g);
        // Rows (a, b) and (b, c): (du, dv) = (−b, a) or (c, −b).
        let r1 = (-b, a);
        let r2 = (c, -b);
        let pick = if a * a + b * b >= b * b + c * c { r1 } else { r2 };
        let t = pick.0 * self.su + pick.1 * self.sv;
        let size = l.abs() + m.abs() + n.abs() + k.abs() * (e + g);
        let row = (a * a + b * b).max(b * b + c * c).sqrt();
        match t.try_normalize() {
            Some(d) if row > 1e-10 * size => d,
            _ => (self.su - normal * normal.dot(self.su)).try_normalize().unwrap_or(DVec3::X),
        }
    }
}
