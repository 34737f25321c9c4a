//! A mesh with spherical faces: every triangle carries a (normalized, generalized) face sphere
//! through its three vertices. Panels, support structures and exports are derived from it.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::mesh::TriMesh;
use crate::sphere::Sphere;

/// The absolute sphere Ω of an ST mesh with support structure (Sec. 4): centre m and R² (real,
/// imaginary or zero), or, when m is at infinity, the plane ⟨x, axis⟩ = d.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum AbsoluteSphere {
    Sphere { center: DVec3, r2: f64 },
    Plane { axis: DVec3, d: f64 },
}

/// A circle in space: centre, unit normal of its plane, radius.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Circle {
    pub center: DVec3,
    pub normal: DVec3,
    pub radius: f64,
}

/// How the arc of a boundary edge (one face only) is cut from its face sphere: by the plane
/// through the edge's two vertices that also contains `through` (a point, e.g. m) or is parallel
/// to `parallel` (a direction, e.g. the axis a). Interior edges use the intersection circle of
/// the two adjacent face spheres.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum BoundaryArcRule {
    Through(DVec3),
    Parallel(DVec3),
}

/// A mesh with spherical triangle faces.
#[derive(Clone, Debug, PartialEq)]
pub struct SphereMesh {
    pub mesh: TriMesh,
    /// One normalized sphere per face, oriented like the face (its outward side follows the
    /// reference normal).
    pub face_spheres: Vec<Sphere>,
    pub boundary_arcs: BoundaryArcRule,
}

/// The torsion-free support structure of an ST mesh (Sec. 2.2, 4, Fig. 1).
#[derive(Clone, Debug, PartialEq)]
pub struct SupportStructure {
    /// Per vertex: a point on the node axis (the vertex itself) and its unit direction, pointing
    /// from the vertex toward the support side (toward m, or along −a).
    pub node_axes: Vec<(DVec3, DVec3)>,
    /// Depth of the planar support elements, along the node axes.
    pub depth: f64,
}

/// A planar support element of an ST mesh with support structure (Sec. 2.2, 4, Fig. 1): the
/// annulus sector in the plane of an edge's circle, between the two node axes, bounded by the
/// edge arc (outer) and its offset toward m by the support depth (inner). Produced by
/// `st_support`; the inner circle is concentric with the outer one (radius ∓ depth) where the node
/// axes reach it, else the circle through the offset corners and the offset arc midpoint.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SupportElement {
    /// The mesh edge (lo, hi), vertex ids.
    pub edge: [u32; 2],
    /// The circle of the edge arc, through both edge vertices; its normal is the element's plane
    /// normal.
    pub circle: Circle,
    /// The circle of the inner (offset) arc, in the same plane, through corners[2] and corners[3].
    pub inner_circle: Circle,
    /// [v_lo, v_hi, inner point on v_hi's node axis, inner point on v_lo's node axis]: the arc
    /// runs from corners[0] to corners[1] (the shorter way), the inner arc from corners[3] to
    /// corners[2].
    pub corners: [DVec3; 4],
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
        let orient = if s1.a != 0.0 && s2.a != 0.0 { (s1.a * s2.a).signum() } else if s2.a == 0.0 { -s1.a.signum() } else { s2.a.signum() };
        let normal = n / len * orient;
        Self::cut(sphere, n / len, k / len).map(|c| Circle { normal, ..c })
    }

    /// The circle where the plane through `p` with normal `n` cuts `sphere`.
    pub fn plane_cut(sphere: &Sphere, p: DVec3, n: DVec3) -> Option<Circle> {
        let n = n.try_normalize()?;
        Self::cut(sphere, n, n.dot(p))
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
