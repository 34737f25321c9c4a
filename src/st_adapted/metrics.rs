//! The quality of an ST mesh against its reference: residuals, kink angles, distances, the
//! gaps of variant (b) and folded faces; the initial mesh's shape without its panels.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::panels::build_panels_with;
use crate::panels::deviation::max_deviation;
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
    #[serde(deserialize_with = "crate::guarantees::f64_or_nan")]
    pub max_vertex_sphere_residual: f64,
    /// Kink angles over interior edges (degrees).
    #[serde(deserialize_with = "crate::guarantees::f64_or_nan")]
    pub mean_kink_angle_deg: f64,
    #[serde(deserialize_with = "crate::guarantees::f64_or_nan")]
    pub max_kink_angle_deg: f64,
    /// Sampled over the panels ([`max_distance_to_reference`]), relative.
    #[serde(deserialize_with = "crate::guarantees::f64_or_nan")]
    pub max_distance_to_reference: f64,
    /// Max vertex distance to the reference, relative.
    #[serde(deserialize_with = "crate::guarantees::f64_or_nan")]
    pub max_vertex_distance_to_reference: f64,
    /// Variant (b), and variant (a) with bisected edges: the largest gap between the two arcs of
    /// an edge ([`max_arc_gap`]), relative.
    pub max_gap: Option<f64>,
    pub faces: usize,
    pub interior_edges: usize,
    /// Faces whose normal points against the reference normal at the closest point of their
    /// centroid (should be 0).
    pub flipped_faces: usize,
    /// Variant (b): the gap of `max_gap` divided by its edge's length.
    pub max_gap_over_edge_length: Option<f64>,
    /// Variant (a): the interior edges cut by bisecting planes, where the intersection circle
    /// would make a panel's arcs cross ([`SphereMesh::bisected_edges`]); they have the gaps.
    #[serde(default)]
    pub bisected_edges: usize,
}

/// The shape of a sphere mesh before it has panels (lengths relative to the reference
/// diagonal): what the initial mesh of the optimization is compared by.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StAdaptedShape {
    /// max over faces and corners of | |v − c| − r |, relative.
    #[serde(deserialize_with = "crate::guarantees::f64_or_nan")]
    pub max_vertex_sphere_residual: f64,
    /// Kink angles over interior edges (degrees).
    #[serde(deserialize_with = "crate::guarantees::f64_or_nan")]
    pub mean_kink_angle_deg: f64,
    #[serde(deserialize_with = "crate::guarantees::f64_or_nan")]
    pub max_kink_angle_deg: f64,
    /// Max vertex distance to the reference, relative.
    #[serde(deserialize_with = "crate::guarantees::f64_or_nan")]
    pub max_vertex_distance_to_reference: f64,
    pub faces: usize,
    pub interior_edges: usize,
    /// Faces whose normal points against the reference normal at the closest point of their
    /// centroid (should be 0).
    pub flipped_faces: usize,
}

/// The shape of a sphere mesh against the reference (see [`StAdaptedShape`]).
pub fn shape(sm: &SphereMesh, reference: &Reference) -> StAdaptedShape {
    let diag = reference.diagonal().max(f64::MIN_POSITIVE);
    let mesh = &sm.mesh;
    let kinks = sm.kink_angles_deg();
    let flipped_faces = (0..mesh.face_count())
        .filter(|&f| {
            let points = mesh.face_points(f);
            let c = points.iter().sum::<DVec3>() / points.len() as f64;
            let Some(normal) = reference.closest_point(c).and_then(|p| p.normal) else { return false };
            mesh.face_area_vector(f).dot(normal) < 0.0
        })
        .count();
    StAdaptedShape {
        max_vertex_sphere_residual: sm.max_vertex_sphere_residual() / diag,
        mean_kink_angle_deg: mean(&kinks),
        max_kink_angle_deg: kinks.iter().copied().fold(0.0, f64::max),
        max_vertex_distance_to_reference: mesh
            .positions
            .iter()
            .map(|&p| reference.closest_point(p).map_or(f64::INFINITY, |h| h.point.distance(p)))
            .fold(0.0, f64::max)
            / diag,
        faces: mesh.face_count(),
        interior_edges: kinks.len(),
        flipped_faces,
    }
}

/// Metrics of a sphere mesh against the reference (see [`StAdaptedMetrics`]), with its panels
/// for `variant` (tessellated to [`DEFAULT_CHORD_TOLERANCE`] of the diagonal) and each panel's
/// [`max_deviation`] (absolute), for the schedule.
pub fn metrics(sm: &SphereMesh, reference: &Reference, variant: EdgeArcs) -> (StAdaptedMetrics, Vec<Panel>, Vec<f64>) {
    let diag = reference.diagonal().max(f64::MIN_POSITIVE);
    let s = shape(sm, reference);
    let panels = build_panels_with(sm, DEFAULT_CHORD_TOLERANCE * diag, variant);
    let deviations: Vec<f64> = panels.iter().map(|p| max_deviation(p, reference)).collect();
    let dist = deviations.iter().copied().fold(0.0, f64::max) / diag;
    let gaps = variant == EdgeArcs::BisectingPlanes || !sm.bisected_edges.is_empty();
    let gap = gaps.then(|| max_arc_gap(&panels, sm.topology(), GAP_SAMPLES));
    let metrics = StAdaptedMetrics {
        max_vertex_sphere_residual: s.max_vertex_sphere_residual,
        mean_kink_angle_deg: s.mean_kink_angle_deg,
        max_kink_angle_deg: s.max_kink_angle_deg,
        max_distance_to_reference: dist,
        max_vertex_distance_to_reference: s.max_vertex_distance_to_reference,
        max_gap: gap.map(|g| g.0 / diag),
        max_gap_over_edge_length: gap.map(|g| g.1),
        faces: s.faces,
        interior_edges: s.interior_edges,
        flipped_faces: s.flipped_faces,
        bisected_edges: sm.bisected_edges.len(),
    };
    (metrics, panels, deviations)
}
