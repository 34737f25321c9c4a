//! Tensor-product B-spline and NURBS surfaces S(u, v) = Σ N_i(u) M_j(v) w_ij P_ij / Σ N_i M_j w_ij
//! with their partial derivatives up to second order (the rational quotient rule, Piegl & Tiller
//! A4.4), and the differential geometry they give exactly: the unit normal, the fundamental
//! forms, H, K, the principal curvatures and directions, and the derivatives of the normal.
//!
//! Conventions (those of `../shared/data/bsplines/README.md`): n = S_u × S_v / |S_u × S_v|;
//! H = (EN − 2FM + GL) / (2(EG − F²)), so a surface curving towards its normal has H > 0 and the
//! central sphere (Sec. 2.6) has centre f + n/H and radius 1/H; K = (LN − M²)/(EG − F²).

// Negated float comparisons are deliberate: they also reject NaN.

use std::fmt;

use glam::DVec3;

use super::basis::{BSplineBasis, BasisValues};
use crate::geometry::mesh::{bbox_diagonal, Face, PolyMesh};

/// Largest chord deviation of a reference's tessellation, relative to the bounding-box diagonal
/// of the control net ([`BSplineSurface::tessellation_segments`]).
pub const TESSELLATION_TOLERANCE: f64 = 5e-4;
/// Segments per parameter direction of a tessellation, at least and at most.
pub const MIN_SEGMENTS: usize = 8;
/// A tessellation's edges are at most this fraction of the diagonal long.
pub const EDGES_PER_DIAGONAL: f64 = 60.0;
pub const MAX_SEGMENTS: usize = 160;

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
    pub(crate) fn is_rational(&self) -> bool {
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

    /// The same surface over a rescaled domain: parameter k runs from its start at `scale[k]`
    /// times its speed, t′ = t₀ + (t − t₀)·scale[k] (exact: only the knots move).
    pub fn rescaled(&self, scale: [f64; 2]) -> Self {
        let stretch = |b: &BSplineBasis, s: f64| {
            let t0 = b.domain().0;
            BSplineBasis::new(b.degree(), b.knots().iter().map(|&k| t0 + (k - t0) * s).collect()).expect("a scaled knot vector is a knot vector")
        };
        Self { u: stretch(&self.u, scale[0]), v: stretch(&self.v, scale[1]), ..self.clone() }
    }

    /// The scale per parameter ([`Self::rescaled`]) after which both run at the same mean speed
    /// in space, |S_u| and |S_v| averaged over a `samples` × `samples` grid; the faster one keeps
    /// its own. The angles between parameter directions are then about those in space.
    pub fn isotropic_scale(&self, samples: usize) -> [f64; 2] {
        let ((u0, u1), (v0, v1)) = self.domain();
        let (mut speed_u, mut speed_v) = (0.0, 0.0);
        for j in 0..samples {
            for i in 0..samples {
                let t = |k: usize, lo: f64, hi: f64| lo + (hi - lo) * (k as f64 + 0.5) / samples as f64;
                let d = self.derivatives(t(i, u0, u1), t(j, v0, v1));
                (speed_u, speed_v) = (speed_u + d.su.length(), speed_v + d.sv.length());
            }
        }
        let fastest = speed_u.max(speed_v);
        if !(fastest > 0.0 && speed_u > 0.0 && speed_v > 0.0) {
            return [1.0, 1.0];
        }
        [speed_u / fastest, speed_v / fastest]
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
    pub(crate) fn derivatives_with(&self, bu: &BasisValues, bv: &BasisValues) -> SurfaceDerivatives {
        let nu = self.u.count();
        // Homogeneous sums A_kl = Σ_j ∂^l M_j Σ_i ∂^k N_i w P_ij and w_kl likewise, k + l ≤ 2: each
        // row of the control net summed along U first (a tensor product).
        let mut a = [[DVec3::ZERO; 3]; 3];
        let mut w = [[0.0; 3]; 3];
        for jb in 0..bv.count {
            let row = bu.first + nu * (bv.first + jb);
            let (mut h, mut hw) = ([DVec3::ZERO; 3], [0.0; 3]);
            if self.rational {
                for ib in 0..bu.count {
                    let wt = self.weights[row + ib];
                    let p = self.control[row + ib] * wt;
                    for k in 0..3 {
                        h[k] += bu.values[k][ib] * p;
                        hw[k] += bu.values[k][ib] * wt;
                    }
                }
            } else {
                for ib in 0..bu.count {
                    let p = self.control[row + ib];
                    for k in 0..3 {
                        h[k] += bu.values[k][ib] * p;
                    }
                }
            }
            for k in 0..3 {
                for l in 0..3 - k {
                    let m = bv.values[l][jb];
                    a[k][l] += m * h[k];
                    w[k][l] += m * hw[k];
                }
            }
        }
        if !self.rational {
            // w ≡ 1: the basis sums to 1, its derivatives to 0.
            return SurfaceDerivatives { s: a[0][0], su: a[1][0], sv: a[0][1], suu: a[2][0], suv: a[1][1], svv: a[0][2] };
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

    /// A uniform grid of `segments` in (u, v): quads (i, j), (i+1, j), (i+1, j+1), (i, j+1)
    /// (counter-clockwise about S_u × S_v; vertex i + (s_u + 1) j), and every vertex's (u, v).
    pub fn tessellate(&self, [su, sv]: [usize; 2]) -> (PolyMesh, Vec<[f64; 2]>) {
        let ((u0, u1), (v0, v1)) = self.domain();
        let param = |a: f64, b: f64, k: usize, n: usize| if k == n { b } else { a + (b - a) * k as f64 / n as f64 };
        let uv: Vec<[f64; 2]> = (0..=sv).flat_map(|j| (0..=su).map(move |i| [param(u0, u1, i, su), param(v0, v1, j, sv)])).collect();
        let positions = uv.iter().map(|p| self.point(p[0], p[1])).collect();
        let id = |i: usize, j: usize| (i + (su + 1) * j) as u32;
        let faces = (0..sv).flat_map(|j| (0..su).map(move |i| Face::quad([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]))).collect();
        (PolyMesh::new(positions, faces), uv)
    }

    /// Segments per direction for chords within `tolerance` × d of the surface (d: the control
    /// net's bounding-box diagonal): along every parameter line of a coarse sample grid, Σ over
    /// its cells of length · √(|κ| / (8 τ)) (a chord of length h on a curve of curvature κ
    /// deviates by about κh²/8 ≤ τ), the largest over the lines. Edges then get one length h
    /// in both directions, the smaller of the two so found and d / [`EDGES_PER_DIAGONAL`], within
    /// [`MIN_SEGMENTS`]..=[`MAX_SEGMENTS`] segments per direction.
    pub fn tessellation_segments(&self, tolerance: f64) -> [usize; 2] {
        let diag = bbox_diagonal(&self.control).max(f64::MIN_POSITIVE);
        let tol = tolerance * diag;
        let ((u0, u1), (v0, v1)) = self.domain();
        let (nu, nv) = ((4 * self.u.count()).clamp(16, 64), (4 * self.v.count()).clamp(16, 64));
        let mut samples = Vec::with_capacity((nu + 1) * (nv + 1));
        for j in 0..=nv {
            for i in 0..=nu {
                let d = self.derivatives(u0 + (u1 - u0) * i as f64 / nu as f64, v0 + (v1 - v0) * j as f64 / nv as f64);
                // Normal curvatures along S_u and S_v: L/E and N/G.
                let (ku, kv) = match d.normal() {
                    Some(n) => (d.suu.dot(n) / d.su.length_squared(), d.svv.dot(n) / d.sv.length_squared()),
                    None => (0.0, 0.0),
                };
                samples.push((d.s, ku.abs(), kv.abs()));
            }
        }
        let at = |i: usize, j: usize| samples[i + (nu + 1) * j];
        let need = |len: f64, k: f64| if k.is_finite() { len * (k / (8.0 * tol)).sqrt() } else { 0.0 };
        // (segments for the sagitta, length) of the longest-needing and of the longest line.
        let fold = |lines: Vec<(f64, f64)>| lines.into_iter().fold((0.0f64, 0.0f64), |a, l| (a.0.max(l.0), a.1.max(l.1)));
        let (need_u, len_u) = fold(
            (0..=nv)
                .map(|j| {
                    (0..nu).fold((0.0, 0.0), |a, i| {
                        let l = at(i, j).0.distance(at(i + 1, j).0);
                        (a.0 + need(l, at(i, j).1.max(at(i + 1, j).1)), a.1 + l)
                    })
                })
                .collect(),
        );
        let (need_v, len_v) = fold(
            (0..=nu)
                .map(|i| {
                    (0..nv).fold((0.0, 0.0), |a, j| {
                        let l = at(i, j).0.distance(at(i, j + 1).0);
                        (a.0 + need(l, at(i, j).2.max(at(i, j + 1).2)), a.1 + l)
                    })
                })
                .collect(),
        );
        let h = [len_u / need_u.max(1.0), len_v / need_v.max(1.0), diag / EDGES_PER_DIAGONAL].into_iter().fold(f64::INFINITY, f64::min);
        let (along_u, along_v) = (len_u / h, len_v / h);
        let clamp = |x: f64| if x.is_finite() { (x.ceil() as usize).clamp(MIN_SEGMENTS, MAX_SEGMENTS) } else { MAX_SEGMENTS };
        [clamp(along_u), clamp(along_v)]
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
