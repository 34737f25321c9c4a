//! Discrete torsal directions of a line congruence on a grid quad (Sec. 2.3, Eq. 3, and Sec. 5.1,
//! Fig. 20): vertices f0..f3 = f(i, j), f(i+1, j), f(i+1, j+1), f(i, j+1) with lines l0..l3. The
//! diagonals d⁺ = f2 − f0 and d⁻ = f1 − f3 approximate f_u ± f_v at the quad's centre, and
//! l⁺ = l2 − l0, l⁻ = l1 − l3 the same derivatives of the lines; l_c is the line at the centre
//! (the mean of the four). A direction t = μ0 d⁺ + μ1 d⁻ is torsal when l_c, l_t = μ0 l⁺ + μ1 l⁻
//! and t are coplanar:
//!
//! det(l_c, μ0 l⁺ + μ1 l⁻, μ0 d⁺ + μ1 d⁻) = a μ0² + b μ0 μ1 + c μ1² = 0,
//! a = det(l_c, l⁺, d⁺), b = det(l_c, l⁺, d⁻) + det(l_c, l⁻, d⁺), c = det(l_c, l⁻, d⁻).
//!
//! Its real roots (b² ≥ 4ac) are the two torsal directions; the torsal planes are spanned by l_c
//! and t. In parameters, d⁺ is (Δu, Δv) and d⁻ is (Δu, −Δv).

// Negated float comparisons are deliberate: they also reject NaN.

use glam::DVec3;

/// The quadratic form's coefficients [a, b, c] of a quad.
pub(crate) fn torsal_quadratic(f: [DVec3; 4], l: [DVec3; 4]) -> [f64; 3] {
    let (dp, dm) = (f[2] - f[0], f[1] - f[3]);
    let (lp, lm) = (l[2] - l[0], l[1] - l[3]);
    let lc = 0.25 * (l[0] + l[1] + l[2] + l[3]);
    let det = |a: DVec3, b: DVec3, c: DVec3| a.dot(b.cross(c));
    [det(lc, lp, dp), det(lc, lp, dm) + det(lc, lm, dp), det(lc, lm, dm)]
}

/// The real roots (μ0 : μ1) of a μ0² + b μ0 μ1 + c μ1², each scaled to |(μ0, μ1)| = 1; None
/// when there are none (b² < 4ac) or every direction is a root (a = b = c = 0).
pub(crate) fn quadratic_roots([a, b, c]: [f64; 3]) -> Option<[[f64; 2]; 2]> {
    let disc = b * b - 4.0 * a * c;
    let size = a.abs().max(b.abs()).max(c.abs());
    if !(disc >= 0.0) || size == 0.0 {
        return None;
    }
    // Stable homogeneous form: with q = −(b + sign(b)√disc)/2 the roots are (q : a) and (c : q).
    let q = -0.5 * (b + b.signum() * disc.sqrt());
    let unit = |m: [f64; 2]| {
        let n = m[0].hypot(m[1]);
        [m[0] / n, m[1] / n]
    };
    let roots = if q.abs() > 1e-300 {
        [unit([q, a]), unit([c, q])]
    } else if a.abs() >= c.abs() {
        // b = 0 and c = 0: a μ0² vanishes only at μ0 = 0 (a double root).
        [[0.0, 1.0], [0.0, 1.0]]
    } else {
        [[1.0, 0.0], [1.0, 0.0]]
    };
    Some(roots)
}

/// A quad's two torsal directions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TorsalPair {
    /// (μ0, μ1) of each direction, scaled so that |t| = 1.
    pub mu: [[f64; 2]; 2],
    /// Unit directions t = μ0 d⁺ + μ1 d⁻.
    pub t: [DVec3; 2],
    /// Unit normals of the torsal planes (spanned by l_c and t).
    pub plane_normals: [DVec3; 2],
    /// The angle between the torsal planes, degrees in [0, 90].
    pub angle_deg: f64,
}

/// The torsal directions of a quad (see the module docs); None without real ones or when a
/// torsal plane is undefined (t parallel to l_c).
pub fn torsal_pair(f: [DVec3; 4], l: [DVec3; 4]) -> Option<TorsalPair> {
    pair_of(f, l, quadratic_roots(torsal_quadratic(f, l))?)
}

/// The pair of directions (μ0 : μ1) `roots` of a quad with their torsal planes.
fn pair_of(f: [DVec3; 4], l: [DVec3; 4], roots: [[f64; 2]; 2]) -> Option<TorsalPair> {
    let (dp, dm) = (f[2] - f[0], f[1] - f[3]);
    let lc = 0.25 * (l[0] + l[1] + l[2] + l[3]);
    let mut mu = [[0.0; 2]; 2];
    let mut t = [DVec3::ZERO; 2];
    let mut plane_normals = [DVec3::ZERO; 2];
    for k in 0..2 {
        let v = roots[k][0] * dp + roots[k][1] * dm;
        let len = v.length();
        if !(len > 0.0) {
            return None;
        }
        mu[k] = [roots[k][0] / len, roots[k][1] / len];
        t[k] = v / len;
        plane_normals[k] = lc.cross(t[k]).try_normalize()?;
    }
    let angle_deg = plane_normals[0].dot(plane_normals[1]).abs().min(1.0).acos().to_degrees();
    Some(TorsalPair { mu, t, plane_normals, angle_deg })
}

/// The pair of parameter directions of a quad (f1 − f0 along u, f3 − f0 along v): the torsal
/// directions where every direction is torsal (a sphere's normals all meet at its centre).
pub(crate) fn parameter_pair(f: [DVec3; 4], l: [DVec3; 4]) -> Option<TorsalPair> {
    // u: d⁺ + d⁻ = 2 Δu f_u; v: d⁺ − d⁻ = 2 Δv f_v.
    pair_of(f, l, [[1.0, 1.0], [1.0, -1.0]])
}
