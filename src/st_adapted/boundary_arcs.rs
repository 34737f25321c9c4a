//! The arcs the method delivers ([`delivered_arcs`]). Those of the boundary edges (one face each): cut from the face sphere by the plane through
//! the edge whose circle passes nearest the reference boundary, so the panels follow the
//! boundary instead of overhanging it.
//!
//! The paper leaves boundary arcs open (Sec. 3). Of the circles of a face sphere through the
//! edge's vertices p and q, the arc midpoints fill the great circle of the sphere in the
//! bisector plane of pq. The arc is the one whose midpoint is the point of that great circle
//! closest to b, the reference boundary's point closest to the chord midpoint: b projected into
//! the bisector plane, then radially onto the sphere. For a boundary curve that lies on the
//! sphere the arc passes through it; a great-circle arc (the rule it replaces) deviates from a
//! boundary with geodesic curvature κ_g by about κ_g·|pq|²/8.

use std::collections::HashMap;

use glam::DVec3;

use crate::panels::bisect_unbuildable_arcs;
use crate::panels::edge_arcs::{cuts_straight, EdgeArcs};
use crate::panels::sphere_mesh::SphereMesh;
use crate::reference::Reference;

/// The farthest the arc midpoint may lie from the chord midpoint, × the chord length: a
/// quarter keeps the arc well under a half circle, so it is the minor arc the panel takes.
const MAX_BULGE: f64 = 0.25;

/// Per boundary edge (lo, hi) of `sphere_mesh`: the normal of its cutting plane. An edge is left
/// out, and keeps the mesh's [`SphereMesh::boundary_arcs`] rule, when its face sphere is a plane
/// (any cut is the straight edge), when the reference boundary is farther than
/// [`MAX_BULGE`] × its length from its midpoint, or when the arc would bulge farther than that
/// (a corner or a thin strip of the reference).
pub fn boundary_planes(sphere_mesh: &SphereMesh, reference: &Reference) -> HashMap<[u32; 2], DVec3> {
    let topology = sphere_mesh.topology();
    let positions = &sphere_mesh.mesh.positions;
    let boundary = reference.boundary_bvh();
    let diag = reference.diagonal();
    let mut planes = HashMap::new();
    for (e, &[lo, hi]) in topology.edges().iter().enumerate() {
        let &[(f, _)] = topology.edge_faces(e) else { continue };
        let sphere = &sphere_mesh.face_spheres[f as usize];
        if cuts_straight(sphere, diag) {
            continue;
        }
        let (p, q) = (positions[lo as usize], positions[hi as usize]);
        let length = p.distance(q);
        let mid = 0.5 * (p + q);
        let Some(hit) = boundary.closest_point_within(mid, MAX_BULGE * length) else { continue };
        let u = (q - p) / length;
        let b = hit.point - (hit.point - mid).dot(u) * u;
        let bulge = sphere.closest_point(b) - mid;
        if bulge.length() > MAX_BULGE * length {
            continue;
        }
        if let Some(n) = u.cross(bulge).try_normalize() {
            planes.insert([lo, hi], n);
        }
    }
    planes
}

/// `sphere_mesh` with the arcs the method delivers: its boundary edges cut along the reference
/// boundary ([`boundary_planes`]) and, in variant (a), the interior edges whose intersection arc
/// would cross another or sweep too wide cut by bisecting planes ([`bisect_unbuildable_arcs`]).
pub fn delivered_arcs(sphere_mesh: SphereMesh, reference: &Reference, variant: EdgeArcs) -> SphereMesh {
    let planes = boundary_planes(&sphere_mesh, reference);
    let sphere_mesh = sphere_mesh.with_boundary_planes(planes);
    match variant {
        EdgeArcs::Intersection => bisect_unbuildable_arcs(sphere_mesh),
        EdgeArcs::BisectingPlanes => sphere_mesh,
    }
}
