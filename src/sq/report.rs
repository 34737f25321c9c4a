//! The section `"sq"` of `report.json` (Sec. 5): the run's parameters, the congruence on G
//! (5.1), the quad mesh along its torsal field and the SQ mesh (5.2), each where the run got to.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::metrics::CongruenceFigures;
use super::moulds::SqMouldRound;
use super::params::{RadiusBasis, RadiusStart, SqParams};
use super::sq_mesh::SqMeshFigures;
use super::{CongruenceAttempt, SqCongruence, SqResult};
use crate::panels::moulds::{MouldOutcome, MouldRoundsSection};
use crate::stats::mean;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SqSection {
    /// Points per direction of G, θ and α (degrees), the basis of r, and the stage the run
    /// stopped after.
    pub grid: usize,
    #[serde(deserialize_with = "crate::guarantees::f64_or_nan")]
    pub theta_deg: f64,
    #[serde(deserialize_with = "crate::guarantees::f64_or_nan")]
    pub alpha_deg: f64,
    pub radius_basis: RadiusBasis,
    pub stopped_after: String,
    /// Solver iterations in all: the congruence's, Q′'s and the final optimization's.
    pub iterations: usize,
    pub congruence: CongruenceSection,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub quad_mesh: Option<QuadMeshSection>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sq_mesh: Option<SqMeshSection>,
}

/// The congruence on G (Sec. 5.1): its figures at the start (the central congruence of the
/// fitted r, or constant radii) and optimized.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CongruenceSection {
    /// The start the congruence was kept from (Sec. 5.1, 6.3): "central" or "constant".
    #[serde(default)]
    pub start: RadiusStart,
    /// Every start tried, in order: its figures at the start and optimized, and its misses of θ
    /// and α on G (the kept one is the first without, else the first with the fewest).
    #[serde(default)]
    pub attempts: Vec<CongruenceAttempt>,
    pub initial: CongruenceFigures,
    pub figures: CongruenceFigures,
    /// E_LC per term (dimensionless, c_u and c_v normalized) after both steps, and after step 1.
    #[serde(deserialize_with = "crate::guarantees::f64_or_nan")]
    pub lc_residual: f64,
    #[serde(deserialize_with = "crate::guarantees::f64_or_nan")]
    pub lc_residual_step1: f64,
    /// Largest |r − 1/H| of the radius fit on G, relative to the mean |1/H|.
    #[serde(deserialize_with = "crate::guarantees::f64_or_nan")]
    pub radius_fit_error: f64,
    /// Solver iterations of the line-congruence and the torsal step.
    pub line_congruence_iterations: usize,
    pub torsal_iterations: usize,
}

/// The quad mesh along the torsal field (Sec. 5.2): Q′, or the SQ mesh when the run got there.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct QuadMeshSection {
    /// The covered share of the patch's area.
    #[serde(deserialize_with = "crate::guarantees::f64_or_nan")]
    pub coverage: f64,
    /// Angle between the mesh edges and the torsal directions at the edge midpoints (degrees;
    /// edges not along the patch boundary).
    #[serde(deserialize_with = "crate::guarantees::f64_or_nan")]
    pub mean_edge_torsal_angle_deg: f64,
    #[serde(deserialize_with = "crate::guarantees::f64_or_nan")]
    pub max_edge_torsal_angle_deg: f64,
    /// What the mesh follows: the torsal field, or the parameter lines where the field has
    /// singular points.
    #[serde(default)]
    pub follows: QuadMeshLines,
    /// The torsal field's singular points (quarter turns, as the remesh placed them) and the mesh's
    /// singular vertices, each by the valence they ask for (3 or 5) and count.
    #[serde(default)]
    pub singular_points_by_valence: BTreeMap<u32, usize>,
    #[serde(default)]
    pub singular_vertices_by_valence: BTreeMap<u32, usize>,
}

/// The lines a quad mesh follows (Sec. 5.2).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum QuadMeshLines {
    #[default]
    TorsalField,
    ParameterLines,
}

/// Counts per valence 4 − quarters.
fn by_valence(quarters: impl Iterator<Item = i32>) -> BTreeMap<u32, usize> {
    let mut out = BTreeMap::new();
    for q in quarters {
        *out.entry((4 - q) as u32).or_default() += 1;
    }
    out
}

/// The SQ mesh out of the final optimization (Sec. 5.2, Eq. 10).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SqMeshSection {
    #[serde(flatten)]
    pub figures: SqMeshFigures,
    /// Iterations of the final optimization: warm-up, full, projection.
    pub final_iterations: [usize; 3],
    /// The rounds toward fewer moulds (`optimize_moulds`); their distance is the vertices'.
    #[serde(flatten)]
    pub moulds: MouldRoundsSection<SqMouldRound>,
}

impl CongruenceSection {
    pub fn of(c: &SqCongruence) -> Self {
        Self {
            start: c.start,
            attempts: c.attempts.clone(),
            initial: c.initial_figures.clone(),
            figures: c.figures.clone(),
            lc_residual: c.lc_residual,
            lc_residual_step1: c.lc_residual_step1,
            radius_fit_error: c.radius_fit_error,
            line_congruence_iterations: c.lc_iterations,
            torsal_iterations: c.torsal_iterations,
        }
    }
}

impl SqSection {
    pub fn of(result: &SqResult, params: &SqParams) -> Self {
        let c = &result.congruence;
        let quad_mesh = result.quad_mesh.as_ref().map(|q| {
            let angles = result.sq_mesh.as_ref().map_or(&q.edge_angles_deg, |f| &f.edge_angles_deg);
            QuadMeshSection {
                coverage: q.coverage,
                mean_edge_torsal_angle_deg: mean(angles),
                max_edge_torsal_angle_deg: angles.iter().copied().fold(0.0, f64::max),
                follows: if q.parameter_lines() { QuadMeshLines::ParameterLines } else { QuadMeshLines::TorsalField },
                singular_points_by_valence: by_valence(q.singular_points.iter().map(|s| s.quarters)),
                singular_vertices_by_valence: by_valence(q.singular.iter().map(|&(_, q)| q)),
            }
        });
        let sq_mesh = result.sq_mesh.as_ref().map(|f| SqMeshSection {
            figures: f.mesh.figures,
            final_iterations: [f.outcome.warm_up_iterations, f.outcome.iterations, f.outcome.projection_iterations],
            moulds: MouldOutcome::section(f.moulds.as_ref()),
        });
        let fairing = result.quad_mesh.as_ref().map_or(0, |q| q.fairing_iterations);
        let spheres = sq_mesh.as_ref().map_or(0, |s| s.final_iterations.iter().sum());
        Self {
            grid: c.grid,
            theta_deg: params.theta_deg,
            alpha_deg: params.alpha_deg,
            radius_basis: c.radius_basis,
            stopped_after: params.until.key().into(),
            iterations: c.lc_iterations + c.torsal_iterations + fairing + spheres,
            congruence: CongruenceSection::of(c),
            quad_mesh,
            sq_mesh,
        }
    }
}
