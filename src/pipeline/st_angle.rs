//! The "ST, adapted face size" method (Sec. 3, issue 4) for the worker and the CLI: runs
//! [`crate::st_angle::st_angle`], streams the sizing field, the remeshed triangulation and the
//! panels of every iteration, and writes the panel files and the shared report (method "st").

use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::protocol::{field, Energy, Field, FromWorker, Progress};
use super::st_support::{f32s, panel_fields, panel_files, ExportFile};
use super::{snapshot, Sink};
use crate::curvature::JetParams;
use crate::export::{self, Metrics, Report};
use crate::mesh::{Topology, TriMesh};
use crate::panels::{build_panels_with, Panel};
use crate::sphere_mesh::SphereMesh;
use crate::st_angle::{
    project_spheres, st_angle, StAngleEvent, StAngleMetrics, StAngleParams, StAngleResult, StSizing, StVariant,
    CHORD_TOLERANCE,
};
use crate::st_support::Clock;

/// Stage name of the method in the worker protocol.
pub const STAGE: &str = "st";
/// Snapshot stage names: the sizing field on the reference, and the remeshed triangulation.
pub const SIZING_STAGE: &str = "st.sizing";
pub const REMESHED_STAGE: &str = "st.remeshed";
/// Chord tolerance of the live panels (× diag): coarser than the exports, cheap to rebuild.
pub const LIVE_CHORD_TOLERANCE: f64 = 1e-3;
/// Least time between two live panel snapshots (ms); every iteration still sends its energies.
pub const SNAPSHOT_INTERVAL_MS: f64 = 100.0;

/// Field names of the method's snapshots (panels use `st_support::fields`).
pub mod fields {
    /// The sizing field g at the reference vertices (absolute length), f32 × 1.
    pub const SIZING: &str = "sizing";
}

/// The method's parameters as the design link and the CLI give them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StRequest {
    pub sizing: StSizing,
    pub variant: StVariant,
    /// Radii closer than this (× diag) count as one in the panel schedule.
    pub radius_tolerance: f64,
    pub jet: JetParams,
}

impl Default for StRequest {
    fn default() -> Self {
        Self {
            sizing: StAngleParams::default().sizing,
            variant: StVariant::A,
            radius_tolerance: 1e-3,
            jet: JetParams::default(),
        }
    }
}

/// What the UI shows after the run: the report and the before/after metrics.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StSummary {
    pub report: Report,
    pub initial: StAngleMetrics,
    pub metrics: StAngleMetrics,
    pub iterations: usize,
    /// min / max of the sizing field g (absolute), when the reference was remeshed adaptively.
    pub sizing_range: Option<(f64, f64)>,
    pub remeshed_faces: usize,
}

/// Runs the method on `reference`, streaming snapshots and progress to `sink`; returns the
/// result, the summary and the export files. Err("cancelled") when the sink asked to stop.
pub fn run(
    reference: &TriMesh,
    req: &StRequest,
    clock: Clock,
    sink: &mut dyn Sink,
) -> Result<(StAngleResult, StSummary, Vec<ExportFile>), String> {
    let params = StAngleParams { sizing: req.sizing, variant: req.variant, jet: req.jet.clone(), ..StAngleParams::default() };
    let total: usize = params.stages.iter().map(|s| s.iterations).sum();
    let start = sink.now_ms();
    let diag = reference.bbox_diagonal();
    let mut last_snapshot = f64::NEG_INFINITY;
    let mut sizing_range = None;
    let mut remeshed_triangles: Vec<[u32; 3]> = Vec::new();
    let mut hook = |e: StAngleEvent| -> bool {
        match e {
            StAngleEvent::Stage(name) => progress(sink, name, 0, 0, Vec::new(), start),
            StAngleEvent::Progress { stage, done, total } => progress(sink, stage, done, total, Vec::new(), start),
            StAngleEvent::Sizing { values } => {
                let (lo, hi) = values.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &g| (lo.min(g), hi.max(g)));
                sizing_range = Some((lo, hi));
                let fields = vec![Field::f32(fields::SIZING, 1, values.iter().map(|&g| g as f32).collect())];
                sink.send(snapshot(SIZING_STAGE, 0, &fields), fields);
            }
            StAngleEvent::Remeshed { mesh } => {
                remeshed_triangles = mesh.triangles.clone();
                let fields = mesh_fields(mesh);
                sink.send(snapshot(REMESHED_STAGE, 0, &fields), fields);
            }
            StAngleEvent::Initialized { sphere_mesh } => {
                send_panels(sink, sphere_mesh, 0, LIVE_CHORD_TOLERANCE * diag, req.variant);
                last_snapshot = sink.now_ms();
            }
            StAngleEvent::Iteration { stage, iteration, energy, terms, vertices, spheres, .. } => {
                let mut energies = vec![Energy { name: "total".into(), value: energy }];
                energies.extend(terms.iter().map(|t| Energy { name: t.name.clone(), value: t.energy }));
                progress(sink, stage, iteration, total, energies, start);
                if sink.now_ms() - last_snapshot >= SNAPSHOT_INTERVAL_MS || iteration == total {
                    let mesh = TriMesh::new(vertices.to_vec(), remeshed_triangles.clone());
                    let sm = SphereMesh { face_spheres: project_spheres(&mesh, spheres), mesh, boundary_arcs: live_rule() };
                    send_panels(sink, &sm, iteration as u32, LIVE_CHORD_TOLERANCE * diag, req.variant);
                    last_snapshot = sink.now_ms();
                }
            }
        }
        !sink.cancel_requested()
    };
    let result = st_angle(reference, &params, clock.0, &mut hook)?;
    let (report, files, panels) = export_result(reference, &result, req.radius_tolerance);
    let fields = panel_fields(&panels);
    sink.send(snapshot(STAGE, result.iterations as u32, &fields), fields);
    let summary = StSummary {
        report,
        initial: result.initial_metrics.clone(),
        metrics: result.metrics.clone(),
        iterations: result.iterations,
        sizing_range,
        remeshed_faces: result.remeshed.face_count(),
    };
    Ok((result, summary, files))
}

/// The boundary-arc rule of the method's sphere meshes.
fn live_rule() -> crate::sphere_mesh::BoundaryArcRule {
    crate::sphere_mesh::BoundaryArcRule::Parallel(DVec3::ZERO)
}

fn progress(sink: &mut dyn Sink, detail: &str, done: usize, total: usize, energies: Vec<Energy>, start: f64) {
    let p = Progress {
        stage: STAGE.into(),
        detail: detail.into(),
        iteration: done as u32,
        total: total as u32,
        energies,
        elapsed_ms: sink.now_ms() - start,
    };
    sink.send(FromWorker::Progress(p), Vec::new());
}

/// Positions, normals, triangles and unique edges of a mesh.
pub fn mesh_fields(mesh: &TriMesh) -> Vec<Field> {
    let topo = Topology::new(mesh);
    vec![
        Field::f32(field::POSITIONS, 3, f32s(mesh.positions.iter().copied())),
        Field::f32(field::NORMALS, 3, f32s(mesh.vertex_normals().into_iter())),
        Field::u32(field::TRIANGLES, 3, mesh.triangles.iter().flatten().copied().collect()),
        Field::u32(field::EDGES, 2, topo.edges().iter().flatten().copied().collect()),
    ]
}

/// A panel snapshot of the method's stage at `iteration`.
pub fn send_panels(sink: &mut dyn Sink, sm: &SphereMesh, iteration: u32, chord_tolerance: f64, variant: StVariant) {
    let fields = panel_fields(&build_panels_with(sm, chord_tolerance, variant.edge_arcs()));
    sink.send(snapshot(STAGE, iteration, &fields), fields);
}

/// The report (`report.json` schema of `st-support`, method `"st"`) and the export files
/// (panels.glb/.obj/.csv/.json, report.json) of a result. `radius_tolerance` is relative to the
/// diagonal. `max_distance_to_reference` comes from the schedule (sampled panels), as in
/// st-support; timings include `"angle_iteration_median"` and the stage timings; the iteration
/// count is `metrics.angle_iterations`.
pub fn report_and_files(reference: &TriMesh, result: &StAngleResult, radius_tolerance: f64) -> (Report, Vec<ExportFile>) {
    let (report, files, _) = export_result(reference, result, radius_tolerance);
    (report, files)
}

/// [`report_and_files`] and the panels they were written from.
pub fn export_result(
    reference: &TriMesh,
    result: &StAngleResult,
    radius_tolerance: f64,
) -> (Report, Vec<ExportFile>, Vec<Panel>) {
    let diag = result.diag;
    let panels = build_panels_with(&result.sphere_mesh, CHORD_TOLERANCE * diag, result.variant.edge_arcs());
    let schedule = export::build_schedule(&panels, reference, radius_tolerance * diag);
    let mut extras = serde_json::json!({});
    extras["method"] = "st".into();
    extras["variant"] = format!("{:?}", result.variant).to_lowercase().into();
    let glb = export::write_glb(&panels, None, None, extras);
    let obj = export::write_obj(&panels, None, None);
    let m = &result.metrics;
    let mut report = Report::for_panels("st", reference, &result.sphere_mesh.mesh, panels.len());
    let mut extra: std::collections::BTreeMap<String, serde_json::Value> = [
        ("angle_iterations", serde_json::json!(result.iterations)),
        ("variant", serde_json::json!(format!("{:?}", result.variant).to_lowercase())),
        ("distinct_radii", serde_json::json!(schedule.distinct_radii)),
        ("flipped_faces", serde_json::json!(m.flipped_faces)),
        ("initial_flipped_faces", serde_json::json!(result.initial_metrics.flipped_faces)),
        ("max_vertex_distance_to_reference", serde_json::json!(m.max_vertex_distance_to_reference)),
        ("initial_mean_kink_angle_deg", serde_json::json!(result.initial_metrics.mean_kink_angle_deg)),
        ("initial_max_kink_angle_deg", serde_json::json!(result.initial_metrics.max_kink_angle_deg)),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_string(), v))
    .collect();
    if let Some(g) = m.max_gap {
        extra.insert("max_gap".into(), serde_json::json!(g));
        // The same gap measured on the exported panels' own arcs (panels::arc_gaps).
        let panel_gap = crate::panels::max_arc_gap(&panels, crate::st_angle::GAP_SAMPLES) / diag;
        extra.insert("max_panel_arc_gap".into(), serde_json::json!(panel_gap));
    }
    report.metrics = Metrics {
        max_vertex_sphere_residual: Some(m.max_vertex_sphere_residual),
        mean_kink_angle_deg: Some(m.mean_kink_angle_deg),
        max_kink_angle_deg: Some(m.max_kink_angle_deg),
        max_distance_to_reference: Some(schedule.max_deviation / diag),
        extra,
        ..Metrics::default()
    };
    for (stage, ms) in &result.timings_ms {
        report.add_timing(stage.clone(), *ms);
    }
    if let Some(med) = result.angle_iteration_median_ms {
        report.add_timing("angle_iteration_median", med);
    }
    let files = panel_files(glb, obj, &schedule, &report);
    (report, files, panels)
}
