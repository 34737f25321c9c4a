//! The section `"st"` of `report.json` (Sec. 3): what the method measured beyond the shared panel
//! metrics (the kinks, the distance to the reference and the radii, which every method has).

use serde::{Deserialize, Serialize};

use super::moulds::MouldRound;
use super::StAdaptedResult;
use crate::guarantees::f64_or_nan;
use crate::panels::edge_arcs::EdgeArcs;
use crate::panels::moulds::{MouldOutcome, MouldRoundsSection};

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StAdaptedSection {
    /// Edge variant (Fig. 12), written "a" or "b".
    #[serde(with = "crate::panels::edge_arcs::as_key")]
    pub variant: EdgeArcs,
    /// Solver iterations of the angle optimization.
    pub angle_iterations: usize,
    /// max over faces and their corners of | |v − c| − r |, relative to the diagonal.
    #[serde(deserialize_with = "f64_or_nan")]
    pub max_vertex_sphere_residual: f64,
    /// Largest vertex distance to the reference, relative.
    #[serde(deserialize_with = "f64_or_nan")]
    pub max_vertex_distance_to_reference: f64,
    /// Faces whose normal points against the reference normal at their centroid, after and before
    /// optimizing.
    pub flipped_faces: usize,
    pub initial_flipped_faces: usize,
    /// Kink angles before optimizing (degrees).
    #[serde(deserialize_with = "f64_or_nan")]
    pub initial_mean_kink_angle_deg: f64,
    #[serde(deserialize_with = "f64_or_nan")]
    pub initial_max_kink_angle_deg: f64,
    /// Variant (b), and variant (a) at its bisected edges: the largest gap between the two arcs
    /// of an edge, measured on the panels' own arcs ([`crate::panels::gaps`]), relative.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_gap: Option<f64>,
    /// Variant (a): the interior edges cut by bisecting planes instead of the intersection
    /// circle, which would make a panel's arcs cross ([`crate::panels::bisect_where_arcs_cross`]).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub bisected_edges: usize,
    /// With `--optimize-moulds`: each round toward fewer moulds (coarsening, moulds at δ, largest
    /// kink, distance, kept), the moulds before them and the distance they were held to.
    #[serde(flatten)]
    pub moulds: MouldRoundsSection<MouldRound>,
}

impl StAdaptedSection {
    pub fn of(result: &StAdaptedResult) -> Self {
        let (m, i) = (&result.metrics, &result.initial_shape);
        Self {
            variant: result.variant,
            angle_iterations: result.iterations,
            max_vertex_sphere_residual: m.max_vertex_sphere_residual,
            max_vertex_distance_to_reference: m.max_vertex_distance_to_reference,
            flipped_faces: m.flipped_faces,
            initial_flipped_faces: i.flipped_faces,
            initial_mean_kink_angle_deg: i.mean_kink_angle_deg,
            initial_max_kink_angle_deg: i.max_kink_angle_deg,
            max_gap: m.max_gap,
            bisected_edges: m.bisected_edges,
            moulds: MouldOutcome::section(result.moulds.as_ref()),
        }
    }
}

fn is_zero(n: &usize) -> bool {
    *n == 0
}
