//! Fewer moulds (Sec. 5.2 with the fabrication's moulds, [`crate::panels::moulds`]): the exact
//! SQ mesh is moved so that its panels have the radii of fewer moulds, exactly. A face sphere
//! passes through its four vertices, so a new radius moves them: each round
//! ([`crate::panels::moulds::fewer_moulds`], SQ's hook in the driver) holds every face's curvature at its mould's and projects to exactness
//! again ([`super::sphere_optimization::project_to_curvatures`]), landing on a nearby exact SQ
//! mesh. A round counts when that mesh meets the method's guarantees (exact, θ, α) and its
//! vertices stay within [`DISTANCE_GROWTH`] × the method's distance to the reference.

use serde::{Deserialize, Serialize};

use crate::panels::moulds::{MouldOutcome, MouldRoundFigures};

/// The vertices' largest distance to the reference may grow by this factor.
pub const DISTANCE_GROWTH: f64 = 1.2;

/// One round toward fewer moulds: the figures of the mesh it made.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SqMouldRound {
    pub coarsening: f64,
    /// Moulds at δ of the moved panels.
    pub moulds: usize,
    pub max_vertex_sphere_residual: f64,
    pub max_centre_face_planarity: f64,
    pub max_axis_normal_angle_deg: f64,
    pub min_support_plane_angle_deg: f64,
    /// Relative to the diagonal.
    pub max_vertex_distance_to_reference: f64,
    pub kept: bool,
}

/// What the rounds did.
pub type SqMouldOutcome = MouldOutcome<SqMouldRound>;

impl MouldRoundFigures for SqMouldRound {
    fn moulds(&self) -> usize {
        self.moulds
    }
    fn distance_to_reference(&self) -> f64 {
        self.max_vertex_distance_to_reference
    }
    fn kept(&self) -> bool {
        self.kept
    }
}
