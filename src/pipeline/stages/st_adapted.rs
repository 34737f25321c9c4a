//! The stage of ST meshes with adapted face size (Sec. 3): runs [`crate::st_adapted::compute`],
//! streams the sizing field, the remeshed triangulation, the panels while the spheres optimize
//! and the energy of every iteration, then the panel files and the report (method "st").

use serde::{Deserialize, Serialize};

use super::StageError;
use crate::export::{report_file, ExportFile, Report};
use crate::geometry::mesh::TriMesh;
use crate::panels::build_live_panels;
use crate::panels::buildability::Buildability;
use crate::panels::edge_arcs::EdgeArcs;
use crate::panels::exact_surface::ExactSurfaces;
use crate::panels::moulds::{MouldAssignment, SnapLimit};
use crate::panels::sphere_mesh::{BoundaryArcRule, SphereMesh};
use crate::pipeline::fields::{field, Energy, Field, StageId};
use crate::pipeline::panel_output::{export_panels, panel_fields, result_panel_fields, triangle_mesh_fields, PanelExport, Snapping};
use crate::pipeline::sink::{report, Sink};
use crate::progress::{Clock, Progress};
use crate::reference::Reference;
use crate::st_adapted::metrics::{StAdaptedMetrics, StAdaptedShape};
use crate::st_adapted::params::StAdaptedParams;
use crate::st_adapted::report::StAdaptedSection;
use crate::st_adapted::{compute, StAdaptedEvent, StAdaptedResult};

/// Stage name of the method in the worker protocol (the design link's `method=st`).
pub const STAGE: StageId = StageId::StAdapted;
/// Snapshot stage names: the sizing field on the reference, and the remeshed triangulation.
pub const SIZING_STAGE: StageId = StageId::StAdaptedSizing;
pub const REMESHED_STAGE: StageId = StageId::StAdaptedRemeshed;
/// Chord tolerance of the live panels (× diag): coarser than the exports, cheap to rebuild.
pub(crate) const LIVE_CHORD_TOLERANCE: f64 = 1e-3;
/// Least time between two live panel snapshots (ms); every iteration still sends its energies.
pub(crate) const SNAPSHOT_INTERVAL_MS: f64 = 100.0;

/// What the UI shows after the run: the report and the before/after metrics.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StAdaptedSummary {
    pub report: Report,
    pub initial: StAdaptedShape,
    pub metrics: StAdaptedMetrics,
    pub iterations: usize,
    /// min / max of the sizing field g (absolute), when the reference was remeshed adaptively.
    pub sizing_range: Option<(f64, f64)>,
    pub remeshed_faces: usize,
}

/// Runs the method on `reference`, streaming snapshots and progress to `sink`; returns the
/// summary and the result after sending the files.
pub fn run(
    reference: &Reference,
    params: &StAdaptedParams,
    clock: Clock,
    sink: &mut dyn Sink,
) -> Result<(StAdaptedSummary, StAdaptedResult), StageError> {
    let start = sink.now_ms();
    let diag = reference.diagonal();
    let mut last_snapshot = f64::NEG_INFINITY;
    let mut sizing_range = None;
    let mut remeshed_triangles: Vec<[u32; 3]> = Vec::new();
    let mut on_event = |e: StAdaptedEvent| {
        match e {
            StAdaptedEvent::Progress(p) => return report(sink, STAGE, p, Vec::new(), start),
            StAdaptedEvent::Sizing { values } => {
                let (lo, hi) = values.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &g| (lo.min(g), hi.max(g)));
                sizing_range = Some((lo, hi));
                sink.snapshot(SIZING_STAGE, 0, vec![Field::f32(field::SIZING, 1, values.iter().map(|&g| g as f32).collect())]);
            }
            StAdaptedEvent::Remeshed { mesh } => {
                remeshed_triangles = mesh.triangles.clone();
                sink.snapshot(REMESHED_STAGE, 0, triangle_mesh_fields(mesh));
            }
            StAdaptedEvent::Initialized { sphere_mesh } => {
                send_panels(sink, sphere_mesh, 0, LIVE_CHORD_TOLERANCE * diag, params.variant);
                last_snapshot = sink.now_ms();
            }
            StAdaptedEvent::MouldRound { round, sphere_mesh } => {
                send_panels(sink, sphere_mesh, round as u32, LIVE_CHORD_TOLERANCE * diag, params.variant);
                last_snapshot = sink.now_ms();
            }
            StAdaptedEvent::Iteration { progress, energy, terms, vertices, spheres } => {
                let mut energies = vec![Energy { name: "total".into(), value: energy }];
                energies.extend(terms.iter().map(|t| Energy { name: t.name.clone(), value: t.energy }));
                let Progress { done, total, .. } = progress;
                let go = report(sink, STAGE, progress, energies, start);
                if go.is_ok() && (sink.now_ms() - last_snapshot >= SNAPSHOT_INTERVAL_MS || done == total) {
                    let mesh = TriMesh::new(vertices.to_vec(), remeshed_triangles.clone());
                    let sm = SphereMesh::new(mesh, spheres.to_vec(), BoundaryArcRule::Parallel(glam::DVec3::ZERO));
                    send_panels(sink, &sm, done as u32, LIVE_CHORD_TOLERANCE * diag, params.variant);
                    last_snapshot = sink.now_ms();
                }
                return go;
            }
        }
        if sink.cancel_requested() {
            Err(crate::progress::Cancelled)
        } else {
            Ok(())
        }
    };
    let result = compute(reference, params, clock, &mut on_event)?;
    let report = reexport(reference, &result, params, clock, sink);
    let summary = StAdaptedSummary {
        report,
        initial: result.initial_shape.clone(),
        metrics: result.metrics.clone(),
        iterations: result.iterations,
        sizing_range,
        remeshed_faces: result.remeshed.face_count(),
    };
    Ok((summary, result))
}

/// Sends a result's final panels (in their moulds' colours) and files for `params`; returns the
/// report. A new δ, K or unit needs only this, not the method again.
pub fn reexport(reference: &Reference, result: &StAdaptedResult, params: &StAdaptedParams, clock: Clock, sink: &mut dyn Sink) -> Report {
    let (report, files, moulds) = exported(reference, result, params, clock);
    sink.snapshot(STAGE, result.iterations as u32, result_panel_fields(&result.panels, &moulds));
    sink.files(STAGE, files);
    report
}

/// A panel snapshot of the method's stage at `iteration`.
fn send_panels(sink: &mut dyn Sink, sm: &SphereMesh, iteration: u32, chord_tolerance: f64, variant: EdgeArcs) {
    sink.snapshot(STAGE, iteration, panel_fields(&build_live_panels(sm, chord_tolerance, variant)));
}

/// The report (method "st") and the export files of a result. `max_distance_to_reference` comes
/// from the schedule (sampled panels); the timings include "angle_iteration_median"; the
/// iteration count is `metrics.angle_iterations`.
pub fn export(reference: &Reference, result: &StAdaptedResult, params: &StAdaptedParams, clock: Clock) -> (Report, Vec<ExportFile>) {
    let (report, files, _) = exported(reference, result, params, clock);
    (report, files)
}

/// [`export`] with the panels' moulds.
fn exported(reference: &Reference, result: &StAdaptedResult, params: &StAdaptedParams, clock: Clock) -> (Report, Vec<ExportFile>, MouldAssignment) {
    let m = &result.metrics;
    let variant = result.variant.key();
    let section = StAdaptedSection::of(result);
    let exact = ExactSurfaces::of(&result.panels, &[]);
    let buildability = Buildability::measure(&exact, &result.panel_deviations, false, result.diag, params.fabrication.units);
    let verdict = crate::st_adapted::guarantees::verdict(m, &buildability, params.distance_bound(reference.facet_sagitta()));
    let mut timings = result.timings_ms.clone();
    if let Some(med) = result.angle_iteration_median_ms {
        timings.push(("angle_iteration_median".into(), med));
    }
    let export = PanelExport::new(
        STAGE.key(),
        &result.sphere_mesh,
        &result.panels,
        result.diag,
        params.radius_tolerance,
        params.fabrication,
        &section,
        &timings,
    )
    .with_extras(serde_json::json!({ "variant": variant }))
    .with_deviations(&result.panel_deviations)
    .with_moulds_before(result.fits_before.as_ref())
    .with_warnings(&result.warnings)
    .with_verdict(&verdict)
    .with_exact_surfaces(&exact)
    .with_snapping(result.mould_snap.as_ref().map_or(Snapping::Not(SnapLimit::NotAsked), Snapping::Snapped));
    let (report, mut files, moulds) = export_panels(reference, export, clock);
    files.push(report_file(&report));
    (report, files, moulds)
}
