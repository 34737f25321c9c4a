//! Fewer moulds (Sec. 3 with the fabrication's moulds, [`crate::panels::moulds`]): the panels
//! of the angle-minimizing ST mesh are moved so that they land on fewer radii. Each round assigns
//! the panels to the moulds of a coarser tolerance (γ δ, fewer moulds), adds [`MouldCurvature`]
//! pulling every face sphere's curvature to its mould's, and optimizes again from the last
//! result with all the method's terms. A round is kept when the moulds at δ fell and the method's
//! targets hold (largest kink ≤ [`KINK_GROWTH`] × before, panels within 2ε); the rounds stop
//! when the count stops falling. Then [`snap_to_moulds`] gives every face sphere its mould's
//! radius exactly: a face sphere is free in the pencil through its three vertices, which holds
//! one sphere of each radius above their circumradius, so the vertices stay.

use super::boundary_arcs::delivered_arcs;
use super::events::{OnEvent, StAdaptedEvent};
use super::metrics::{metrics, StAdaptedMetrics};
use super::optimization::{run_stages, OptimizationFrame};
use super::params::{OptimizationStage, StAdaptedParams};
use super::terms::{vertex_offset, FaceSpheres};
use crate::geometry::mesh::TriMesh;
use crate::geometry::sphere::Sphere;
use crate::panels::edge_arcs::EdgeArcs;
use crate::panels::exact_surface::arcs_cross;
use crate::panels::moulds::{
    fewer_moulds, per_face, Fabrication, MouldAssignment, MouldFits, MouldHook, MouldOutcome, MouldRoundFigures, MouldSnap, RoundCount,
    RoundSchedule, SnapLimit,
};
use crate::panels::panel::Panel;
use crate::panels::sphere_mesh::SphereMesh;
use crate::progress::{Cancelled, Clock, Progress, Timings};
use crate::reference::Reference;
use crate::solver::{JacobianSink, Solver, SolverOptions, Term};

/// The largest kink may grow by this factor.
pub const KINK_GROWTH: f64 = 1.2;
/// Coarser tolerances tried, as multiples of δ, in order.
const COARSENING: [f64; 6] = [1.5, 2.0, 3.0, 4.0, 6.0, 8.0];
/// Solver iterations per round (of the method's last stage).
const ROUND_ITERATIONS: usize = 10;
/// Weight of [`MouldCurvature`] against the kink term's (frame units).
const MOULD_WEIGHT: f64 = 1e-2;

/// E_mould: 2a_f − κ_f for every face with a target, the curvature of face f's sphere
/// (normalized: κ = 2a along its normal) minus its mould's, in the optimization's frame.
pub struct MouldCurvature {
    spheres: FaceSpheres,
    /// Signed target curvature per face (NaN: none).
    targets: Vec<f64>,
}

impl MouldCurvature {
    pub fn new(spheres: FaceSpheres, targets: Vec<f64>) -> Self {
        Self { spheres, targets }
    }
}

impl Term for MouldCurvature {
    fn name(&self) -> &str {
        "mould"
    }
    fn residual_count(&self) -> usize {
        self.targets.len()
    }
    fn eval(&self, x: &[f64], r: &mut [f64], jac: &mut JacobianSink) {
        self.spheres.with(x, |m| {
            for (f, (&target, member)) in self.targets.iter().zip(m).enumerate() {
                if target.is_nan() {
                    r[f] = 0.0;
                    continue;
                }
                r[f] = 2.0 * member.sphere[0] - target;
                self.spheres.add_chain(jac, f, f, member, &[2.0, 0.0, 0.0, 0.0, 0.0]);
            }
        });
    }
}

/// The method's targets a mould round or the snap must keep: the largest kink within
/// [`KINK_GROWTH`] × the method's, the panels within 2ε (or as far as they were), no fold.
#[derive(Clone, Copy, Debug)]
pub struct MouldTargets {
    pub max_kink_angle_deg: f64,
    pub max_distance_to_reference: f64,
}

impl MouldTargets {
    /// The targets around the method's own result `start`.
    pub fn of(start: &StAdaptedMetrics, params: &StAdaptedParams) -> Self {
        Self {
            max_kink_angle_deg: KINK_GROWTH * start.max_kink_angle_deg,
            max_distance_to_reference: params.epsilon().map_or(f64::INFINITY, |e| (2.0 * e).max(start.max_distance_to_reference)),
        }
    }

    /// Whether a result with metrics `m` and `panels` holds the targets, folds no face and has no
    /// panel whose arcs cross ([`arcs_cross`]).
    pub fn hold(&self, m: &StAdaptedMetrics, panels: &[Panel]) -> bool {
        m.max_kink_angle_deg <= self.max_kink_angle_deg
            && m.max_distance_to_reference <= self.max_distance_to_reference
            && m.flipped_faces == 0
            && !panels.iter().any(|p| arcs_cross(&p.sphere, &p.arcs))
    }
}

/// The method's result as the rounds move it: the sphere mesh, its panels, their distances and
/// the metrics.
#[derive(Clone, Debug)]
pub struct Moved {
    pub sphere_mesh: SphereMesh,
    pub panels: Vec<Panel>,
    pub deviations: Vec<f64>,
    pub metrics: StAdaptedMetrics,
}

/// One round toward fewer moulds: its coarsening γ, the moulds at δ of the moved panels, the
/// largest kink and distance, and whether it was kept.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MouldRound {
    pub coarsening: f64,
    pub moulds: usize,
    pub max_kink_angle_deg: f64,
    pub max_distance_to_reference: f64,
    pub kept: bool,
}

impl MouldRoundFigures for MouldRound {
    fn moulds(&self) -> usize {
        self.moulds
    }
    fn distance_to_reference(&self) -> f64 {
        self.max_distance_to_reference
    }
    fn kept(&self) -> bool {
        self.kept
    }
}

/// What the rounds did.
pub type StAdaptedMouldOutcome = MouldOutcome<MouldRound>;

/// The method's part in the rounds ([`crate::panels::moulds::fewer_moulds`]): each round
/// continues the method's last stage for a few iterations with [`MouldCurvature`] pulling every
/// face sphere's curvature to its mould's; after the rounds [`snap_to_moulds`].
struct Hook<'a, 'e> {
    reference: &'a Reference,
    params: &'a StAdaptedParams,
    /// The params with the method's last stage only, for [`ROUND_ITERATIONS`].
    stages: StAdaptedParams,
    targets: MouldTargets,
    clock: Clock,
    on_event: &'a mut OnEvent<'e>,
    round: usize,
    /// The method's step timings: the rounds' lap, then the snap's.
    timings: &'a mut Timings,
}

impl MouldHook for Hook<'_, '_> {
    type Result = Moved;
    type Round = MouldRound;
    type Error = Cancelled;

    fn schedule(&self) -> RoundSchedule {
        RoundSchedule { coarsening: &COARSENING, exact: false }
    }

    fn panels<'r>(&self, result: &'r Moved) -> &'r [Panel] {
        &result.panels
    }

    fn pull(&mut self, from: &Moved, curvatures: &[f64]) -> Result<Option<(Moved, bool)>, Cancelled> {
        let (reference, params) = (self.reference, self.params);
        let diag = reference.diagonal();
        let current = &from.sphere_mesh;
        // The frame scales lengths by 1/diag, curvatures by diag.
        let targets = per_face(&from.panels, curvatures, current.mesh.face_count(), diag);
        let mesh = current.mesh.triangulated();
        let frame = OptimizationFrame::new(reference, &mesh, &current.face_spheres, params);
        let mut x = frame.x0.clone();
        let (mut problem, ids) = frame.problem(&params.variant_weights());
        let corners = mesh.triangles.iter().map(|t| t.map(|v| vertex_offset(mesh.face_count(), v as usize))).collect();
        problem.add_term(MouldCurvature::new(FaceSpheres::new(corners), targets), MOULD_WEIGHT * params.weights.angle);
        let mut solver = Solver::new(SolverOptions { clock: self.clock, ..SolverOptions::default() });
        run_stages(&mut problem, &ids, &mut x, &self.stages, &mut solver, &mut |_, _| Ok(()))?;
        let (verts, spheres) = frame.to_model(&x);
        let moved = SphereMesh::new(TriMesh::new(verts, mesh.triangles.clone()), spheres, current.boundary_arcs);
        let moved = delivered_arcs(moved, reference, params.variant);
        self.round += 1;
        (self.on_event)(StAdaptedEvent::MouldRound { round: self.round, sphere_mesh: &moved })?;
        let (metrics, panels, deviations) = metrics(&moved, reference, params.variant);
        let holds = self.targets.hold(&metrics, &panels);
        Ok(Some((Moved { sphere_mesh: moved, panels, deviations, metrics }, holds)))
    }

    fn round(&self, moved: &Moved, count: RoundCount) -> MouldRound {
        MouldRound {
            coarsening: count.coarsening,
            moulds: count.moulds,
            max_kink_angle_deg: moved.metrics.max_kink_angle_deg,
            max_distance_to_reference: moved.metrics.max_distance_to_reference,
            kept: count.kept,
        }
    }

    fn snap(&mut self, kept: &Moved, fabrication: &Fabrication) -> Option<(Option<Moved>, MouldSnap)> {
        self.timings.lap("fewer_moulds");
        // The snap takes milliseconds: a cancel arriving now stops the method after it.
        let _ = (self.on_event)(StAdaptedEvent::Progress(Progress::new("snap_moulds", 0, 0)));
        let (snapped, snap) = snap_to_moulds(self.reference, &kept.sphere_mesh, &kept.panels, &self.targets, fabrication, self.params.variant);
        let snapped = snapped.map(|s| Moved { sphere_mesh: s.sphere_mesh, panels: s.panels, deviations: s.deviations, metrics: s.metrics });
        self.timings.lap("snap_moulds");
        Some((snapped, snap))
    }

    fn distance_limit(&self) -> f64 {
        self.targets.max_distance_to_reference
    }

    fn progress(&mut self, p: Progress) -> Result<(), Cancelled> {
        (self.on_event)(StAdaptedEvent::Progress(p))
    }
}

/// The rounds toward fewer moulds on the method's result `start` on `reference`, each round's
/// mesh sent to `on_event`, then the snap: the result moved onto fewer moulds (`start` where no
/// round was kept and the snap missed the targets) and what the rounds did. `timings` gets the
/// laps `fewer_moulds` and `snap_moulds`.
pub fn fewer_moulds_of(
    reference: &Reference,
    start: Moved,
    params: &StAdaptedParams,
    fabrication: &Fabrication,
    clock: Clock,
    timings: &mut Timings,
    on_event: &mut OnEvent,
) -> Result<(Moved, StAdaptedMouldOutcome), Cancelled> {
    // Each round continues the last stage of the method for a few iterations.
    let last = params.stages.last().cloned().map(|s| OptimizationStage { iterations: s.iterations.min(ROUND_ITERATIONS), ..s });
    let stages = StAdaptedParams { stages: last.into_iter().collect(), ..params.clone() };
    let targets = MouldTargets::of(&start.metrics, params);
    let mut hook = Hook { reference, params, stages, targets, clock, on_event, round: 0, timings };
    let run = fewer_moulds(&mut hook, &start, reference.diagonal(), fabrication)?;
    Ok((run.best.unwrap_or(start), run.outcome))
}

/// The sphere mesh with every face sphere snapped to its mould's radius, its panels, their
/// distances and the metrics.
pub struct Snapped {
    pub sphere_mesh: SphereMesh,
    pub panels: Vec<Panel>,
    pub deviations: Vec<f64>,
    pub metrics: StAdaptedMetrics,
}

/// Each face sphere becomes the member of the pencil through its three vertices with its
/// mould's curvature, the one nearest it ([`Sphere::through_points_with_curvature`]): the panel
/// is then cut from its mould with no deviation. A face whose mould is smaller than its corners'
/// circumradius keeps its sphere. None (and every panel limited by the targets) when the snapped
/// mesh misses `targets`.
pub fn snap_to_moulds(
    reference: &Reference,
    sphere_mesh: &SphereMesh,
    panels: &[Panel],
    targets: &MouldTargets,
    fabrication: &Fabrication,
    variant: EdgeArcs,
) -> (Option<Snapped>, MouldSnap) {
    let diag = reference.diagonal();
    let (mut snapped, mut snap) = snap_once(reference, sphere_mesh, panels, targets, fabrication.assign(&MouldFits::of(panels), diag), variant);
    // Snapped panels share their moulds' radii exactly, so the sweep may now find fewer moulds:
    // snap again to those while the count falls.
    for _ in 0..SNAP_PASSES {
        let Some(s) = &snapped else { break };
        let fewer = fabrication.assign(&MouldFits::of(&s.panels), diag);
        if fewer.moulds.len() >= snap.moulds.moulds.len() {
            break;
        }
        let (again, again_snap) = snap_once(reference, &s.sphere_mesh, &s.panels, targets, fewer, variant);
        if again.is_none() {
            break;
        }
        (snapped, snap) = (again, again_snap);
    }
    (snapped, snap)
}

/// Snaps beyond the first while the count falls.
const SNAP_PASSES: usize = 4;

/// One snap of the face spheres to `moulds` (see [`snap_to_moulds`]).
fn snap_once(
    reference: &Reference,
    sphere_mesh: &SphereMesh,
    panels: &[Panel],
    targets: &MouldTargets,
    moulds: MouldAssignment,
    variant: EdgeArcs,
) -> (Option<Snapped>, MouldSnap) {
    let positions = &sphere_mesh.mesh.positions;
    let mut spheres = sphere_mesh.face_spheres.clone();
    let mut limits = vec![None; panels.len()];
    for (i, p) in panels.iter().enumerate() {
        let current = spheres[p.face];
        let curvature = moulds.moulds[moulds.panel_mould[i] as usize].curvature.copysign(current.a);
        let snapped = match p.corners[..] {
            [a, b, c] => Sphere::through_points_with_curvature([a, b, c].map(|v| positions[v as usize]), curvature, &current),
            _ => None,
        };
        match snapped {
            Some(s) => spheres[p.face] = s,
            None => limits[i] = Some(SnapLimit::MouldBelowCircumradius),
        }
    }
    let moved = SphereMesh::new(sphere_mesh.mesh.clone(), spheres, sphere_mesh.boundary_arcs);
    let moved = delivered_arcs(moved, reference, variant);
    let (m, moved_panels, deviations) = metrics(&moved, reference, variant);
    if !targets.hold(&m, &moved_panels) {
        let limits = vec![Some(SnapLimit::MethodTargets); panels.len()];
        return (None, MouldSnap { moulds, limits });
    }
    (Some(Snapped { sphere_mesh: moved, panels: moved_panels, deviations, metrics: m }), MouldSnap { moulds, limits })
}
