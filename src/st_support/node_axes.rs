//! Step 4 of Sec. 4: the node axes, from the spheres ([`star_axis`]): the line through v and the
//! second common point v̄ of the spheres around v. Where a star does not determine it (fewer than
//! 3 faces, or nearly coaxal spheres: condition below [`STAR_AXIS_MIN_CONDITION`]) the axis is the
//! line v m (or parallel to a) and does not count in `max_node_axis_offset`.

use glam::DVec3;

use crate::congruence::support_structure::{star_axis, STAR_AXIS_MIN_CONDITION};
use crate::geometry::absolute_sphere::AbsoluteSphere;
use crate::geometry::mesh::topology::Topology;
use crate::geometry::mesh::TriMesh;
use crate::geometry::sphere::Sphere;
use crate::progress::{Cancelled, OnProgress, Progress};

/// The node axes of an ST mesh with support structure.
pub struct NodeAxes {
    /// Per vertex: the vertex and the unit axis toward the support side (toward m, or along −a).
    pub axes: Vec<(DVec3, DVec3)>,
    /// Per vertex: v̄ from the star's spheres (None where not determined).
    pub second_points: Vec<Option<DVec3>>,
    /// Per vertex: whether its axis comes from its star's spheres.
    pub from_spheres: Vec<bool>,
}

/// The node axes of `mesh` with face spheres `face_spheres`, orthogonal to `omega`; `normals`
/// orient the fallback where m is at a vertex.
pub fn node_axes(
    mesh: &TriMesh,
    topo: &Topology,
    face_spheres: &[Sphere],
    omega: &AbsoluteSphere,
    normals: &[DVec3],
    progress: &mut OnProgress,
) -> Result<NodeAxes, Cancelled> {
    let nv = mesh.vertex_count();
    let support_dir = |v: DVec3, n: DVec3| -> DVec3 {
        match *omega {
            AbsoluteSphere::Sphere { center, .. } => (center - v).try_normalize().unwrap_or(-n),
            AbsoluteSphere::Plane { axis, .. } => -axis,
        }
    };
    let mut axes = Vec::with_capacity(nv);
    let mut second_points = vec![None; nv];
    let mut from_spheres = vec![false; nv];
    let mut star = Vec::new();
    for v in 0..nv {
        if v % 1024 == 0 {
            progress(Progress::new("node_axes", v, nv))?;
        }
        let p = mesh.positions[v];
        let toward = support_dir(p, normals[v]);
        star.clear();
        star.extend(
            topo.vertex_faces(v)
                .iter()
                .map(|&f| face_spheres[f as usize]),
        );
        let mut dir = toward;
        if let Some(axis) = star_axis(&star, p).filter(|a| a.condition >= STAR_AXIS_MIN_CONDITION) {
            dir = if axis.direction.dot(toward) < 0.0 {
                -axis.direction
            } else {
                axis.direction
            };
            second_points[v] = axis.second_point;
            from_spheres[v] = true;
        }
        axes.push((p, dir));
    }
    progress(Progress::new("node_axes", nv, nv))?;
    Ok(NodeAxes {
        axes,
        second_points,
        from_spheres,
    })
}
