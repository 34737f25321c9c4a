//! Rational Bézier curves and tensor-product patches: one span of a NURBS, as CAD files store
//! exact circles and spheres. Points are kept Euclidean with their weights; the homogeneous form
//! (w·x, w) is what sums and products act on.

use glam::DVec3;

/// A rational Bézier curve of degree `points.len() − 1`.
#[derive(Clone, Debug, PartialEq)]
pub struct RationalCurve {
    pub points: Vec<DVec3>,
    pub weights: Vec<f64>,
}

/// A rational Bézier patch of bidegree `degree = [p, q]`: control point (i, j), i ≤ p along u and
/// j ≤ q along v, at `points[i * (q + 1) + j]`.
#[derive(Clone, Debug, PartialEq)]
pub struct RationalPatch {
    pub degree: [usize; 2],
    pub points: Vec<DVec3>,
    pub weights: Vec<f64>,
}

/// The four sides of a patch, each as a curve in the direction of its own parameter: v = 0 and
/// v = 1 along u, u = 0 and u = 1 along v.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    V0,
    U1,
    V1,
    U0,
}

impl Side {
    pub const ALL: [Side; 4] = [Side::V0, Side::U1, Side::V1, Side::U0];
}

/// Why three points give no rational quadratic arc.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ArcError {
    /// The arc sweeps half a circle or more (a quadratic needs a weight ≤ 0 there).
    TooWide { sweep_deg: f64 },
    /// A point is not finite, or the ends coincide.
    Degenerate,
}

impl std::fmt::Display for ArcError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ArcError::TooWide { sweep_deg } => write!(f, "an arc sweeps {sweep_deg:.1}°, beyond what one rational quadratic holds (< 180°)"),
            ArcError::Degenerate => f.write_str("an arc has coinciding or non-finite ends"),
        }
    }
}

impl std::error::Error for ArcError {}

/// Bernstein polynomials of degree `n` ≤ 7 at t.
pub fn bernstein(n: usize, t: f64) -> Vec<f64> {
    bernstein_with_derivative(n, t).0[..=n].to_vec()
}

/// Bernstein polynomials of degree `n` ≤ 7 at t and their derivatives, on the stack:
/// B'ᵢⁿ = n (Bᵢ₋₁ⁿ⁻¹ − Bᵢⁿ⁻¹).
fn bernstein_with_derivative(n: usize, t: f64) -> ([f64; 8], [f64; 8]) {
    assert!(n < 8, "degree {n} above 7");
    let mut b = [0.0; 8];
    b[0] = 1.0;
    let mut d = [0.0; 8];
    for k in 1..=n {
        if k == n {
            for i in 0..=n {
                let left = if i > 0 { b[i - 1] } else { 0.0 };
                let right = if i < n { b[i] } else { 0.0 };
                d[i] = n as f64 * (left - right);
            }
        }
        let mut saved = 0.0;
        for j in 0..k {
            let tmp = b[j];
            b[j] = saved + (1.0 - t) * tmp;
            saved = t * tmp;
        }
        b[k] = saved;
    }
    (b, d)
}

fn binomial(n: usize, k: usize) -> f64 {
    (0..k).fold(1.0, |acc, i| acc * (n - i) as f64 / (i + 1) as f64)
}

impl RationalCurve {
    pub fn degree(&self) -> usize {
        self.points.len() - 1
    }

    pub fn evaluate(&self, t: f64) -> DVec3 {
        let b = bernstein(self.degree(), t);
        let (mut x, mut w) = (DVec3::ZERO, 0.0);
        for ((p, &wi), bi) in self.points.iter().zip(&self.weights).zip(b) {
            x += bi * wi * *p;
            w += bi * wi;
        }
        x / w
    }

    /// The same curve run the other way.
    pub fn reversed(&self) -> RationalCurve {
        RationalCurve { points: self.points.iter().rev().copied().collect(), weights: self.weights.iter().rev().copied().collect() }
    }

    /// A straight segment as a quadratic (weights 1).
    pub fn segment(from: DVec3, to: DVec3) -> RationalCurve {
        RationalCurve { points: vec![from, 0.5 * (from + to), to], weights: vec![1.0; 3] }
    }

    /// A point as a quadratic: the collapsed side of a triangle.
    pub fn point(p: DVec3) -> RationalCurve {
        RationalCurve { points: vec![p; 3], weights: vec![1.0; 3] }
    }

    /// The circular arc from `from` through `through` (any point strictly inside it) to `to`,
    /// as a rational quadratic with end weights 1: with φ half the arc's angle (π − the inscribed
    /// angle at `through`), its middle point lies l·tan(φ/2) above the chord's midpoint Q (half
    /// chord l), the control point at Q + h(1 + w)/w and w = cos φ. Three collinear points give
    /// the segment.
    pub fn circular_arc(from: DVec3, through: DVec3, to: DVec3) -> Result<RationalCurve, ArcError> {
        let chord = to - from;
        let l = 0.5 * chord.length();
        if !(l > 0.0) || !from.is_finite() || !through.is_finite() || !to.is_finite() {
            return Err(ArcError::Degenerate);
        }
        let (u, v) = (from - through, to - through);
        let phi = u.cross(v).length().atan2(-u.dot(v));
        if phi >= 0.5 * std::f64::consts::PI * (1.0 - 1e-9) {
            return Err(ArcError::TooWide { sweep_deg: (2.0 * phi).to_degrees() });
        }
        let q = 0.5 * (from + to);
        let e = chord / (2.0 * l);
        let off = through - q;
        let Some(side) = (off - off.dot(e) * e).try_normalize() else {
            return Ok(RationalCurve::segment(from, to));
        };
        let t = (0.5 * phi).tan();
        let w = phi.cos();
        let h = (l * t) * side;
        Ok(RationalCurve { points: vec![from, q + h * ((1.0 + w) / w), to], weights: vec![1.0, w, 1.0] })
    }
}

impl RationalPatch {
    fn index(&self, i: usize, j: usize) -> usize {
        i * (self.degree[1] + 1) + j
    }

    pub fn point(&self, i: usize, j: usize) -> DVec3 {
        self.points[self.index(i, j)]
    }

    pub fn weight(&self, i: usize, j: usize) -> f64 {
        self.weights[self.index(i, j)]
    }

    /// The homogeneous value (Σ w·x·B, Σ w·B) at (u, v).
    fn homogeneous(&self, u: f64, v: f64) -> (DVec3, f64) {
        let [p, q] = self.degree;
        let (bu, bv) = (bernstein(p, u), bernstein(q, v));
        let (mut x, mut w) = (DVec3::ZERO, 0.0);
        for i in 0..=p {
            for j in 0..=q {
                let k = self.index(i, j);
                let b = bu[i] * bv[j] * self.weights[k];
                x += b * self.points[k];
                w += b;
            }
        }
        (x, w)
    }

    pub fn evaluate(&self, u: f64, v: f64) -> DVec3 {
        let (x, w) = self.homogeneous(u, v);
        x / w
    }

    /// The point and its first derivatives along u and v at (u, v), from the homogeneous form:
    /// X = P/w, X_u = (P_u − X w_u)/w.
    pub fn derivatives(&self, u: f64, v: f64) -> (DVec3, DVec3, DVec3) {
        let [p, q] = self.degree;
        let (bu, du) = bernstein_with_derivative(p, u);
        let (bv, dv) = bernstein_with_derivative(q, v);
        let (mut x, mut xu, mut xv) = (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO);
        let (mut w, mut wu, mut wv) = (0.0, 0.0, 0.0);
        for i in 0..=p {
            for j in 0..=q {
                let k = self.index(i, j);
                let (wk, pk) = (self.weights[k], self.points[k]);
                let (b, bu_, bv_) = (bu[i] * bv[j] * wk, du[i] * bv[j] * wk, bu[i] * dv[j] * wk);
                x += b * pk;
                xu += bu_ * pk;
                xv += bv_ * pk;
                w += b;
                wu += bu_;
                wv += bv_;
            }
        }
        let point = x / w;
        (point, (xu - point * wu) / w, (xv - point * wv) / w)
    }

    /// The side `side` as a curve (its row or column of control points).
    pub fn side(&self, side: Side) -> RationalCurve {
        let [p, q] = self.degree;
        let (idx, n): (Box<dyn Fn(usize) -> usize>, usize) = match side {
            Side::V0 => (Box::new(|i| self.index(i, 0)), p),
            Side::V1 => (Box::new(|i| self.index(i, q)), p),
            Side::U0 => (Box::new(|j| self.index(0, j)), q),
            Side::U1 => (Box::new(|j| self.index(p, j)), q),
        };
        RationalCurve { points: (0..=n).map(|k| self.points[idx(k)]).collect(), weights: (0..=n).map(|k| self.weights[idx(k)]).collect() }
    }

    /// The bilinearly blended Coons patch of four quadratic sides, in homogeneous form (so the
    /// sides stay exactly what they are, rational or not): `v0` and `v1` along u (v = 0, 1),
    /// `u0` and `u1` along v (u = 0, 1); the corners must agree, with equal weights. Bidegree
    /// (2, 2), the interior control point (P₁₀ + P₁₂ + P₀₁ + P₂₁)/2 − (P₀₀ + P₂₀ + P₀₂ + P₂₂)/4.
    pub fn coons(v0: &RationalCurve, u1: &RationalCurve, v1: &RationalCurve, u0: &RationalCurve) -> RationalPatch {
        let h = |c: &RationalCurve, k: usize| (c.points[k] * c.weights[k], c.weights[k]);
        let mut net = [[(DVec3::ZERO, 0.0); 3]; 3];
        for k in 0..3 {
            net[k][0] = h(v0, k);
            net[k][2] = h(v1, k);
            net[0][k] = h(u0, k);
            net[2][k] = h(u1, k);
        }
        let add = |a: (DVec3, f64), b: (DVec3, f64), s: f64| (a.0 + s * b.0, a.1 + s * b.1);
        let mut mid = (DVec3::ZERO, 0.0);
        for e in [net[1][0], net[1][2], net[0][1], net[2][1]] {
            mid = add(mid, e, 0.5);
        }
        for c in [net[0][0], net[2][0], net[0][2], net[2][2]] {
            mid = add(mid, c, -0.25);
        }
        net[1][1] = mid;
        let mut patch = RationalPatch { degree: [2, 2], points: Vec::with_capacity(9), weights: Vec::with_capacity(9) };
        for row in net {
            for (x, w) in row {
                patch.points.push(x / w);
                patch.weights.push(w);
            }
        }
        patch
    }
}

/// A scalar tensor-product Bernstein polynomial of bidegree `degree`, coefficients as in
/// [`RationalPatch`].
#[derive(Clone, Debug, PartialEq)]
pub struct BernsteinPoly {
    pub degree: [usize; 2],
    pub coefficients: Vec<f64>,
}

impl BernsteinPoly {
    /// The product, of bidegree the sum: c_{mn} = Σ C(p,i)C(p',m−i)/C(p+p',m) · C(q,j)C(q',n−j)/C(q+q',n) · a_{ij} b_{m−i,n−j}.
    pub fn mul(&self, other: &BernsteinPoly) -> BernsteinPoly {
        let ([p, q], [r, s]) = (self.degree, other.degree);
        let degree = [p + r, q + s];
        let mut coefficients = vec![0.0; (p + r + 1) * (q + s + 1)];
        for i in 0..=p {
            for j in 0..=q {
                let a = self.coefficients[i * (q + 1) + j];
                if a == 0.0 {
                    continue;
                }
                for k in 0..=r {
                    for l in 0..=s {
                        let (m, n) = (i + k, j + l);
                        let f = binomial(p, i) * binomial(r, k) / binomial(p + r, m) * binomial(q, j) * binomial(s, l) / binomial(q + s, n);
                        coefficients[m * (q + s + 1) + n] += f * a * other.coefficients[k * (s + 1) + l];
                    }
                }
            }
        }
        BernsteinPoly { degree, coefficients }
    }

    /// a·self + b·other, of the same bidegree.
    pub fn combine(&self, a: f64, other: &BernsteinPoly, b: f64) -> BernsteinPoly {
        debug_assert_eq!(self.degree, other.degree);
        BernsteinPoly { degree: self.degree, coefficients: self.coefficients.iter().zip(&other.coefficients).map(|(x, y)| a * x + b * y).collect() }
    }

    pub fn evaluate(&self, u: f64, v: f64) -> f64 {
        let [p, q] = self.degree;
        let (bu, bv) = (bernstein(p, u), bernstein(q, v));
        let mut x = 0.0;
        for i in 0..=p {
            for j in 0..=q {
                x += bu[i] * bv[j] * self.coefficients[i * (q + 1) + j];
            }
        }
        x
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    #[test]
    fn arcs_lie_on_their_circle_and_pass_through_their_points() {
        let mut rng = Rng(5);
        for _ in 0..200 {
            let (c, r) = (DVec3::new(rng.range(-3.0, 3.0), rng.range(-3.0, 3.0), rng.range(-3.0, 3.0)), rng.range(0.1, 10.0));
            let n = DVec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)).normalize();
            let e1 = n.any_orthonormal_vector();
            let e2 = n.cross(e1);
            let at = |t: f64| c + r * (t.cos() * e1 + t.sin() * e2);
            let (a, b) = (rng.range(0.0, 6.0), rng.range(0.01, 3.0));
            let mid = rng.range(0.05, 0.95);
            let arc = RationalCurve::circular_arc(at(a), at(a + mid * b), at(a + b)).unwrap();
            for k in 0..=20 {
                let x = arc.evaluate(k as f64 / 20.0);
                assert!(((x - c).length() - r).abs() < 1e-12 * r.max(1.0), "off the circle");
                assert!((x - c).dot(n).abs() < 1e-12 * r.max(1.0), "off the plane");
            }
            assert!((arc.evaluate(0.0) - at(a)).length() < 1e-12 && (arc.evaluate(1.0) - at(a + b)).length() < 1e-12);
            assert!(arc.weights.iter().all(|&w| w > 0.0));
        }
        assert!(matches!(RationalCurve::circular_arc(DVec3::X, DVec3::Y, -DVec3::X), Err(ArcError::TooWide { .. })));
        let s = RationalCurve::circular_arc(DVec3::ZERO, DVec3::X, 2.0 * DVec3::X).unwrap();
        assert!((s.evaluate(0.25) - 0.5 * DVec3::X).length() < 1e-15);
    }

    #[test]
    fn coons_keeps_its_sides_and_products_multiply() {
        let arc = |a: DVec3, m: DVec3, b: DVec3| RationalCurve::circular_arc(a, m, b).unwrap();
        let (p00, p20, p22, p02) = (DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y);
        let v0 = arc(p00, DVec3::new(0.5, -0.1, 0.0), p20);
        let u1 = RationalCurve::segment(p20, p22);
        let v1 = arc(p02, DVec3::new(0.5, 1.2, 0.0), p22);
        let u0 = arc(p00, DVec3::new(-0.05, 0.5, 0.0), p02);
        let patch = RationalPatch::coons(&v0, &u1, &v1, &u0);
        for k in 0..=10 {
            let t = k as f64 / 10.0;
            assert!((patch.evaluate(t, 0.0) - v0.evaluate(t)).length() < 1e-14);
            assert!((patch.evaluate(t, 1.0) - v1.evaluate(t)).length() < 1e-14);
            assert!((patch.evaluate(0.0, t) - u0.evaluate(t)).length() < 1e-14);
            assert!((patch.evaluate(1.0, t) - u1.evaluate(t)).length() < 1e-14);
            assert!((patch.side(Side::V1).evaluate(t) - v1.evaluate(t)).length() < 1e-14);
        }
        for (u, v) in [(0.2, 0.3), (0.7, 0.9)] {
            let (x, xu, xv) = patch.derivatives(u, v);
            let h = 1e-6;
            assert!((x - patch.evaluate(u, v)).length() < 1e-15);
            assert!((xu - (patch.evaluate(u + h, v) - patch.evaluate(u - h, v)) / (2.0 * h)).length() < 1e-8);
            assert!((xv - (patch.evaluate(u, v + h) - patch.evaluate(u, v - h)) / (2.0 * h)).length() < 1e-8);
        }
        let a = BernsteinPoly { degree: [2, 1], coefficients: vec![1.0, -2.0, 0.5, 3.0, 2.0, 1.5] };
        let b = BernsteinPoly { degree: [1, 2], coefficients: vec![0.3, 1.0, -1.0, 2.0, 0.7, 0.1] };
        let ab = a.mul(&b);
        assert_eq!(ab.degree, [3, 3]);
        for (u, v) in [(0.1, 0.7), (0.5, 0.5), (0.93, 0.2)] {
            assert!((ab.evaluate(u, v) - a.evaluate(u, v) * b.evaluate(u, v)).abs() < 1e-13);
        }
    }
}
