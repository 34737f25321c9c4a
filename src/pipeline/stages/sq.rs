//! The stage of SQ meshes with support structure (Sec. 5), part 5.1: runs [`crate::sq::compute`],
//! streams the lines of the congruence while they optimize and the energy of every term, then
//! the cross field, the files (`congruence.json`, `congruence.glb`, `report.json`) and the
//! summary (method "sq"). The run stops after the congruence stage and says so in the report
//! (`stopped_after: "congruence"`); quad remeshing and the final optimization (Sec. 5.2) follow.
//!
//! When the mean curvature changes sign (Sec. 6.3), the stage sends H at the reference's
//! vertices (snapshot [`REFUSED_STAGE`]) before its error, so the app can show where.

use serde::{Deserialize, Serialize};

use super::StageError;
use crate::congruence::central_spheres::JetParams;
use crate::export::congruence::{congruence_glb, CongruenceJson, CongruenceSegments};
use crate::export::report::{InputCounts, OutputCounts};
use crate::export::{ExportFile, Metrics, Report};
use crate::pipeline::fields::{field, Energy, Field};
use crate::pipeline::panel_output::f32s;
use crate::pipeline::sink::{report, Sink};
use crate::progress::{ignore, Clock, Progress};
use crate::reference::Reference;
use crate::sq::metrics::CongruenceFigures;
use crate::sq::optimization::SqStep;
use crate::sq::params::SqParams;
use crate::sq::segments::{grid_spacing, line_segments, LINE_LENGTH};
use crate::sq::{compute, SqCongruence, SqError, SqEvent};

/// Stage name of the method in the worker protocol (the design link's `method=sq`).
pub const STAGE: &str = "sq";
/// Snapshot of H at the reference vertices, sent when SQ refuses the surface (Sec. 6.3).
pub const REFUSED_STAGE: &str = "sq.refused";
/// What this part of the method computes last.
pub const STOPS_AFTER: &str = "congruence";
/// Least time between two live line snapshots (ms); every iteration still sends its energies.
pub const SNAPSHOT_INTERVAL_MS: f64 = 100.0;

/// What the UI shows after the run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SqSummary {
    pub report: Report,
    /// Of the central congruence of the fitted r, and of the optimized one.
    pub initial: CongruenceFigures,
    pub figures: CongruenceFigures,
}

/// Runs the method on `reference`, streaming the lines and the energies to `sink`; returns the
/// summary after sending the display fields and the files.
pub fn run(reference: &Reference, params: &SqParams, clock: Clock, sink: &mut dyn Sink) -> Result<SqSummary, StageError> {
    let start = sink.now_ms();
    let mut last_snapshot = f64::NEG_INFINITY;
    let (mut points, mut length, mut lc_done) = (Vec::new(), 0.0, 0);
    let mut on_event = |e: SqEvent| match e {
        SqEvent::Progress(p) => report(sink, STAGE, p, Vec::new(), start),
        SqEvent::Started { points: p, lines } => {
            points = p.to_vec();
            length = LINE_LENGTH * grid_spacing(params.grid, &points);
            let initial = line_segments(&points, lines, length);
            sink.snapshot(STAGE, 0, vec![segments_field(field::SQ_INITIAL_LINES, &initial), segments_field(field::SQ_LINES, &initial)]);
            last_snapshot = sink.now_ms();
            report(sink, STAGE, Progress::new("line_congruence", 0, params.lc_iterations + params.torsal_iterations), Vec::new(), start)
        }
        SqEvent::Iteration { step, iteration, terms, lines } => {
            let total: f64 = terms.iter().map(|t| t.energy).sum();
            let mut energies = vec![Energy { name: "total".into(), value: total }];
            energies.extend(terms.iter().map(|t| Energy { name: t.name.clone(), value: t.energy }));
            // Step 1 may converge early: step 2 counts on from where it stopped.
            if step == SqStep::LineCongruence {
                lc_done = iteration;
            }
            let done = iteration + if step == SqStep::Torsal { lc_done } else { 0 };
            let total = if step == SqStep::Torsal { lc_done } else { params.lc_iterations } + params.torsal_iterations;
            let go = report(sink, STAGE, Progress::new(step.key(), done, total), energies, start);
            if go.is_ok() && sink.now_ms() - last_snapshot >= SNAPSHOT_INTERVAL_MS {
                sink.snapshot(STAGE, done as u32, vec![segments_field(field::SQ_LINES, &line_segments(&points, &lines, length))]);
                last_snapshot = sink.now_ms();
            }
            go
        }
    };
    let result = match compute(reference, params, clock, &mut on_event) {
        Ok(r) => r,
        Err(e @ (SqError::MeanCurvatureSignChange { .. } | SqError::MeanCurvatureNearZero { .. })) => {
            // Exact H at the vertices of a B-spline reference (cached for the app's colour map).
            if let Ok(c) = reference.curvature(&JetParams::default(), &mut ignore) {
                let h = c.vertices.iter().map(|v| v.mean as f32).collect();
                sink.snapshot(REFUSED_STAGE, 0, vec![Field::f32(field::MEAN_CURVATURE, 1, h)]);
            }
            return Err(e.into());
        }
        Err(e) => return Err(e.into()),
    };
    let segments = CongruenceSegments::of(&result);
    let (report, files) = export(reference, &result, params, &segments);
    sink.snapshot(STAGE, (result.lc_iterations + result.torsal_iterations) as u32, display_fields(&segments));
    sink.files(STAGE, files);
    Ok(SqSummary { report, initial: result.initial_figures, figures: result.figures })
}

/// Segments as a field of point pairs.
fn segments_field(name: &str, segments: &[(glam::DVec3, glam::DVec3)]) -> Field {
    Field::f32(name, 3, f32s(segments.iter().flat_map(|&(a, b)| [a, b])))
}

/// Lines (initial and optimized), the cross field with its angles, and the quads without real
/// torsal directions.
pub fn display_fields(s: &CongruenceSegments) -> Vec<Field> {
    vec![
        segments_field(field::SQ_INITIAL_LINES, &s.initial_lines),
        segments_field(field::SQ_LINES, &s.lines),
        segments_field(field::SQ_CROSS_FIELD, &s.cross_field),
        Field::f32(field::SQ_CROSS_FIELD_ANGLE, 1, s.cross_field_angle_deg.iter().map(|&a| a as f32).collect()),
        segments_field(field::SQ_NO_REAL_QUADS, &s.no_real_quads),
    ]
}

/// The report (method "sq") of a result.
pub fn sq_report(reference: &Reference, result: &SqCongruence, params: &SqParams) -> Report {
    let (f, i) = (&result.figures, &result.initial_figures);
    let mut report = Report::new(STAGE);
    let mesh = reference.mesh();
    report.input = InputCounts { vertices: mesh.positions.len(), faces: reference.surface().face_count() };
    report.output = OutputCounts { vertices: result.points.len(), faces: result.torsal.len(), panels: 0 };
    report.metrics = Metrics {
        max_line_normal_angle_deg: Some(f.max_line_normal_angle_deg),
        initial_max_line_normal_angle_deg: Some(i.max_line_normal_angle_deg),
        mean_line_normal_angle_deg: Some(f.mean_line_normal_angle_deg),
        min_torsal_plane_angle_deg: Some(f.min_torsal_plane_angle_deg),
        initial_min_torsal_plane_angle_deg: Some(i.min_torsal_plane_angle_deg),
        mean_torsal_plane_angle_deg: Some(f.mean_torsal_plane_angle_deg),
        quads_without_real_torsal_directions: Some(f.quads_without_real_torsal_directions),
        initial_quads_without_real_torsal_directions: Some(i.quads_without_real_torsal_directions),
        lc_residual: Some(result.lc_residual),
        lc_residual_step1: Some(result.lc_residual_step1),
        radius_fit_error: Some(result.radius_fit_error),
        line_congruence_iterations: Some(result.lc_iterations),
        torsal_iterations: Some(result.torsal_iterations),
        ..Metrics::default()
    };
    for (step, ms) in &result.timings_ms {
        report.add_timing(step.clone(), *ms);
    }
    report.add_timing("total", result.timings_ms.iter().map(|(_, ms)| ms).sum::<f64>());
    report.add_timing("lc_iteration_median", result.lc_iteration_median_ms().unwrap_or(0.0));
    report.add_timing("torsal_iteration_median", result.torsal_iteration_median_ms().unwrap_or(0.0));
    report.iterations = Some(result.lc_iterations + result.torsal_iterations);
    report.grid = Some(result.grid);
    report.theta_deg = Some(params.theta_deg);
    report.alpha_deg = Some(params.alpha_deg);
    report.radius_basis = Some(result.radius_basis);
    report.stopped_after = Some(STOPS_AFTER.into());
    report.warnings = result.warnings.clone();
    report
}

/// The report and the files: `congruence.json`, `congruence.glb`, `report.json`.
pub fn export(reference: &Reference, result: &SqCongruence, params: &SqParams, segments: &CongruenceSegments) -> (Report, Vec<ExportFile>) {
    let report = sq_report(reference, result, params);
    let ((u0, u1), (v0, v1)) = reference.spline().map_or(((0.0, 1.0), (0.0, 1.0)), |s| s.domain());
    let json = CongruenceJson::of(result, params.theta_deg, params.alpha_deg, [[u0, u1], [v0, v1]]);
    let extras = serde_json::json!({
        "method": STAGE,
        "theta_deg": params.theta_deg,
        "alpha_deg": params.alpha_deg,
        "grid": result.grid,
        "metrics": &report.metrics,
    });
    let file = |name: &str, mime: &str, bytes: Vec<u8>| ExportFile { name: name.into(), mime: mime.into(), bytes };
    let files = vec![
        file("congruence.glb", "model/gltf-binary", congruence_glb(reference.mesh(), segments, extras)),
        file("congruence.json", "application/json", json.to_json().into_bytes()),
        file("report.json", "application/json", report.to_json().into_bytes()),
    ];
    (report, files)
}
