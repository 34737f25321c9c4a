//! One osculating jet (Cazals & Pouget 2005): the least-squares height function
//! z = J(x, y) = Σ_{i+j ≤ d} c_ij xⁱ yʲ in a local frame, and the exact shape operator of its graph at
//! (0, 0).
//!
//! The fitter owns every buffer it needs, so fitting a whole mesh allocates nothing per vertex.

// Negated float comparisons are deliberate: they also reject NaN.

use crate::geometry::linalg::{lstsq_householder, sym2_eigen, sym3_eigen, MAX_COLS};
use glam::DVec3;

/// Number of coefficients of a bivariate polynomial of degree `d`: (d + 1)(d + 2)/2.
pub const fn coefficient_count(degree: u8) -> usize {
    let d = degree as usize;
    (d + 1) * (d + 2) / 2
}

/// Relative rank tolerance of the least-squares fit (on the preconditioned, O(1) coordinates).
const RANK_TOL: f64 = 1e-9;

/// Refit in the jet's own normal frame when the first fit's gradient exceeds this slope (≈ 27°),
/// i.e. when the input normal was badly off.
const REFIT_SLOPE: f64 = 0.5;

/// Second-order differential geometry at the origin of a jet, in 3D.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JetGeometry {
    /// Principal curvatures k1 ≥ k2 w.r.t. `normal` (positive where the surface bends toward it).
    pub k1: f64,
    pub k2: f64,
    /// Unit normal of the jet at (0, 0), with a positive component along the frame normal.
    pub normal: DVec3,
    /// Unit principal directions; (dir1, dir2, normal) is a right-handed orthonormal frame.
    pub dir1: DVec3,
    pub dir2: DVec3,
    /// The polynomial degree actually fitted (≤ the requested one).
    pub degree: u8,
}

/// Reusable buffers for fitting jets to point sets.
#[derive(Default, Debug)]
pub struct JetFitter {
    /// Local coordinates (x, y, z) of the points, preconditioned.
    local: Vec<DVec3>,
    /// Column-major design matrix and right-hand side.
    a: Vec<f64>,
    b: Vec<f64>,
}

impl JetFitter {
    pub fn new() -> Self {
        Self::default()
    }

    /// Fits a jet of degree `degree` (2..=4; lower when the points cannot support it, never below
    /// 2) to `points` around the origin `origin` (usually the vertex, which should be among the
    /// points), with `normal` the approximate unit normal that fixes the frame and the curvature
    /// sign. None when the neighbourhood is degenerate (too few points, all collinear, coincident,
    /// or non-finite).
    pub fn fit(&mut self, origin: DVec3, normal: DVec3, points: impl Iterator<Item = DVec3> + Clone, degree: u8) -> Option<JetGeometry> {
        let n0 = normal.try_normalize()?;
        let first = self.fit_in_frame(origin, n0, points.clone(), degree)?;
        if first.1 > REFIT_SLOPE {
            // The frame normal was far from the surface normal: refit once in the jet's frame.
            if let Some(second) = self.fit_in_frame(origin, first.0.normal, points, degree) {
                if second.1 < first.1 {
                    return Some(second.0);
                }
            }
        }
        Some(first.0)
    }

    /// PCA normal of a point set: the eigenvector of the smallest covariance eigenvalue, oriented
    /// to have a non-negative component along `orient`. None for fewer than 3 points or a
    /// degenerate (collinear or coincident) set.
    pub(crate) fn pca_normal(points: impl Iterator<Item = DVec3> + Clone, orient: DVec3) -> Option<DVec3> {
        let (mut count, mut mean) = (0usize, DVec3::ZERO);
        for p in points.clone() {
            count += 1;
            mean += p;
        }
        if count < 3 {
            return None;
        }
        mean /= count as f64;
        let mut c = [[0.0f64; 3]; 3];
        for p in points {
            let d = (p - mean).to_array();
            for i in 0..3 {
                for j in 0..3 {
                    c[i][j] += d[i] * d[j];
                }
            }
        }
        let (vals, vecs) = sym3_eigen(c);
        // Needs a 2D spread: the middle eigenvalue clearly above zero.
        if !(vals[1] > 1e-12 * vals[2]) || !vals[2].is_finite() {
            return None;
        }
        let n = vecs[0].try_normalize()?;
        Some(if n.dot(orient) < 0.0 { -n } else { n })
    }

    /// One fit in the frame with normal `n0`. Returns the geometry and the slope |∇J(0,0)|.
    fn fit_in_frame(&mut self, origin: DVec3, n0: DVec3, points: impl Iterator<Item = DVec3>, degree: u8) -> Option<(JetGeometry, f64)> {
        let (t1, t2) = tangent_basis(n0);
        self.local.clear();
        let mut dist_sum = 0.0;
        let mut count = 0usize;
        for p in points {
            let d = p - origin;
            let l = DVec3::new(d.dot(t1), d.dot(t2), d.dot(n0));
            let r = d.length();
            if r > 0.0 {
                dist_sum += r;
                count += 1;
            }
            self.local.push(l);
        }
        if count == 0 {
            return None;
        }
        // Preconditioning: unit mean neighbour distance.
        let scale = dist_sum / count as f64;
        if !(scale > 0.0) || !scale.is_finite() {
            return None;
        }
        let inv = 1.0 / scale;
        for l in &mut self.local {
            *l *= inv;
        }
        let m = self.local.len();
        let mut d = degree.clamp(2, 4);
        let mut coef = [0.0f64; MAX_COLS];
        loop {
            let n = coefficient_count(d);
            if m >= n && self.solve(d, &mut coef) {
                break;
            }
            if d == 2 {
                return None;
            }
            d -= 1;
        }
        // Derivatives at (0, 0) in original units: J(x, y) = scale · Ĵ(x/scale, y/scale).
        let (hx, hy) = (coef[1], coef[2]);
        let (hxx, hxy, hyy) = (2.0 * coef[3] * inv, coef[4] * inv, 2.0 * coef[5] * inv);
        let geo = shape_operator(t1, t2, n0, hx, hy, hxx, hxy, hyy, d)?;
        Some((geo, hx.hypot(hy)))
    }

    /// Least squares for the degree-`d` monomials of the local points. False when rank deficient.
    fn solve(&mut self, d: u8, coef: &mut [f64; MAX_COLS]) -> bool {
        let m = self.local.len();
        let n = coefficient_count(d);
        self.a.clear();
        self.a.resize(m * n, 0.0);
        self.b.clear();
        for (i, l) in self.local.iter().enumerate() {
            let (mut px, mut py) = ([1.0f64; 5], [1.0f64; 5]);
            for k in 1..=d as usize {
                px[k] = px[k - 1] * l.x;
                py[k] = py[k - 1] * l.y;
            }
            // Monomials by total degree k, then xᵏ⁻ʲ yʲ for j = 0..=k.
            let mut col = 0;
            for k in 0..=d as usize {
                for j in 0..=k {
                    self.a[col * m + i] = px[k - j] * py[j];
                    col += 1;
                }
            }
            self.b.push(l.z);
        }
        lstsq_householder(&mut self.a, m, n, &mut self.b, &mut coef[..], RANK_TOL)
    }
}

/// An orthonormal tangent basis (t1, t2) with t1 × t2 = n.
pub(crate) fn tangent_basis(n: DVec3) -> (DVec3, DVec3) {
    let helper = if n.x.abs() < 0.6 {
        DVec3::X
    } else if n.y.abs() < 0.6 {
        DVec3::Y
    } else {
        DVec3::Z
    };
    let t1 = (helper - n * n.dot(helper)).normalize();
    (t1, n.cross(t1))
}

/// Principal curvatures and directions of the graph (x, y, h(x, y)) over the frame (t1, t2, n0) at
/// (0, 0), from its first and second derivatives. Exact (the gradient is not assumed zero):
/// first fundamental form E, F, G and second L, M, N w.r.t. the graph normal (−hx, −hy, 1)/W; the
/// generalized eigenproblem II v = κ I v is made symmetric with the Cholesky factor of I.
pub(crate) fn shape_operator(t1: DVec3, t2: DVec3, n0: DVec3, hx: f64, hy: f64, hxx: f64, hxy: f64, hyy: f64, degree: u8) -> Option<JetGeometry> {
    let (e, f, g) = (1.0 + hx * hx, hx * hy, 1.0 + hy * hy);
    let w = (1.0 + hx * hx + hy * hy).sqrt();
    let (l, m, n) = (hxx / w, hxy / w, hyy / w);
    // I = C Cᵀ with C = [[c11, 0], [c21, c22]].
    let c11 = e.sqrt();
    let c21 = f / c11;
    let c22 = (g - c21 * c21).max(0.0).sqrt();
    if !(c22 > 0.0) {
        return None;
    }
    // S = C⁻¹ II C⁻ᵀ, C⁻¹ = [[i11, 0], [i21, i22]].
    let (i11, i21, i22) = (1.0 / c11, -c21 / (c11 * c22), 1.0 / c22);
    // First C⁻¹ II (rows), then times C⁻ᵀ.
    let (r11, r12) = (i11 * l, i11 * m);
    let (r21, r22) = (i21 * l + i22 * m, i21 * m + i22 * n);
    let s11 = r11 * i11;
    let s12 = r11 * i21 + r12 * i22;
    let s22 = r21 * i21 + r22 * i22;
    let (k1, k2, (c, s)) = sym2_eigen(s11, s12, s22);
    // Parameter direction v = C⁻ᵀ w for w = (c, s); C⁻ᵀ = [[i11, i21], [0, i22]].
    let (vx, vy) = (i11 * c + i21 * s, i22 * s);
    let rx = t1 + hx * n0;
    let ry = t2 + hy * n0;
    let normal = ((n0 - hx * t1 - hy * t2) / w).try_normalize()?;
    let dir1 = (vx * rx + vy * ry).try_normalize()?;
    let dir1 = (dir1 - normal * normal.dot(dir1)).try_normalize()?;
    let dir2 = normal.cross(dir1);
    let geo = JetGeometry { k1, k2, normal, dir1, dir2, degree };
    (k1.is_finite() && k2.is_finite() && dir2.is_finite()).then_some(geo)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(f: impl Fn(f64, f64) -> f64) -> Vec<DVec3> {
        let mut pts = vec![DVec3::new(0.0, 0.0, f(0.0, 0.0))];
        for i in -3i32..=3 {
            for j in -3i32..=3 {
                if i != 0 || j != 0 {
                    let (x, y) = (0.1 * i as f64 + 0.013 * j as f64, 0.1 * j as f64);
                    pts.push(DVec3::new(x, y, f(x, y)));
                }
            }
        }
        pts
    }

    #[test]
    fn exact_quadric_with_tilt() {
        // z = 0.3 + 0.2x − 0.1y + 1.5x² + 0.4xy − 0.5y²: the fit is exact for every degree.
        let f = |x: f64, y: f64| 0.2 * x - 0.1 * y + 1.5 * x * x + 0.4 * x * y - 0.5 * y * y;
        let pts = grid(f);
        let mut fitter = JetFitter::new();
        let (hx, hy, hxx, hxy, hyy) = (0.2, -0.1, 3.0, 0.4, -1.0);
        let exact = shape_operator(DVec3::X, DVec3::Y, DVec3::Z, hx, hy, hxx, hxy, hyy, 2).unwrap();
        for d in 2..=4 {
            let g = fitter.fit(DVec3::ZERO, DVec3::Z, pts.iter().copied(), d).unwrap();
            assert_eq!(g.degree, d);
            assert!((g.k1 - exact.k1).abs() < 1e-9 && (g.k2 - exact.k2).abs() < 1e-9, "{g:?} {exact:?}");
            assert!((g.normal - exact.normal).length() < 1e-9);
        }
        // Check the exact shape operator against the textbook H and K of a graph.
        let w2 = 1.0 + hx * hx + hy * hy;
        let h = ((1.0 + hy * hy) * hxx - 2.0 * hx * hy * hxy + (1.0 + hx * hx) * hyy) / (2.0 * w2.powf(1.5));
        let k = (hxx * hyy - hxy * hxy) / (w2 * w2);
        assert!((0.5 * (exact.k1 + exact.k2) - h).abs() < 1e-12 && (exact.k1 * exact.k2 - k).abs() < 1e-12);
        // Principal directions are tangent, orthonormal, and satisfy II(d1, d2) = 0 (checked via
        // the normal curvature: κ_n(d1) = k1).
        assert!(exact.dir1.dot(exact.normal).abs() < 1e-12 && exact.dir1.dot(exact.dir2).abs() < 1e-12);
        assert!((exact.dir1.cross(exact.dir2) - exact.normal).length() < 1e-12);
    }

    #[test]
    fn sign_follows_the_normal() {
        let pts = grid(|x, y| 0.5 * (x * x + y * y));
        let mut fitter = JetFitter::new();
        let up = fitter.fit(DVec3::ZERO, DVec3::Z, pts.iter().copied(), 3).unwrap();
        let down = fitter.fit(DVec3::ZERO, -DVec3::Z, pts.iter().copied(), 3).unwrap();
        assert!((up.k1 - 1.0).abs() < 1e-9 && (up.k2 - 1.0).abs() < 1e-9);
        assert!((down.k1 + 1.0).abs() < 1e-9 && (down.k2 + 1.0).abs() < 1e-9);
        assert!(up.normal.z > 0.99 && down.normal.z < -0.99);
    }

    #[test]
    fn degenerate_inputs() {
        let mut fitter = JetFitter::new();
        let line: Vec<DVec3> = (0..10).map(|i| DVec3::new(i as f64, 0.0, 0.0)).collect();
        assert!(fitter.fit(DVec3::ZERO, DVec3::Z, line.iter().copied(), 3).is_none());
        assert!(fitter.fit(DVec3::ZERO, DVec3::Z, [DVec3::ZERO; 8].iter().copied(), 3).is_none());
        assert!(fitter.fit(DVec3::ZERO, DVec3::ZERO, line.iter().copied(), 3).is_none());
        // Too few for a cubic: falls back to degree 2.
        let pts = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0), (1.0, 1.0), (-1.0, -1.0)];
        let pts: Vec<DVec3> = pts.iter().map(|&(x, y)| DVec3::new(x, y, x * x)).collect();
        let g = fitter.fit(DVec3::ZERO, DVec3::Z, pts.iter().copied(), 3).unwrap();
        assert_eq!(g.degree, 2);
        assert!((g.k1 - 2.0).abs() < 1e-9 && g.k2.abs() < 1e-9);
        assert!(JetFitter::pca_normal(line.iter().copied(), DVec3::Z).is_none());
        let n = JetFitter::pca_normal(pts.iter().map(|p| DVec3::new(p.x, p.y, 0.0)), -DVec3::Z).unwrap();
        assert!((n + DVec3::Z).length() < 1e-12);
    }
}
