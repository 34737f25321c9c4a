//! The stage of ST meshes with adapted face size (Sec. 3): runs [`crate::st_adapted::compute`],
//! streams the sizing field, the remeshed triangulation, the panels while the spheres optimize
//! and the energy of every iteration, then the panel files and the report (method "st").

use serde::{Deserialize, Serialize};

use super::StageError;
use crate::export::{report_file, Report};
use crate::geometry::mesh::TriMesh;
use crate::panels::build_live_panels;
use crate::panels::edge_arcs::EdgeArcs;
use crate::panels::moulds::MouldAssignment;
use crate::panels::sphere_mesh::{BoundaryArcRule, SphereMesh};
use crate::pipeline::fields::{field, Energy, Field, Part};
use crate::pipeline::method::{Computed, Exported, Method, Request};
use crate::pipeline::panel_output::{export_panels, panel_fields, result_panel_fields, triangle_mesh_fields, with_moulds, PanelExport, Snapping};
use crate::pipeline::sink::{report, Sink};
use crate::progress::{Clock, Progress};
use crate::reference::Reference;
use crate::st_adapted::guarantees::measure;
use crate::st_adapted::metrics::{StAdaptedMetrics, StAdaptedShape};
use crate::st_adapted::params::StAdaptedParams;
use crate::st_adapted::report::StAdaptedSection;
use crate::st_adapted::{compute, StAdaptedEvent, StAdaptedResult};

/// Least time between two live panel snapshots (ms); every iteration still sends its energies.
pub(crate) const SNAPSHOT_INTERVAL_MS: f64 = 100.0;
/// Chord tolerance of the live panels (× diag): coarser than the exports, cheap to rebuild.
pub(crate) const LIVE_CHORD_TOLERANCE: f64 = 1e-3;

/// The method in the pipeline.
pub struct StAdaptedStage;

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

impl Method for StAdaptedStage {
    const KEY: &'static str = "st";
    const LABEL: &'static str = "ST, adapted face size (Sec. 3)";
    type Params = StAdaptedParams;
    type Result = StAdaptedResult;
    type Summary = StAdaptedSummary;

    fn optimizes_moulds(params: &StAdaptedParams) -> bool {
        params.optimize_moulds
    }

    fn compute(
        reference: &Reference,
        request: &Request<StAdaptedParams>,
        clock: Clock,
        sink: &mut dyn Sink,
    ) -> Result<Computed<StAdaptedResult>, StageError> {
        let params = &core_params(request);
        let start = sink.now_ms();
        let diag = reference.diagonal();
        let live = sink.wants_snapshots();
        let mut last_snapshot = f64::NEG_INFINITY;
        let mut remeshed_triangles: Vec<[u32; 3]> = Vec::new();
        let mut on_event = |e: StAdaptedEvent| {
            match e {
                StAdaptedEvent::Progress(p) => return report(sink, p, Vec::new(), start),
                StAdaptedEvent::Sizing { values } => {
                    sink.snapshot(Part::Sizing, 0, vec![Field::f32(field::SIZING, 1, values.iter().map(|&g| g as f32).collect())]);
                }
                StAdaptedEvent::Remeshed { mesh } => {
                    remeshed_triangles = mesh.triangles.clone();
                    sink.snapshot(Part::Remeshed, 0, triangle_mesh_fields(mesh));
                }
                StAdaptedEvent::Initialized { sphere_mesh } if live => {
                    send_panels(sink, sphere_mesh, 0, LIVE_CHORD_TOLERANCE * diag, params.variant);
                    last_snapshot = sink.now_ms();
                }
                StAdaptedEvent::MouldRound { round, sphere_mesh } if live => {
                    send_panels(sink, sphere_mesh, round as u32, LIVE_CHORD_TOLERANCE * diag, params.variant);
                    last_snapshot = sink.now_ms();
                }
                StAdaptedEvent::Initialized { .. } | StAdaptedEvent::MouldRound { .. } => {}
                StAdaptedEvent::Iteration { progress, energy, terms, vertices, spheres } => {
                    let mut energies = vec![Energy { name: "total".into(), value: energy }];
                    energies.extend(terms.iter().map(|t| Energy { name: t.name.clone(), value: t.energy }));
                    let Progress { done, total, .. } = progress;
                    let go = report(sink, progress, energies, start);
                    if go.is_ok() && live && (sink.now_ms() - last_snapshot >= SNAPSHOT_INTERVAL_MS || done == total) {
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
        let result = compute(reference, params, &request.fabrication, clock, &mut on_event)?;
        Ok(Computed { iteration: result.iterations as u32, result })
    }

    /// The report (method "st") and the export files of a result. `max_distance_to_reference`
    /// comes from the schedule (sampled panels); the timings include "angle_iteration_median";
    /// the iteration count is `metrics.angle_iterations`.
    fn export(reference: &Reference, result: &StAdaptedResult, request: &Request<StAdaptedParams>, clock: Clock) -> Exported {
        let params = &core_params(request);
        let variant = result.variant.key();
        let section = StAdaptedSection::of(result);
        let (verdict, exact) = measure(result, reference, params, request.fabrication.units);
        let mut timings = result.timings_ms.clone();
        if let Some(med) = result.angle_iteration_median_ms {
            timings.push(("angle_iteration_median".into(), med));
        }
        let export = PanelExport::new(
            Self::KEY,
            &result.sphere_mesh,
            &result.panels,
            result.diag,
            params.radius_tolerance,
            request.fabrication,
            &section,
            &timings,
        )
        .with_extras(serde_json::json!({ "variant": variant }))
        .with_deviations(&result.panel_deviations)
        .with_moulds_before(result.moulds.as_ref().map(|m| &m.fits_before))
        .with_warnings(&result.warnings)
        .with_verdict(&verdict)
        .with_exact_surfaces(&exact)
        .with_snapping(Snapping::of(result.moulds.as_ref().map(|m| &m.snap)));
        let (report, mut files, moulds) = export_panels(reference, export, clock);
        files.push(report_file(&report));
        Exported { report, files, moulds: Some(moulds) }
    }

    fn display(result: &StAdaptedResult, moulds: Option<&MouldAssignment>) -> Vec<Field> {
        moulds.map_or_else(Vec::new, |m| result_panel_fields(&result.panels, m))
    }

    fn summary(result: &StAdaptedResult, report: Report) -> StAdaptedSummary {
        StAdaptedSummary {
            report,
            initial: result.initial_shape.clone(),
            metrics: result.metrics.clone(),
            iterations: result.iterations,
            sizing_range: result.sizing_range,
            remeshed_faces: result.remeshed.face_count(),
        }
    }

    fn report(summary: &StAdaptedSummary) -> &Report {
        &summary.report
    }

    fn report_mut(summary: &mut StAdaptedSummary) -> &mut Report {
        &mut summary.report
    }

    /// The ST method on a small dome ([`crate::st_adapted::warm_up`]).
    fn warm_up() -> Result<(), String> {
        crate::st_adapted::warm_up::warm_up().map(|_| ()).map_err(|e| e.to_string())
    }

    fn describe(result: &StAdaptedResult, report: &Report, _request: &Request<StAdaptedParams>, out: &str) -> String {
        let line = format!(
            "wrote {} panels to {out} (kink mean {:.3}°, max {:.3}°; max distance to reference {}; {} folded faces)",
            report.output.panels,
            result.metrics.mean_kink_angle_deg,
            result.metrics.max_kink_angle_deg,
            report.metrics.as_ref().map_or("–".into(), |m| m.max_distance_text()),
            result.metrics.flipped_faces
        );
        with_moulds(line, report)
    }
}

/// The method's own parameters with the request's jet fit.
fn core_params(request: &Request<StAdaptedParams>) -> StAdaptedParams {
    StAdaptedParams { jet: request.jet.clone(), ..request.params.clone() }
}

/// A panel snapshot of the method's stage at `iteration`.
fn send_panels(sink: &mut dyn Sink, sm: &SphereMesh, iteration: u32, chord_tolerance: f64, variant: EdgeArcs) {
    sink.snapshot(Part::Main, iteration, panel_fields(&build_live_panels(sm, chord_tolerance, variant)));
}

impl From<crate::st_adapted::StAdaptedError> for StageError {
    fn from(e: crate::st_adapted::StAdaptedError) -> Self {
        use crate::st_adapted::StAdaptedError;
        match e {
            StAdaptedError::Cancelled => StageError::Cancelled,
            StAdaptedError::TooManyFaces(t) => StageError::refused(&t, Some(t.suggested())),
            e => StageError::refused(&e, None),
        }
    }
}
