//! The arc of every mesh edge (Fig. 12): the intersection circle of the two face spheres
//! (variant (a)), each face sphere cut by the bisecting plane of the two faces (variant (b)), or
//! the boundary rule's plane. See the [`super`] module docs.

// Negated float comparisons are deliberate: they also reject NaN.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::arc::Arc;
use super::sphere_mesh::BoundaryArcRule;
use crate::geometry::circle::Circle;
use crate::geometry::closest::closest_point_on_triangle;
use crate::geometry::mesh::PolyMesh;
use crate::geometry::sphere::Sphere;

/// How the arcs of interior edges are cut (Fig. 12; see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum EdgeArcs {
    /// Variant (a): the intersection circle of the two face spheres, one arc shared by both
    /// panels (no gaps).
    #[default]
    Intersection,
    /// Variant (b): each face sphere cut by the bisecting plane of the two face planes, one arc
    /// per panel (small gaps between adjacent panels, see [`super::gaps::arc_gaps`]).
    BisectingPlanes,
}

impl EdgeArcs {
    /// "a" or "b" (Fig. 12), as in design links, the CLI and reports.
    pub fn key(self) -> &'static str {
        match self {
            EdgeArcs::Intersection => "a",
            EdgeArcs::BisectingPlanes => "b",
        }
    }

    pub fn from_key(key: &str) -> Option<Self> {
        [EdgeArcs::Intersection, EdgeArcs::BisectingPlanes].into_iter().find(|v| v.key() == key)
    }
}

/// Normal of the bisecting plane of edge p→q between two faces with area vectors `af`, `ag`
/// (variant (b), Fig. 12): the plane through the edge containing n_f + n_g (n_f − n_g when the
/// faces are not `consistent`ly oriented along the edge). If that direction is (nearly) along
/// the edge, the plane containing n_f, else n_g; `None` when all are degenerate.
pub(crate) fn bisecting_plane_normal(p: DVec3, q: DVec3, af: DVec3, ag: DVec3, consistent: bool) -> Option<DVec3> {
    let eh = (q - p).try_normalize()?;
    let (nf, ng) = (af.normalize_or_zero(), ag.normalize_or_zero());
    let sum = if consistent { nf + ng } else { nf - ng };
    [sum, nf, ng].into_iter().find_map(|d| {
        let n = eh.cross(d);
        (n.length() > 1e-6 && n.is_finite()).then(|| n.normalize())
    })
}

/// An [`EdgeArcs`] written as its key ("a" or "b"), as reports carry it.
pub mod as_key {
    use crate::panels::edge_arcs::EdgeArcs;
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(v: &EdgeArcs, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(v.key())
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<EdgeArcs, D::Error> {
        let key = String::deserialize(d)?;
        EdgeArcs::from_key(&key).ok_or_else(|| serde::de::Error::custom(format!("unknown edge variant '{key}'")))
    }
}

/// The triangles of face `f` (one for a triangle, two for a quad), for the side tests below.
pub(crate) fn face_triangles(mesh: &PolyMesh, f: usize) -> Vec<[DVec3; 3]> {
    mesh.faces[f].triangles().map(|t| t.map(|v| mesh.positions[v as usize])).collect()
}

/// The arc of edge p→q shared by `faces` (one or two faces).
pub(crate) fn edge_arc(p: DVec3, q: DVec3, faces: &[usize], spheres: &[Sphere], mesh: &PolyMesh, rule: BoundaryArcRule, diag: f64) -> Arc {
    let e = q - p;
    let l = e.length();
    let tris: Vec<Vec<[DVec3; 3]>> = faces.iter().map(|&f| face_triangles(mesh, f)).collect();
    // The more curved sphere (ties: lower face index) carries the cut.
    let cut_face = faces.iter().copied().fold(faces[0], |best, f| if spheres[f].a.abs() > spheres[best].a.abs() { f } else { best });
    let s_cut = spheres[cut_face];
    if l == 0.0 {
        return Arc::straight(p, q, DVec3::Z);
    }
    let eh = e / l;
    if let [f1, f2] = faces {
        let (s1, s2) = (spheres[*f1], spheres[*f2]);
        let g1 = 2.0 * s1.a * p - s1.b;
        let g2 = 2.0 * s2.a * p - s2.b;
        let n = s2.a * g1 - s1.a * g2;
        let scale = s1.a.abs() * g1.length() + s2.a.abs() * g2.length();
        let nl = n.length();
        if nl > 1e-9 * scale && nl.is_finite() && (n.dot(eh) / nl).abs() < 1e-4 {
            return cut_arc(p, q, n, &s_cut, &tris, diag);
        }
    }
    // Boundary rule (also the fallback for ill-conditioned interior edges).
    let g = -(2.0 * s_cut.a * p - s_cut.b);
    let rule_normal = match rule {
        BoundaryArcRule::Through(m) => eh.cross(m - p),
        BoundaryArcRule::Parallel(a) => eh.cross(a),
    };
    let ref_len = match rule {
        BoundaryArcRule::Through(m) => (m - p).length(),
        BoundaryArcRule::Parallel(a) => a.length(),
    };
    let n = if rule_normal.length() > 1e-9 * ref_len && rule_normal.is_finite() { rule_normal } else { eh.cross(g) };
    if !n.is_finite() || n.length() == 0.0 {
        let t = tris[0][0];
        return Arc::straight(p, q, (t[2] - t[0]).cross(t[1] - t[0]).cross(e));
    }
    cut_arc(p, q, n, &s_cut, &tris, diag)
}

/// Whether every plane cut of `s` is a straight edge: a plane, or a sphere so flat
/// (r > 5e11·diag) that it deviates from its tangent plane by < 1e-12·diag over the model.
pub(crate) fn cuts_straight(s: &Sphere, diag: f64) -> bool {
    s.a.abs() * diag <= 1e-12
}

/// The arc p→q of the circle where the plane through p with normal `n` (made orthogonal to the
/// edge) cuts the sphere `s`; the arc nearer the faces (given by their triangles).
pub(crate) fn cut_arc(p: DVec3, q: DVec3, n: DVec3, s: &Sphere, faces: &[Vec<[DVec3; 3]>], diag: f64) -> Arc {
    let e = q - p;
    let l = e.length();
    let eh = e / l;
    let n = (n - n.dot(eh) * eh).normalize();
    let w = n.cross(eh);
    let mid = 0.5 * (p + q);
    if cuts_straight(s, diag) {
        return Arc::straight(p, q, n);
    }
    // Circle centre = M + h w, h = ⟨C − p, w⟩ with C − p = −∇ψ(p)/(2a).
    let g = 2.0 * s.a * p - s.b;
    let h = -g.dot(w) / (2.0 * s.a);
    let half = 0.5 * l;
    let r = half.hypot(h);
    // Distance from the chord midpoint to the near arc point: r − |h| = (l/2)²/(r + |h|).
    let near = half * half / (r + h.abs());
    if !h.is_finite() || !r.is_finite() || near <= 1e-13 * diag {
        return Arc::straight(p, q, n);
    }
    let sign_h = if h >= 0.0 { 1.0 } else { -1.0 };
    // The two arc midpoints lie on the bisector through M: M − sign(h)(r − |h|) w (near side)
    // and M + sign(h)(r + |h|) w.
    let m_near = mid - sign_h * near * w;
    let m_far = mid + sign_h * (r + h.abs()) * w;
    // Sum over the faces of the distance to the face (its nearest triangle).
    let score = |x: DVec3| -> f64 {
        faces.iter().map(|tris| tris.iter().map(|t| closest_point_on_triangle(x, t[0], t[1], t[2]).0.distance(x)).fold(f64::INFINITY, f64::min)).sum()
    };
    let chosen = if score(m_far) < score(m_near) { m_far } else { m_near };
    // p → chosen → q is counter-clockwise about ±n.
    let orient = (chosen - p).cross(q - p).dot(n);
    let normal = if orient >= 0.0 { n } else { -n };
    Arc { circle: Circle { center: mid + h * w, normal, radius: r }, from: p, to: q }
}

/// Normalized face sphere, or the plane of the face's first triangle (corners 0, 1, 2) when the
/// given sphere is unusable (non-finite or imaginary).
pub(crate) fn usable_sphere(s: &Sphere, face: &[DVec3]) -> Sphere {
    let tri = [face[0], face[1], face[2]];
    let n = s.normalized();
    if n.is_finite() && (n.discriminant() - 1.0).abs() < 1e-6 {
        return n;
    }
    let normal = (tri[1] - tri[0]).cross(tri[2] - tri[0]).try_normalize().unwrap_or(DVec3::Z);
    Sphere::plane(tri[0], normal)
}
