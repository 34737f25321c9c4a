//! The quality of an ST mesh against its reference: residuals, kink angles, distances, the
//! gaps of variant (b) and folded faces.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::panels::build_panels_with;
use crate::panels::deviation::max_distance_to_reference;
use crate::panels::edge_arcs::EdgeArcs;
use crate::panels::gaps::{max_arc_gap, GAP_SAMPLES};
use crate::panels::panel::Panel;
use crate::panels::sphere_mesh::SphereMesh;
use crate::panels::DEFAULT_CHORD_TOLERANCE;
use crate::reference::Reference;
use crate::stats::mean;

/// Quality of an ST mesh (lengths relative to the reference diagonal).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StAdaptedMetrics {
    /// max over faces and corners of | |v − c| − r |, relative.
    pub max_vertex_sphere_residual: f64,
    /// Kink angles over interior edges (degrees).
    pub mean_kink_angle_deg: f64,
    pub max_kink_angle_deg: f64,
    /// Sampled over the panels ([`max_distance_to_reference`]), relative.
    pub max_distance_to_reference: f64,
    /// Max vertex distance to the reference, relative.
    pub max_vertex_distance_to_reference: f64,
    /// Variant (b): the largest gap between the two arcs of an edge ([`max_arc_gap`]), relative.
    pub max_gap: Option<f64>,
    pub faces: usize,
    pub interior_edges: usize,
    /// Faces whose normal points against the reference normal at the closest point of their
    /// centroid (should be 0).
    pub flipped_faces: usize,
    /// Variant (b): the gap of `max_gap` divided by its edge's length.
    pub max_gap_over_edge_length: Option<f64>,
}

/// Metrics of a sphere mesh against the reference (see [`StAdaptedMetrics`]), with its panels
/// for `variant` (tessellated to [`DEFAULT_CHORD_TOLERANCE`] of the diagonal).
pub fn metrics(sm: &SphereMesh, reference: &Reference, variant: EdgeArcs) -> (StAdaptedMetrics, Vec<Panel>) {
    let diag = reference.diagonal().max(f64::MIN_POSITIVE);
    let mesh = &sm.mesh;
    let res = sm.max_vertex_sphere_residual();
    let kinks = sm.kink_angles_deg();
    let mean = mean(&kinks);
    let max = kinks.iter().copied().fold(0.0, f64::max);
    let panels = build_panels_with(sm, DEFAULT_CHORD_TOLERANCE * diag, variant);
    let dist = max_distance_to_reference(&panels, reference.bvh(), reference.diagonal());
    let vdist = mesh.positions.iter().map(|&p| reference.bvh().distance(p)).fold(0.0, f64::max) / diag;
    let gap = (variant == EdgeArcs::BisectingPlanes).then(|| max_arc_gap(&panels, sm.topology(), GAP_SAMPLES));
    let flipped_faces = (0..mesh.face_count())
        .filter(|&f| {
            let points = mesh.face_points(f);
            let c = points.iter().sum::<DVec3>() / points.len() as f64;
            let Some(normal) = reference.closest_point(c).and_then(|p| p.normal) else { return false };
            mesh.face_area_vector(f).dot(normal) < 0.0
        })
        .count();
    let metrics = StAdaptedMetrics {
        max_vertex_sphere_residual: res / diag,
        mean_kink_angle_deg: mean,
        max_kink_angle_deg: max,
        max_distance_to_reference: dist,
        max_vertex_distance_to_reference: vdist,
        max_gap: gap.map(|g| g.0 / diag),
        max_gap_over_edge_length: gap.map(|g| g.1),
        faces: mesh.face_count(),
        interior_edges: kinks.len(),
        flipped_faces,
    };
    (metrics, panels)
}
