//! The absolute sphere Ω (Sec. 2.4, 4): the sphere (real, imaginary or zero, R² of any sign) or
//! plane that every face sphere of an ST mesh with support structure is orthogonal to, with its
//! power, inversion and the orthogonality condition (`notes/sphere-geometry.md`).

// Negated float comparisons are deliberate: they also reject NaN.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::sphere::Sphere;

/// The absolute sphere Ω of an ST mesh with support structure (Sec. 4): centre m and R² (real,
/// imaginary or zero), or, when m is at infinity, the plane ⟨x, axis⟩ = d.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum AbsoluteSphere {
    Sphere { center: DVec3, r2: f64 },
    Plane { axis: DVec3, d: f64 },
}

impl AbsoluteSphere {
    /// The generalized-sphere coefficients of Ω, unnormalized: (1, 2m, |m|² − R²) for a sphere,
    /// so that `eval(x)` is the power |x − m|² − R² (valid for R² < 0 too, where bᵀb − 4ac < 0);
    /// (0, −a, −d) for the plane ⟨x, a⟩ = d, so that `eval(x)` = ⟨x, a⟩ − d.
    pub fn coefficients(&self) -> Sphere {
        match *self {
            AbsoluteSphere::Sphere { center, r2 } => Sphere { a: 1.0, b: 2.0 * center, c: center.length_squared() - r2 },
            AbsoluteSphere::Plane { axis, d } => Sphere { a: 0.0, b: -axis, c: -d },
        }
    }

    /// The linear condition on a sphere s = (a, b, c) to be orthogonal to Ω (notes, "Linear
    /// conditions"): [|m|² − R², −m, 1] · s = ψ_s(m) − a R² = 0 for a sphere, i.e.
    /// |c − m|² − r² = R²; [−2d, a, 0] · s = 0 for the plane ⟨x, a⟩ = d (the centre lies in it).
    /// Proportional to the inversive row of [`Self::coefficients`].
    pub fn row(&self) -> [f64; 5] {
        match *self {
            AbsoluteSphere::Sphere { center, r2 } => [center.length_squared() - r2, -center.x, -center.y, -center.z, 1.0],
            AbsoluteSphere::Plane { axis, d } => [-2.0 * d, axis.x, axis.y, axis.z, 0.0],
        }
    }

    /// The power of x: |x − m|² − R²; for a plane the signed distance ⟨x, a⟩ − d.
    pub fn power(&self, x: DVec3) -> f64 {
        match *self {
            AbsoluteSphere::Sphere { center, r2 } => (x - center).length_squared() - r2,
            AbsoluteSphere::Plane { axis, d } => x.dot(axis) - d,
        }
    }

    /// Inversion in Ω: m + R² (x − m)/|x − m|². R² < 0 is the anti-inversion (through m to the
    /// other side), R² = 0 maps every x ≠ m to m. For a plane it is the reflection in it. Every
    /// sphere orthogonal to Ω is mapped onto itself. None for x = m (or non-finite results).
    pub fn invert(&self, x: DVec3) -> Option<DVec3> {
        let y = match *self {
            AbsoluteSphere::Sphere { center, r2 } => {
                let d = x - center;
                let l2 = d.length_squared();
                if !(l2 > 0.0) {
                    return None;
                }
                center + (r2 / l2) * d
            }
            AbsoluteSphere::Plane { axis, d } => x - 2.0 * (x.dot(axis) - d) * axis,
        };
        y.is_finite().then_some(y)
    }

    /// Centre m (None for a plane).
    pub fn center(&self) -> Option<DVec3> {
        match *self {
            AbsoluteSphere::Sphere { center, .. } => Some(center),
            AbsoluteSphere::Plane { .. } => None,
        }
    }

    /// How far a normalized sphere s is from being orthogonal to Ω:
    /// - Ω a sphere: the power defect | |c − m|² − r² − R² | = |row · s| / |a| (an area); for a
    ///   plane s (|a| ≤ 1e-300) the distance of m from it, |ψ_s(m)| (planes orthogonal to Ω pass
    ///   through m);
    /// - Ω a plane: the distance of s's centre from it, |⟨c, a⟩ − d|; for a plane s, |⟨b_s, a⟩|
    ///   (the cosine of its angle to Ω: 0 when perpendicular to it).
    pub fn orthogonality_defect(&self, s: &Sphere) -> f64 {
        let row = self.row();
        let dot: f64 = row.iter().zip(s.to_array()).map(|(r, x)| r * x).sum();
        match self {
            AbsoluteSphere::Sphere { center, .. } => {
                if s.a.abs() > 1e-300 {
                    (dot / s.a).abs()
                } else {
                    s.eval(*center).abs()
                }
            }
            AbsoluteSphere::Plane { .. } => {
                if s.a.abs() > 1e-300 {
                    (dot / (2.0 * s.a)).abs()
                } else {
                    dot.abs()
                }
            }
        }
    }
}
