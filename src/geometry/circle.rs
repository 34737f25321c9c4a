//! Circles in space: the intersection of two generalized spheres, the cut of a sphere by a
//! plane, and the circle through three points.

// Negated float comparisons are deliberate: they also reject NaN.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::sphere::Sphere;

/// A circle in space: centre, unit normal of its plane, radius.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Circle {
    pub center: DVec3,
    pub normal: DVec3,
    pub radius: f64,
}

impl Circle {
    /// The intersection circle of two generalized spheres (at most one of them a plane). Its
    /// normal points from the second centre to the first (c₁ − c₂), or along the plane's `b`.
    /// `None` when they do not meet in a real circle (or are both planes, or coincide).
    pub fn intersection(s1: &Sphere, s2: &Sphere) -> Option<Circle> {
        // a₂ψ₁ − a₁ψ₂ = 0 is the plane ⟨N, x⟩ = k of the circle (notes: "Intersection circle").
        let n = s2.a * s1.b - s1.a * s2.b;
        let k = s2.a * s1.c - s1.a * s2.c;
        let sphere = if s1.a.abs() >= s2.a.abs() { s1 } else { s2 };
        let len = n.length();
        if len < 1e-300 || !len.is_finite() {
            return None;
        }
        // Orient as c₁ − c₂ = (b₁/a₁ − b₂/a₂)/2, i.e. N times sign(a₁a₂); with a plane, along its b.
        let orient = if s1.a != 0.0 && s2.a != 0.0 {
            (s1.a * s2.a).signum()
        } else if s2.a == 0.0 {
            -s1.a.signum()
        } else {
            s2.a.signum()
        };
        let normal = n / len * orient;
        Self::cut(sphere, n / len, k / len).map(|c| Circle { normal, ..c })
    }

    /// The circle where the plane through `p` with normal `n` cuts `sphere`.
    pub(crate) fn plane_cut(sphere: &Sphere, p: DVec3, n: DVec3) -> Option<Circle> {
        let n = n.try_normalize()?;
        Self::cut(sphere, n, n.dot(p))
    }

    /// The circle through three points, its normal along (b − a) × (c − a); None when they are
    /// (numerically) collinear.
    pub fn through(a: DVec3, b: DVec3, c: DVec3) -> Option<Circle> {
        let (ab, ac) = (b - a, c - a);
        let n = ab.cross(ac);
        let n2 = n.length_squared();
        if !(n2 > 1e-30 * ab.length_squared() * ac.length_squared()) {
            return None;
        }
        let center = a + (ab.length_squared() * ac.cross(n) + ac.length_squared() * n.cross(ab)) / (2.0 * n2);
        Some(Circle { center, normal: n / n2.sqrt(), radius: (a - center).length() })
    }

    /// The point at angle `phi` from the direction `u` (unit, in the plane), counter-clockwise
    /// about the normal: centre + r (cos φ u + sin φ (n × u)).
    pub(crate) fn point_at(&self, u: DVec3, phi: f64) -> DVec3 {
        let (s, c) = phi.sin_cos();
        self.center + self.radius * (c * u + s * self.normal.cross(u))
    }

    /// The angle of `x` about the normal, from the direction `u` (unit, in the plane), in (−π, π].
    pub(crate) fn angle_of(&self, u: DVec3, x: DVec3) -> f64 {
        let d = x - self.center;
        d.dot(self.normal.cross(u)).atan2(d.dot(u))
    }

    /// Sphere (a ≠ 0) cut by the plane ⟨n, x⟩ = k, |n| = 1.
    fn cut(sphere: &Sphere, n: DVec3, k: f64) -> Option<Circle> {
        let c = sphere.center()?;
        let r = sphere.signed_radius()?.abs();
        let t = k - n.dot(c);
        let r2 = r * r - t * t;
        (r2 > 0.0).then(|| Circle { center: c + t * n, normal: n, radius: r2.sqrt() })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn intersection_circle_lies_on_both_spheres() {
        let s1 = Sphere::from_center_radius(DVec3::new(0.0, 0.0, 0.0), 2.0);
        let s2 = Sphere::from_center_radius(DVec3::new(1.5, 0.5, -0.25), -1.25);
        for (a, b) in [(s1, s2), (s2, s1)] {
            let c = Circle::intersection(&a, &b).unwrap();
            let (ca, cb) = (a.center().unwrap(), b.center().unwrap());
            assert!(c.normal.cross(ca - cb).length() < 1e-12 && c.normal.dot(ca - cb) > 0.0);
            let u = c.normal.any_orthonormal_vector();
            let v = c.normal.cross(u);
            for k in 0..12 {
                let phi = k as f64 * 0.5;
                let x = c.center + c.radius * (phi.cos() * u + phi.sin() * v);
                assert!(a.eval(x).abs() < 1e-12 && b.eval(x).abs() < 1e-12);
            }
        }
        let plane = Sphere::plane(DVec3::new(0.0, 0.0, 0.5), DVec3::Z);
        let c = Circle::intersection(&s1, &plane).unwrap();
        assert!((c.radius - (4.0f64 - 0.25).sqrt()).abs() < 1e-12);
        assert!((c.center - DVec3::new(0.0, 0.0, 0.5)).length() < 1e-12);
        assert!(Circle::intersection(&plane, &plane).is_none());
        let far = Sphere::from_center_radius(DVec3::new(10.0, 0.0, 0.0), 1.0);
        assert!(Circle::intersection(&s1, &far).is_none());
    }
}
