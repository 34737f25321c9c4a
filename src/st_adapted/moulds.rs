//! Fewer moulds (Sec. 3 with the fabrication's moulds, [`crate::panels::moulds`]): the panels
//! of the angle-minimizing ST mesh are moved so that they land on fewer radii. Each round assigns
//! the panels to the moulds of a coarser tolerance (γ δ, fewer moulds), adds [`MouldCurvature`]
//! pulling every face sphere's curvature to its mould's, and optimizes again from the last
//! result with all the method's terms. A round is kept when the moulds at δ fell and the method's
//! targets hold (largest kink ≤ [`KINK_GROWTH`] × before, panels within 2ε); the rounds stop
//! when the count stops falling. Then [`snap_to_moulds`] gives every face sphere its mould's
//! radius exactly: a face sphere is free in the pencil through its three vertices, which holds
//! one sphere of each radius above their circumradius, so the vertices stay.

use std::cell::RefCell;

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
use crate::panels::moulds::{Fabrication, MouldAssignment, MouldFits, MouldSnap, SnapLimit};
use crate::panels::panel::Panel;
use crate::panels::sphere_mesh::SphereMesh;
use crate::progress::{Cancelled, Clock, Progress};
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

/// What the rounds made: the kept sphere mesh with its panels and deviations, and per round
/// (γ, moulds at δ, largest kink, largest distance) for the report.
pub struct FewerMoulds {
    pub sphere_mesh: SphereMesh,
    pub panels: Vec<Panel>,
    pub deviations: Vec<f64>,
    pub metrics: StAdaptedMetrics,
    pub rounds: Vec<MouldRound>,
    pub iterations: usize,
    /// Moulds at δ before the rounds, and the fits of the panels then.
    pub before: usize,
    pub fits_before: MouldFits,
}

/// One round of [`fewer_moulds`].
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MouldRound {
    pub coarsening: f64,
    pub moulds: usize,
    pub max_kink_angle_deg: f64,
    pub max_distance_to_reference: f64,
    pub kept: bool,
}

/// The rounds on `sphere_mesh` (the method's result on `reference`), each sent to `on_event` as
/// moved; None when no round kept fewer moulds.
pub fn fewer_moulds(
    reference: &Reference,
    sphere_mesh: &SphereMesh,
    start: &StAdaptedMetrics,
    panels: &[Panel],
    fabrication: &Fabrication,
    params: &StAdaptedParams,
    clock: Clock,
    on_event: &mut OnEvent,
) -> Result<Option<FewerMoulds>, Cancelled> {
    let diag = reference.diagonal();
    let mut panels = panels.to_vec();
    let limits = MouldTargets::of(start, params);
    let fits_before = MouldFits::of(&panels);
    let before = fabrication.assign(&fits_before, diag).moulds.len();
    let mut best_count = before;
    let mut best: Option<FewerMoulds> = None;
    let mut rounds = Vec::new();
    let mut iterations = 0;
    let mut current = sphere_mesh.clone();
    // Each round continues the last stage of the method for a few iterations.
    let last = params.stages.last().cloned().map(|s| OptimizationStage { iterations: s.iterations.min(ROUND_ITERATIONS), ..s });
    let stages = StAdaptedParams { stages: last.into_iter().collect(), ..params.clone() };
    for (k, &gamma) in COARSENING.iter().enumerate() {
        on_event(StAdaptedEvent::Progress(Progress::new("fewer_moulds", k, COARSENING.len())))?;
        let fits = MouldFits::of(&panels);
        let coarse = fits.assign(gamma * fabrication.tolerance(&fits, diag));
        let mut targets = vec![f64::NAN; current.mesh.face_count()];
        for (i, p) in panels.iter().enumerate() {
            let m = coarse.moulds[coarse.panel_mould[i] as usize].curvature;
            // The frame scales lengths by 1/diag, curvatures by diag; the mould either way up.
            targets[p.face] = m * diag * if fits.curvature[i] < 0.0 { -1.0 } else { 1.0 };
        }
        let mesh = current.mesh.triangulated();
        let frame = OptimizationFrame::new(reference, &mesh, &current.face_spheres, params);
        let mut x = frame.x0.clone();
        let (mut problem, ids) = frame.problem(&params.variant_weights());
        let corners = mesh.triangles.iter().map(|t| t.map(|v| vertex_offset(mesh.face_count(), v as usize))).collect();
        problem.add_term(MouldCurvature::new(FaceSpheres::new(corners), targets), MOULD_WEIGHT * params.weights.angle);
        let mut solver = Solver::new(SolverOptions { clock, ..SolverOptions::default() });
        let run = RefCell::new(0usize);
        run_stages(&mut problem, &ids, &mut x, &stages, &mut solver, &mut |_, _| {
            *run.borrow_mut() += 1;
            Ok(())
        })?;
        iterations += run.into_inner();
        let (verts, spheres) = frame.to_model(&x);
        let moved = SphereMesh::new(TriMesh::new(verts, mesh.triangles.clone()), spheres, current.boundary_arcs);
        let moved = delivered_arcs(moved, reference, params.variant);
        on_event(StAdaptedEvent::MouldRound { round: k + 1, sphere_mesh: &moved })?;
        let (m, moved_panels, deviations) = metrics(&moved, reference, params.variant);
        let count = fabrication.assign(&MouldFits::of(&moved_panels), diag).moulds.len();
        let holds = limits.hold(&m, &moved_panels);
        let kept = holds && count < best_count;
        rounds.push(MouldRound {
            coarsening: gamma,
            moulds: count,
            max_kink_angle_deg: m.max_kink_angle_deg,
            max_distance_to_reference: m.max_distance_to_reference,
            kept,
        });
        if !holds {
            break;
        }
        if kept {
            best_count = count;
            best = Some(FewerMoulds {
                sphere_mesh: moved.clone(),
                panels: moved_panels.clone(),
                deviations,
                metrics: m,
                rounds: Vec::new(),
                iterations: 0,
                before,
                fits_before: MouldFits::default(),
            });
        }
        (current, panels) = (moved, moved_panels);
    }
    Ok(best.map(|b| FewerMoulds { rounds, iterations, fits_before, ..b }))
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
