//! Generalized spheres (paper Sec. 5.2, `notes/sphere-geometry.md`): the zero set of
//! ψ(x) = a|x|² − ⟨b, x⟩ + c, a sphere for a ≠ 0 and a plane for a = 0.
//!
//! A sphere is **normalized** when bᵀb − 4ac = 1. Then the signed radius is r = 1/(2a), the centre
//! is b/(2a) = r b, and for a plane (a = 0) `b` is its unit normal. The sign of r carries the
//! orientation: `from_point_normal_curvature(f, n, h)` has its centre at f + n/h, so r = 1/h > 0 when
//! the sphere bends toward `n`, and b = n on the plane h = 0.
//!
//! For a normalized sphere ψ(x) = (|x − c|² − r²)/(2r). Near the point f of
//! `from_point_normal_curvature(f, n, h)`, ψ(f + t n) = −t + h t²/2: ψ is minus the signed distance
//! along `n`, for every h including the plane.

// Negated float comparisons are deliberate in the toolkit: they also reject NaN.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::linalg::Svd;

/// A generalized sphere ψ(x) = a|x|² − ⟨b, x⟩ + c = 0 (a plane when a = 0).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Sphere {
    pub a: f64,
    pub b: DVec3,
    pub c: f64,
}

impl Sphere {
    /// The normalized sphere with centre `center` and signed radius `signed_r` (≠ 0):
    /// a = 1/(2r), b = centre/r, c = (|centre|² − r²)/(2r).
    pub fn from_center_radius(center: DVec3, signed_r: f64) -> Self {
        let r = signed_r;
        Self { a: 0.5 / r, b: center / r, c: (center.length_squared() - r * r) / (2.0 * r) }
    }

    /// The normalized sphere through `f`, tangent there to the plane with unit normal `n`, with
    /// curvature `h` measured w.r.t. `n` (centre f + n/h, signed radius 1/h):
    /// (a, b, c) = (h/2, h f + n, h|f|²/2 + ⟨f, n⟩).
    ///
    /// bᵀb − 4ac = |n|² = 1 for every h, so the result is normalized and finite for any finite h;
    /// h = 0 gives the tangent plane ⟨n, x − f⟩ = 0 with b = n.
    pub fn from_point_normal_curvature(f: DVec3, n: DVec3, h: f64) -> Self {
        Self { a: 0.5 * h, b: h * f + n, c: 0.5 * h * f.length_squared() + f.dot(n) }
    }

    /// The plane through `p` with unit normal `n` (normalized: b = n).
    pub fn plane(p: DVec3, n: DVec3) -> Self {
        Self::from_point_normal_curvature(p, n, 0.0)
    }

    /// bᵀb − 4ac: 1 for a normalized sphere, < 0 for an imaginary one.
    pub fn discriminant(&self) -> f64 {
        self.b.length_squared() - 4.0 * self.a * self.c
    }

    /// Scaled by 1/√(bᵀb − 4ac) (a positive factor: the orientation is kept). Imaginary or
    /// degenerate coefficient vectors (discriminant ≤ 0) are returned unchanged.
    pub fn normalized(&self) -> Self {
        let d = self.discriminant();
        if d > 0.0 && d.is_finite() {
            let s = 1.0 / d.sqrt();
            Self { a: self.a * s, b: self.b * s, c: self.c * s }
        } else {
            *self
        }
    }

    /// True when |a| ≤ eps·√(bᵀb − 4ac), i.e. (normalized) when the radius is at least 1/(2 eps).
    pub fn is_plane(&self, eps: f64) -> bool {
        let d = self.discriminant().max(0.0).sqrt();
        self.a.abs() <= eps * d
    }

    /// The centre b/(2a); None for a plane (a = 0) or when it is not finite.
    pub fn center(&self) -> Option<DVec3> {
        if self.a == 0.0 {
            return None;
        }
        let c = self.b / (2.0 * self.a);
        c.is_finite().then_some(c)
    }

    /// Signed radius √(bᵀb − 4ac)/(2a) (= 1/(2a) when normalized); None for a plane, an imaginary
    /// sphere or a non-finite value.
    pub fn signed_radius(&self) -> Option<f64> {
        let d = self.discriminant();
        if self.a == 0.0 || d < 0.0 {
            return None;
        }
        let r = d.sqrt() / (2.0 * self.a);
        r.is_finite().then_some(r)
    }

    /// ψ(x) = a|x|² − ⟨b, x⟩ + c. For a normalized sphere (|x − c|² − r²)/(2r); for the normalized
    /// plane through p with unit normal n, −⟨n, x − p⟩.
    pub fn eval(&self, x: DVec3) -> f64 {
        self.a * x.length_squared() - self.b.dot(x) + self.c
    }

    /// The inversive product b·b' − 2(a c' + a' c). For two normalized spheres it is the cosine of
    /// their intersection angle (the angle between their oriented normals (x − cᵢ)/rᵢ on the common
    /// circle); ⟨s, s⟩ = 1 is the normalization.
    pub fn inversive_product(&self, other: &Sphere) -> f64 {
        self.b.dot(other.b) - 2.0 * (self.a * other.c + other.a * self.c)
    }

    /// All coefficients finite.
    pub fn is_finite(&self) -> bool {
        self.a.is_finite() && self.b.is_finite() && self.c.is_finite()
    }
}

// --- Sphere toolkit (notes/sphere-geometry.md) ---------------------------------------------------
//
// Conventions used below (all checked in `tests/sphere_toolkit.rs`):
// - The **oriented normal** of a normalized sphere at a point x on it is N(x) = b − 2a x (unit
//   there, since |b − 2ax|² = 1 + 4aψ(x)). For r > 0 it points to the centre: N = (c − x)/r; for a
//   plane it is b. `from_point_normal_curvature(f, n, h)` has N(f) = n. Multiplying (a, b, c) by
//   −1 flips the orientation ([`Sphere::flipped`]).
// - The inversive product ⟨s₁, s₂⟩ = N₁·N₂ on the common circle, so with both spheres oriented
//   like the surface the **kink angle** of two panels is arccos⟨s₁, s₂⟩, computed stably by
//   [`Sphere::kink_angle`].
// - A similarity x = t + σ y (σ > 0) maps coefficients to (a σ², σ(b − 2a t), ψ(t)) in the y-frame
//   ([`Sphere::in_frame`]); bᵀb − 4ac scales by σ² and the orientation is kept. The toolkit solves
//   its small linear systems in frames centred at the data and scaled to it, then maps back.

impl Sphere {
    /// (a, b₁, b₂, b₃, c).
    pub fn to_array(&self) -> [f64; 5] {
        [self.a, self.b.x, self.b.y, self.b.z, self.c]
    }

    /// From (a, b₁, b₂, b₃, c).
    pub(crate) fn from_array(v: [f64; 5]) -> Self {
        Self { a: v[0], b: DVec3::new(v[1], v[2], v[3]), c: v[4] }
    }

    /// The same point set with the opposite orientation: (−a, −b, −c). The signed radius changes
    /// sign, the centre is kept.
    pub fn flipped(&self) -> Self {
        Self { a: -self.a, b: -self.b, c: -self.c }
    }

    /// Linear combination w₀ s₀ + w₁ s₁ of coefficient vectors (not normalized).
    pub fn combine(s0: &Sphere, w0: f64, s1: &Sphere, w1: f64) -> Self {
        Self { a: w0 * s0.a + w1 * s1.a, b: w0 * s0.b + w1 * s1.b, c: w0 * s0.c + w1 * s1.c }
    }

    /// The sum of coefficient vectors (a, b, c) (each already weighted by the caller), normalized
    /// where it is a real sphere or plane (bᵀb − 4ac > 0): the blend of neighbouring spheres
    /// oriented alike, e.g. the central spheres at a face's or a triangle's corners.
    pub fn blend(terms: impl IntoIterator<Item = [f64; 5]>) -> Self {
        let mut sum = [0.0; 5];
        for t in terms {
            for (s, t) in sum.iter_mut().zip(t) {
                *s += t;
            }
        }
        let sum = Sphere::from_array(sum);
        if sum.discriminant() > 0.0 {
            sum.normalized()
        } else {
            sum
        }
    }

    /// The oriented normal b − 2a x. Unit at points of a normalized sphere; for r > 0 it points to
    /// the centre, for a plane it is b. ψ decreases along it.
    pub fn normal_at(&self, x: DVec3) -> DVec3 {
        self.b - 2.0 * self.a * x
    }

    /// The oriented unit normal at `x`: [`Self::normal_at`] normalized (+z where it vanishes).
    pub(crate) fn unit_normal_at(&self, x: DVec3) -> DVec3 {
        self.normal_at(x).try_normalize().unwrap_or(DVec3::Z)
    }

    /// `self` or its flip, whichever has ⟨normal_at(x), n⟩ ≥ 0 (x a point on the sphere, n the
    /// desired outward direction there).
    pub fn orient_toward(&self, x: DVec3, n: DVec3) -> Self {
        if self.normal_at(x).dot(n) < 0.0 {
            self.flipped()
        } else {
            *self
        }
    }

    /// Unsigned Euclidean distance from `x` to a **normalized** sphere or plane, | |x − c| − |r| |,
    /// evaluated without cancellation for huge radii: with ψ = ψ(x), |x − c| = |r|√(1 + 4aψ), so
    /// |x − c| − |r| = 2 sign(a) ψ / (1 + √(1 + 4aψ)) (= |ψ| for a plane).
    pub fn distance(&self, x: DVec3) -> f64 {
        let psi = self.eval(x);
        let q = (1.0 + 4.0 * self.a * psi).max(0.0);
        (2.0 * psi / (1.0 + q.sqrt())).abs()
    }

    /// The point of a **normalized** sphere or plane closest to `x`: x moved along the (radial)
    /// normal by its signed distance 2ψ/(1 + √(1 + 4aψ)), without cancellation for huge radii.
    /// Undefined at the centre.
    pub fn closest_point(&self, x: DVec3) -> DVec3 {
        let psi = self.eval(x);
        let q = (1.0 + 4.0 * self.a * psi).max(0.0);
        x + (2.0 * psi / (1.0 + q.sqrt())) * self.unit_normal_at(x)
    }

    /// The row of the linear condition "passes through p": [|p|², −p, 1] · (a, b, c) = ψ(p).
    pub fn point_row(p: DVec3) -> [f64; 5] {
        [p.length_squared(), -p.x, -p.y, -p.z, 1.0]
    }

    /// The row r with r · (a', b', c') = ⟨self, s'⟩ (inversive product): [−2c, b, −2a]. For Ω's
    /// coefficients it is the condition "orthogonal to Ω".
    pub fn inversive_row(&self) -> [f64; 5] {
        [-2.0 * self.c, self.b.x, self.b.y, self.b.z, -2.0 * self.a]
    }

    /// Coefficients in the frame y = (x − t)/σ (σ > 0): (a σ², σ(b − 2a t), ψ(t)), the same set
    /// with the same orientation; bᵀb − 4ac is multiplied by σ².
    pub fn in_frame(&self, t: DVec3, sigma: f64) -> Self {
        Self { a: self.a * sigma * sigma, b: sigma * (self.b - 2.0 * self.a * t), c: self.eval(t) }
    }

    /// The sphere moved by the rigid motion x ↦ R x + t: with x = Rᵀ(y − t), ψ(x) =
    /// a|y|² − ⟨2a t + R b, y⟩ + c + a|t|² + ⟨R b, t⟩ (planes included).
    pub fn moved(&self, rotation: glam::DMat3, t: DVec3) -> Self {
        let rb = rotation * self.b;
        Self { a: self.a, b: 2.0 * self.a * t + rb, c: self.c + self.a * t.length_squared() + rb.dot(t) }
    }

    /// Inverse of [`Self::in_frame`]: coefficients given in the frame y = (x − t)/σ, back in x.
    pub fn from_frame(&self, t: DVec3, sigma: f64) -> Self {
        let a = self.a / (sigma * sigma);
        let b = self.b / sigma + 2.0 * a * t;
        // ψ_y(0) = ψ_x(t) = a|t|² − ⟨b, t⟩ + c.
        let c = self.c - a * t.length_squared() + b.dot(t);
        Self { a, b, c }
    }

    /// The spheres through three points form a pencil: the 2-dimensional null space of the 3 × 5
    /// matrix of their [`Self::point_row`]s. It is computed by a Jacobi SVD in the frame centred
    /// at the centroid and scaled by the largest distance from it, and returned as a normalized
    /// basis that is orthonormal for the inversive product:
    /// - `[0]`: the plane of the points, oriented by (p₁ − p₀) × (p₂ − p₀);
    /// - `[1]`: the sphere through them with its centre in that plane (their circumcircle's
    ///   smallest sphere), with positive radius, i.e. its normal points to the centre.
    ///
    /// Every sphere through the points is, up to a positive factor, cos θ `[0]` + sin θ `[1]`,
    /// which is already normalized. On the points the normal of that member is
    /// cos θ n + sin θ (in-plane), so the members with cos θ > 0 are the ones oriented like the
    /// triangle. Collinear points give two planes through their line; coincident points give
    /// some spheres through them.
    pub fn through_points_family(p: [DVec3; 3]) -> [Sphere; 2] {
        let (t, sigma) = point_frame(&p);
        let [s0, s1] = family_in_frame(&p, t, sigma);
        [s0.from_frame(t, sigma).normalized(), s1.from_frame(t, sigma).normalized()]
    }

    /// The sphere through three points with signed curvature `curvature` (2a, normalized, along
    /// its own orientation) nearest `near` (a sphere through them, whose orientation it keeps):
    /// in [`Self::through_points_family`], cos φ `[0]` + sin φ `[1]` has curvature sin φ / ρ (ρ
    /// the circumradius), so sin φ = κρ, and of φ and π − φ the one nearer `near`'s angle. None
    /// when |κ| ρ > 1: no sphere of that radius passes through the points.
    pub fn through_points_with_curvature(p: [DVec3; 3], curvature: f64, near: &Sphere) -> Option<Sphere> {
        let [plane, centred] = Self::through_points_family(p);
        // `centred` is normalized with positive radius ρ = 1/(2a).
        let rho_k = curvature / (2.0 * centred.a);
        if !rho_k.is_finite() || rho_k.abs() > 1.0 + 1e-12 {
            return None;
        }
        let phi = rho_k.clamp(-1.0, 1.0).asin();
        let current = near.inversive_product(&centred).atan2(near.inversive_product(&plane));
        let gap = |a: f64| (a - current + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
        let phi = if gap(phi).abs() <= gap(std::f64::consts::PI - phi).abs() { phi } else { std::f64::consts::PI - phi };
        Some(Sphere::combine(&plane, phi.cos(), &centred, phi.sin()).normalized())
    }

    /// The sphere through three points orthogonal to Ω: the null vector of the 4 × 5 matrix of
    /// the three [`Self::point_row`]s and Ω's row, normalized. Computed as the member of
    /// [`Self::through_points_family`] (in the local frame of the points) on which Ω's row
    /// vanishes: s = ⟨s₁, Ω⟩ s₀ − ⟨s₀, Ω⟩ s₁, so planes (a → 0) need no special case. Works for
    /// R² > 0, R² < 0, R² = 0 (the sphere passes through m) and for Ω a plane (the centre lies in
    /// it). Oriented like the triangle (p₁ − p₀) × (p₂ − p₀) (see the family). None when the
    /// points coincide or every member is orthogonal to Ω (e.g. R² = 0 and m on their circle).
    /// `omega` is Ω's coefficients (`AbsoluteSphere::coefficients`).
    pub fn through_points_orthogonal(p: [DVec3; 3], omega: &Sphere) -> Option<Sphere> {
        let (t, sigma) = point_frame(&p);
        if !(sigma > 0.0) || !sigma.is_finite() {
            return None;
        }
        let [s0, s1] = family_in_frame(&p, t, sigma);
        let o = omega.in_frame(t, sigma);
        // Scale Ω's row to unit size so that the degeneracy test is relative.
        let scale = o.a.abs().max(o.b.length()).max(o.c.abs());
        if !(scale > 0.0) || !scale.is_finite() {
            return None;
        }
        let o = Sphere { a: o.a / scale, b: o.b / scale, c: o.c / scale };
        combine_orthogonal(&s0, &s1, &o).map(|s| s.from_frame(t, sigma).normalized())
    }

    /// The kink angle (radians, in [0, π]) of two panels along their common circle: the angle
    /// between their oriented normals there, arccos⟨s₁, s₂⟩ for normalized spheres oriented alike
    /// (0 = tangent continuous). Evaluated as 2 atan2(|s₁ − s₂|, |s₁ + s₂|) with the inversive
    /// norm |s|² = bᵀb − 4ac (|s₁ ∓ s₂|² = 2 ∓ 2 cos φ), accurate for small angles too. For
    /// spheres that do not meet (|⟨s₁, s₂⟩| > 1) the result is 0 or π.
    pub fn kink_angle(&self, other: &Sphere) -> f64 {
        let d = Sphere::combine(self, 1.0, other, -1.0).discriminant().max(0.0).sqrt();
        let s = Sphere::combine(self, 1.0, other, 1.0).discriminant().max(0.0).sqrt();
        2.0 * d.atan2(s)
    }
}

/// Centroid and largest distance from it.
fn point_frame(p: &[DVec3; 3]) -> (DVec3, f64) {
    let t = (p[0] + p[1] + p[2]) / 3.0;
    let sigma = p.iter().map(|q| (*q - t).length()).fold(0.0, f64::max);
    (t, sigma)
}

/// The inversive-orthonormal family basis [plane, centred sphere] in the frame (t, σ).
fn family_in_frame(p: &[DVec3; 3], t: DVec3, sigma: f64) -> [Sphere; 2] {
    let inv = if sigma > 0.0 && sigma.is_finite() { 1.0 / sigma } else { 1.0 };
    let y = p.map(|q| (q - t) * inv);
    let rows = [Sphere::point_row(y[0]), Sphere::point_row(y[1]), Sphere::point_row(y[2])];
    let svd = Svd::new(&rows);
    let n1 = Sphere::from_array(svd.v[3]);
    let n2 = Sphere::from_array(svd.v[4]);
    let normal = (y[1] - y[0]).cross(y[2] - y[0]);
    // The plane member: a = 0 exactly (a₂a₁ − a₁a₂ rounds to 0).
    let mut plane = if n1.a == 0.0 && n2.a == 0.0 { n1 } else { Sphere::combine(&n1, n2.a, &n2, -n1.a) };
    if plane.discriminant() <= 0.0 {
        plane = n1;
    }
    let plane = plane.normalized();
    let plane = if plane.b.dot(normal) < 0.0 { plane.flipped() } else { plane };
    // The member orthogonal to it, by Gram–Schmidt in the inversive product (positive definite on
    // a pencil of real spheres): start from the basis vector farther from the plane.
    let other = if n1.a.abs() >= n2.a.abs() { n1 } else { n2 };
    let other = Sphere::combine(&other, 1.0, &plane, -other.inversive_product(&plane)).normalized();
    let other = if other.a < 0.0 { other.flipped() } else { other };
    [plane, other]
}

/// The member of the orthonormal pencil (s₀, s₁) orthogonal to `o`, oriented with a non-negative
/// s₀ component and normalized; None when every member is orthogonal to `o`.
fn combine_orthogonal(s0: &Sphere, s1: &Sphere, o: &Sphere) -> Option<Sphere> {
    let alpha = s1.inversive_product(o);
    let beta = s0.inversive_product(o);
    let h = alpha.hypot(beta);
    if !(h > 1e-13) {
        return None;
    }
    let sign = if alpha < 0.0 { -1.0 } else { 1.0 };
    Some(Sphere::combine(s0, sign * alpha / h, s1, -sign * beta / h))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ψ of a moved sphere (or plane) at a moved point is ψ at the point: what lies on the
    /// sphere lies on its image.
    #[test]
    fn a_rigid_motion_moves_spheres_and_planes_onto_their_images() {
        let rotation = glam::DMat3::from_quat(glam::DQuat::from_scaled_axis(DVec3::new(0.3, -0.2, 0.5)));
        let t = DVec3::new(1.0, -2.0, 0.5);
        let sphere = Sphere::from_center_radius(DVec3::new(0.2, 0.1, -0.3), 1.7);
        let plane = Sphere { a: 0.0, b: DVec3::new(0.0, 0.6, 0.8), c: 0.25 };
        for (x, points) in [
            (
                sphere,
                (0..20)
                    .map(|k| DVec3::new(0.2, 0.1, -0.3) + 1.7 * DVec3::new((k as f64).cos(), (k as f64).sin() * 0.6, (k as f64).sin() * 0.8))
                    .collect::<Vec<_>>(),
            ),
            (plane, (0..20).map(|k| DVec3::new(k as f64, (k as f64 * 0.3).sin(), 0.1 * k as f64)).collect()),
        ] {
            let moved = x.moved(rotation, t);
            for p in points {
                let before = x.eval(p);
                assert!((moved.eval(rotation * p + t) - before).abs() < 1e-12, "{before} → {}", moved.eval(rotation * p + t));
            }
        }
    }

    const EPS: f64 = 1e-12;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol * (1.0 + a.abs().max(b.abs()))
    }

    #[test]
    fn center_radius_round_trip() {
        for (c, r) in [(DVec3::new(1.0, -2.0, 0.5), 3.0), (DVec3::new(-4.0, 0.25, 7.0), -0.75), (DVec3::ZERO, 1.0)] {
            let s = Sphere::from_center_radius(c, r);
            assert!(close(s.discriminant(), 1.0, EPS));
            assert!((s.center().unwrap() - c).length() <= EPS * (1.0 + c.length()));
            assert!(close(s.signed_radius().unwrap(), r, EPS));
            // Points on the sphere.
            for d in [DVec3::X, DVec3::new(0.6, 0.0, -0.8), DVec3::new(1.0, 2.0, 2.0) / 3.0] {
                assert!(s.eval(c + r.abs() * d).abs() <= EPS * 10.0, "{}", s.eval(c + r * d));
            }
            // ψ(x) = (|x − c|² − r²)/(2r).
            let x = DVec3::new(0.3, 0.1, -2.0);
            assert!(close(s.eval(x), ((x - c).length_squared() - r * r) / (2.0 * r), EPS));
        }
    }

    #[test]
    fn closest_point_is_the_radial_foot() {
        let x = DVec3::new(0.3, 0.1, -2.0);
        for (c, r) in [(DVec3::new(1.0, -2.0, 0.5), 3.0), (DVec3::new(-4.0, 0.25, 7.0), -0.75), (DVec3::new(0.0, 0.0, 1e7), -1e7)] {
            let s = Sphere::from_center_radius(c, r);
            let foot = s.closest_point(x);
            let exact = c + r.abs() * (x - c).normalize();
            assert!((foot - exact).length() <= 1e-9 * (1.0 + r.abs()), "{foot} vs {exact}");
            assert!(s.eval(foot).abs() <= 1e-9, "{}", s.eval(foot));
        }
        let plane = Sphere::plane(DVec3::new(0.0, 0.0, 1.0), DVec3::Z);
        assert!((plane.closest_point(x) - DVec3::new(0.3, 0.1, 1.0)).length() <= EPS);
    }

    #[test]
    fn point_normal_curvature() {
        let f = DVec3::new(2.0, -1.0, 3.0);
        let n = DVec3::new(1.0, 2.0, -2.0) / 3.0;
        for h in [0.5, -2.0, 1e-9, 0.0, 1e-300] {
            let s = Sphere::from_point_normal_curvature(f, n, h);
            assert!(s.is_finite());
            assert!(close(s.discriminant(), 1.0, EPS), "h={h}: {}", s.discriminant());
            assert!(s.eval(f).abs() <= EPS * 10.0);
            // Tangent plane at f: the gradient 2a f − b is parallel to −n.
            let grad = 2.0 * s.a * f - s.b;
            assert!((grad + n).length() <= EPS * 10.0);
            if h.abs() > 1e-6 {
                let c = s.center().unwrap();
                assert!((c - (f + n / h)).length() <= EPS * (1.0 + c.length()));
                assert!(close(s.signed_radius().unwrap(), 1.0 / h, EPS));
                assert!(!s.is_plane(1e-6));
            }
        }
        let p = Sphere::from_point_normal_curvature(f, n, 0.0);
        assert!(p.is_plane(0.0));
        assert!(p.center().is_none());
        assert!(p.signed_radius().is_none());
        assert_eq!(p, Sphere::plane(f, n));
        // The plane's ψ is minus the signed distance along n.
        assert!(close(p.eval(f + 0.7 * n), -0.7, EPS));
        // Same as from centre/radius.
        let s = Sphere::from_point_normal_curvature(f, n, 0.25);
        let t = Sphere::from_center_radius(f + 4.0 * n, 4.0);
        assert!(close(s.a, t.a, EPS) && (s.b - t.b).length() <= EPS * 10.0 && close(s.c, t.c, EPS));
    }

    #[test]
    fn normalization() {
        let s = Sphere::from_center_radius(DVec3::new(1.0, 2.0, 3.0), -2.5);
        let scaled = Sphere { a: s.a * 7.0, b: s.b * 7.0, c: s.c * 7.0 };
        let back = scaled.normalized();
        assert!(close(back.a, s.a, EPS) && (back.b - s.b).length() <= EPS && close(back.c, s.c, EPS));
        assert!(close(scaled.signed_radius().unwrap(), -2.5, EPS));
        assert!(close(scaled.center().unwrap().z, 3.0, EPS));
        // A plane given with an unnormalized normal.
        let p = Sphere { a: 0.0, b: DVec3::new(0.0, 0.0, 2.0), c: 4.0 }.normalized();
        assert!(close(p.b.z, 1.0, EPS) && close(p.c, 2.0, EPS));
        // Imaginary: unchanged.
        let im = Sphere { a: 1.0, b: DVec3::ZERO, c: 1.0 };
        assert_eq!(im.normalized(), im);
        assert!(im.signed_radius().is_none());
    }

    #[test]
    fn inversive_product_is_cos_of_intersection_angle() {
        // Two explicit spheres: centres (0,0,0) r1 = 1.5 and (2,0,0) r2 = 1. They meet on the circle
        // x = t, t = (d² + r1² − r2²)/(2d) = (4 + 2.25 − 1)/4 = 1.3125, ρ = √(r1² − t²).
        let (c1, r1, c2, r2) = (DVec3::ZERO, 1.5, DVec3::new(2.0, 0.0, 0.0), 1.0);
        let t: f64 = 1.3125;
        let x = DVec3::new(t, (r1 * r1 - t * t).sqrt(), 0.0);
        let (s1, s2) = (Sphere::from_center_radius(c1, r1), Sphere::from_center_radius(c2, r2));
        assert!(s1.eval(x).abs() < EPS && s2.eval(x).abs() < EPS);
        let cos = ((x - c1) / r1).dot((x - c2) / r2);
        assert!(close(s1.inversive_product(&s2), cos, EPS));
        assert!(close(s1.inversive_product(&s2), (r1 * r1 + r2 * r2 - 4.0) / (2.0 * r1 * r2), EPS));
        // Flipping one orientation flips the cosine.
        let s3 = Sphere::from_center_radius(c2, -r2);
        assert!(close(s1.inversive_product(&s3), -cos, EPS));
        // Orthogonal spheres: d² = r1² + r2².
        let o = Sphere::from_center_radius(DVec3::new(0.0, 0.0, (r1 * r1 + 1.0f64).sqrt()), 1.0);
        assert!(s1.inversive_product(&o).abs() < EPS);
        // A sphere and a plane through its centre meet at 90°; a tangent plane at 0°.
        let through = Sphere::plane(c1, DVec3::Y);
        assert!(s1.inversive_product(&through).abs() < EPS);
        let tangent = Sphere::from_point_normal_curvature(DVec3::new(0.0, 0.0, 1.5), DVec3::Z, 0.0);
        assert!(close(s1.inversive_product(&tangent).abs(), 1.0, EPS));
        assert!(close(s1.inversive_product(&s1), 1.0, EPS));
    }
}
