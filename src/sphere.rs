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

use glam::DVec3;
use serde::{Deserialize, Serialize};

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

#[cfg(test)]
mod tests {
    use super::*;

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
