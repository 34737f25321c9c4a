//! The circle of every edge's arc, from which its support element is cut (Sec. 2.2, 4).

// Negated float comparisons are deliberate: they also reject NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use glam::DVec3;

use crate::geometry::circle::Circle;
use crate::geometry::sphere::Sphere;
use crate::panels::sphere_mesh::BoundaryArcRule;

/// The circle of the arc of edge (u, w) on face sphere `s1` (and `s2`, the other face's sphere, for
/// an interior edge). In theory the arc's plane is both the radical plane of s1 and s2 and the
/// [`BoundaryArcRule`] plane through u, w and m (or parallel to a), since it contains u, w, ū, w̄
/// and so both node axes. Numerically the radical plane is ill-conditioned when the two spheres
/// nearly coincide (its tilt errs by ≈ ε / sin φ, φ the kink angle: 1e-7 rad at φ ≈ 1e-9 rad,
/// which occurs after optimizing R), and the rule plane when m is nearly on the edge's line. So
/// the better conditioned of the two is used: the radical circle ([`Circle::intersection`]) when
/// sin φ ≥ sin ∠(w − u, m − u) (resp. ∠(w − u, a)), else the rule plane's cut of s1 (or s2 if s1
/// is a plane), its normal oriented like c₁ − c₂. Boundary edges: the rule plane. None when no
/// real circle results (e.g. both spheres planes).
pub fn edge_circle(
    s1: &Sphere,
    s2: Option<&Sphere>,
    u: DVec3,
    w: DVec3,
    rule: &BoundaryArcRule,
) -> Option<Circle> {
    let e = w - u;
    let (n, q_plane) = match *rule {
        BoundaryArcRule::Through(m) => {
            let n = e.cross(m - u);
            (n, n.length() / (e.length() * (m - u).length()))
        }
        BoundaryArcRule::Parallel(a) => {
            let n = e.cross(a);
            (n, n.length() / (e.length() * a.length()))
        }
    };
    let q_plane = if q_plane.is_finite() { q_plane } else { 0.0 };
    let radical = |s2: &Sphere| Circle::intersection(s1, s2);
    if let Some(s2) = s2 {
        if s1.kink_angle(s2).sin() >= q_plane {
            if let Some(c) = radical(s2) {
                return Some(c);
            }
        }
    }
    let cut = |s: &Sphere| Circle::plane_cut(s, u, n);
    let plane_circle = if s1.a != 0.0 {
        cut(s1)
    } else {
        s2.and_then(cut)
    };
    match plane_circle {
        Some(mut c) => {
            if let (Some(c1), Some(c2)) = (s1.center(), s2.and_then(|s| s.center())) {
                if c.normal.dot(c1 - c2) < 0.0 {
                    c.normal = -c.normal;
                }
            }
            Some(c)
        }
        None => s2.and_then(radical),
    }
}
