//! What an SQ run promises (Sec. 2.5 (b), (c); Sec. 5.2), measured on its result.
//!
//! - **Congruence** (on G, from the lines of the final radius function, c_u × c_v, and the torsal
//!   directions recomputed exactly from them, [`super::metrics`]): every line within θ of the
//!   normal, every grid quad with real torsal directions, their planes at ≥ α.
//! - **SQ mesh** (from the final vertices and face spheres, [`super::sq_mesh`]): quads only,
//!   every vertex on its faces' spheres and the centres around every inner vertex coplanar
//!   (≤ [`EXACT`] of the diagonal: an exact SQ mesh with a torsion-free support structure), node
//!   axes within θ of the normals, support planes at a node meeting at ≥ α; at a singular vertex
//!   of valence m at ≥ min(α, bound(m) − 1°), since m planes through one axis cannot all meet
//!   wider than bound(m) ([`super::sphere_terms::support_plane_bound_deg`]: 60° at three edges,
//!   72° at five).
//! - **Panels** (the delivered panels and support elements, [`Buildability`]): no panel whose
//!   arcs cross or without its exact surface, no support element that folds, every panel within
//!   the stated distance of the reference; and at least [`MIN_COVERAGE`] of the patch's area
//!   paneled ([`crate::remeshing::quad_remeshing::coverage`]).

use crate::geometry::mesh::PolyMesh;
use crate::guarantees::{Guarantee, Verdict};
use crate::panels::buildability::Buildability;

use super::metrics::CongruenceFigures;
use super::sphere_terms::support_plane_aim_deg;
use super::sq_mesh::SqMeshFigures;

/// Exactness: vertex–sphere residual and centre-face planarity, relative to the diagonal.
pub const EXACT: f64 = 1e-8;
/// The least share of the patch's area the panels cover.
pub const MIN_COVERAGE: f64 = 0.95;

/// The coverage guarantee: at least [`MIN_COVERAGE`] of the patch paneled.
fn coverage_guarantee(coverage: f64) -> Guarantee {
    Guarantee::at_least("coverage", coverage, MIN_COVERAGE, "of the patch area")
}

/// The congruence's guarantees at θ and α (degrees).
pub(crate) fn congruence_guarantees(f: &CongruenceFigures, theta_deg: f64, alpha_deg: f64) -> Vec<Guarantee> {
    vec![
        Guarantee::at_most("max_line_normal_angle_deg", f.max_line_normal_angle_deg, theta_deg, "deg"),
        Guarantee::count_at_most("quads_without_real_torsal_directions", f.quads_without_real_torsal_directions, 0),
        Guarantee::at_least("min_torsal_plane_angle_deg", f.min_torsal_plane_angle_deg, alpha_deg, "deg"),
    ]
}

/// The SQ mesh's guarantees at θ and α (degrees).
pub(crate) fn mesh_guarantees(mesh: &PolyMesh, f: &SqMeshFigures, theta_deg: f64, alpha_deg: f64) -> Vec<Guarantee> {
    let not_quads = mesh.faces.iter().filter(|face| face.len() != 4).count();
    let mut support_planes = Guarantee::at_least("min_support_plane_angle_deg", f.min_torsal_plane_angle_deg, alpha_deg, "deg");
    if let Some(v) = f.unmeasured_support_planes {
        support_planes = support_planes.unmeasured(format!(
            "at vertex {v} two consecutive faces' spheres meet in no circle through their common edge, so its support planes have no angle"
        ));
    }
    let mut all = vec![
        Guarantee::at_least("faces", mesh.faces.len() as f64, 1.0, ""),
        Guarantee::count_at_most("faces_not_quads", not_quads, 0),
        Guarantee::at_most("max_vertex_sphere_residual", f.max_vertex_sphere_residual, EXACT, "of the diagonal"),
        Guarantee::at_most("max_centre_face_planarity", f.max_centre_face_planarity, EXACT, "of the diagonal"),
        Guarantee::at_most("max_axis_normal_angle_deg", f.max_axis_normal_angle_deg, theta_deg, "deg"),
        support_planes,
    ];
    for (valence, name, figure) in [
        (3, "min_support_plane_angle_valence_3_deg", f.min_support_plane_angle_valence_3_deg),
        (5, "min_support_plane_angle_valence_5_deg", f.min_support_plane_angle_valence_5_deg),
    ] {
        if let Some(worst) = figure {
            all.push(Guarantee::at_least(name, worst, support_plane_aim_deg(valence, alpha_deg), "deg"));
        }
    }
    all
}

/// What a run delivers, as far as it went.
pub enum Delivered<'a> {
    Congruence,
    /// The quad mesh Q′ and the share of the patch it covers.
    QuadMesh(&'a PolyMesh, f64),
    /// The SQ mesh: its figures of exactness, its panels (within `max_distance` of the
    /// reference, relative to the diagonal) and the share of the patch they cover.
    SqMesh {
        mesh: &'a PolyMesh,
        figures: &'a SqMeshFigures,
        panels: &'a Buildability,
        max_distance: f64,
        coverage: f64,
    },
}

/// The verdict of a run on what it delivers: the congruence's guarantees when it stopped there
/// (with quads only when it stopped after the quad mesh), the SQ mesh's otherwise.
pub fn verdict(congruence: &CongruenceFigures, delivered: Delivered, theta_deg: f64, alpha_deg: f64) -> Verdict {
    Verdict::new(match delivered {
        Delivered::Congruence => congruence_guarantees(congruence, theta_deg, alpha_deg),
        Delivered::QuadMesh(m, coverage) => {
            let mut all = congruence_guarantees(congruence, theta_deg, alpha_deg);
            all.push(Guarantee::count_at_most("faces_not_quads", m.faces.iter().filter(|f| f.len() != 4).count(), 0));
            all.push(coverage_guarantee(coverage));
            all
        }
        Delivered::SqMesh { mesh, figures, panels, max_distance, coverage } => {
            let mut all = mesh_guarantees(mesh, figures, theta_deg, alpha_deg);
            all.extend(panels.guarantees(max_distance));
            all.push(coverage_guarantee(coverage));
            all
        }
    })
}
