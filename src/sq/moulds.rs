//! Fewer moulds (Sec. 5.2 with the fabrication's moulds, [`crate::panels::moulds`]): the exact
//! SQ mesh is moved so that its panels have the radii of fewer moulds, exactly. A face sphere
//! passes through its four vertices, so a new radius moves them: each round
//! ([`snapped_rounds`]) holds every face's curvature at its mould's and projects to exactness
//! again ([`super::sphere_optimization::project_to_curvatures`]), landing on a nearby exact SQ
//! mesh. A round counts when that mesh meets the method's guarantees (exact, θ, α) and its
//! vertices stay within [`DISTANCE_GROWTH`] × the method's distance to the reference.

use serde::{Deserialize, Serialize};

use crate::panels::moulds::{snapped_rounds, Fabrication, MouldOutcome, MouldRoundFigures, RoundCount};
use crate::progress::{Cancelled, Progress};

use super::error::SqError;
use super::sq_mesh::SqMesh;

/// The vertices' largest distance to the reference may grow by this factor.
pub const DISTANCE_GROWTH: f64 = 1.2;

/// One round of [`fewer_moulds`]: the figures of the mesh it made.
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

/// The rounds from the method's result `done` (meeting its guarantees; `mesh` gives its SQ
/// mesh) on a reference of diagonal `diag`: the last kept round's result (None: none was kept)
/// and what they did. `project` moves a result so that every face has the given signed
/// curvature (model units, per face; NaN: free) and answers whether the moved one meets the
/// guarantees.
/// The projection of a result to exactness with every face at the curvature given, and whether
/// it is exact.
pub type SqProjection<'a, R> = dyn FnMut(&R, &[f64]) -> Result<(R, bool), SqError> + 'a;

pub fn fewer_moulds<R>(
    done: &R,
    mesh: &dyn Fn(&R) -> &SqMesh,
    diag: f64,
    fabrication: &Fabrication,
    project: &mut SqProjection<R>,
    progress: &mut dyn FnMut(Progress) -> Result<(), Cancelled>,
) -> Result<(Option<R>, SqMouldOutcome), SqError> {
    let distance_limit = DISTANCE_GROWTH * mesh(done).figures.max_vertex_distance_to_reference;
    let faces = mesh(done).sphere_mesh.mesh.face_count();
    let mut on_faces = |from: &R, per_panel: &[f64]| {
        let mut curvatures = vec![f64::NAN; faces];
        for (p, &k) in mesh(from).panels.iter().zip(per_panel) {
            curvatures[p.face] = k;
        }
        match project(from, &curvatures) {
            Err(SqError::Cancelled) => Err(SqError::Cancelled),
            Err(_) => Ok(None),
            Ok((moved, meets)) => {
                let holds = meets && mesh(&moved).figures.max_vertex_distance_to_reference <= distance_limit;
                Ok(Some((moved, holds)))
            }
        }
    };
    let mut rounds = Vec::new();
    let mut on_round = |moved: &R, count: RoundCount| {
        let f = &mesh(moved).figures;
        rounds.push(SqMouldRound {
            coarsening: count.coarsening,
            moulds: count.moulds,
            max_vertex_sphere_residual: f.max_vertex_sphere_residual,
            max_centre_face_planarity: f.max_centre_face_planarity,
            max_axis_normal_angle_deg: f.max_axis_normal_angle_deg,
            min_support_plane_angle_deg: f.min_torsal_plane_angle_deg,
            max_vertex_distance_to_reference: f.max_vertex_distance_to_reference,
            kept: count.kept,
        });
    };
    let out = snapped_rounds(done, &|r: &R| &mesh(r).panels[..], diag, fabrication, &mut on_faces, &mut on_round, progress)?;
    Ok((out.best, MouldOutcome { snap: out.snap, rounds, before: out.before, fits_before: out.fits_before, distance_limit }))
}
