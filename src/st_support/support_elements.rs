//! Step 5 of Sec. 4: the support elements. Per edge the arc circle ([`edge_circle`]: interior
//! edges the intersection circle of the two face spheres, boundary edges the plane through the
//! edge and m, or parallel to a) and the annulus sector between the node axes with the given
//! depth ([`support_element`]).

use glam::DVec3;

use crate::congruence::support_structure::{edge_circle, support_element, EdgePlane, SupportElement};
use crate::geometry::mesh::topology::Topology;
use crate::geometry::mesh::TriMesh;
use crate::geometry::sphere::Sphere;
use crate::progress::{Cancelled, OnProgress, Progress};

/// The support elements of `mesh` (absolute `depth`), and how many edges have none (both face
/// spheres planes, or no circle).
pub fn support_elements(
    mesh: &TriMesh,
    topo: &Topology,
    face_spheres: &[Sphere],
    node_axes: &[(DVec3, DVec3)],
    plane: EdgePlane,
    depth: f64,
    progress: &mut OnProgress,
) -> Result<(Vec<SupportElement>, usize), Cancelled> {
    let edges = topo.edges();
    let mut elements = Vec::with_capacity(edges.len());
    let mut without_support = 0;
    for (e, edge) in edges.iter().enumerate() {
        if e % 1024 == 0 {
            progress(Progress::new("support_elements", e, edges.len()))?;
        }
        let faces: Vec<u32> = topo.edge_faces(e).iter().map(|&(f, _)| f).collect();
        let (u, w) = (mesh.positions[edge[0] as usize], mesh.positions[edge[1] as usize]);
        let circle = faces.first().and_then(|&f1| {
            let s2 = (faces.len() == 2).then(|| &face_spheres[faces[1] as usize]);
            edge_circle(&face_spheres[f1 as usize], s2, [u, w], plane)
        });
        let element = circle.and_then(|c| support_element(*edge, c, [u, w], [node_axes[edge[0] as usize].1, node_axes[edge[1] as usize].1], depth));
        match element {
            Some(el) => elements.push(el),
            None => without_support += 1,
        }
    }
    progress(Progress::new("support_elements", edges.len(), edges.len()))?;
    Ok((elements, without_support))
}
