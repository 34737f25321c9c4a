//! The "ST, adapted face size" method (Sec. 3, issue 4) for the worker and the CLI: runs
//! [`crate::st_angle::st_angle`], streams the sizing field, the remeshed triangulation and the
//! panels of every iteration, and writes the panel files and the shared report (method "st").

use crate::export::{self, report::InputCounts, report::OutputCounts, Metrics, Report};
use crate::mesh::TriMesh;
use crate::panels::build_panels;
use crate::st_angle::{StAngleResult, CHORD_TOLERANCE};

use super::st_support::{panel_files, ExportFile};

/// The report (`report.json` schema of `st-support`, method `"st"`) and the export files
/// (panels.glb/.obj/.csv/.json, report.json) of a result. `radius_tolerance` is relative to the
/// diagonal. `max_distance_to_reference` comes from the schedule (sampled panels), as in
/// st-support; timings include `"angle_iteration_median"` and the stage timings; the iteration
/// count is `metrics.angle_iterations`.
pub fn report_and_files(
    reference: &TriMesh,
    result: &StAngleResult,
    radius_tolerance: f64,
) -> (Report, Vec<ExportFile>) {
    let diag = result.diag;
    let panels = build_panels(&result.sphere_mesh, CHORD_TOLERANCE * diag);
    let schedule = export::build_schedule(&panels, reference, radius_tolerance * diag);
    let mut extras = serde_json::json!({});
    extras["method"] = "st".into();
    extras["variant"] = format!("{:?}", result.variant).to_lowercase().into();
    let glb = export::write_glb(&panels, None, None, extras);
    let obj = export::write_obj(&panels, None, None);
    let m = &result.metrics;
    let mut report = Report::new("st");
    report.input = InputCounts { vertices: reference.vertex_count(), faces: reference.face_count() };
    report.output = OutputCounts {
        vertices: result.sphere_mesh.mesh.vertex_count(),
        faces: result.sphere_mesh.mesh.face_count(),
        panels: panels.len(),
    };
    let mut extra: std::collections::BTreeMap<String, serde_json::Value> = [
        ("angle_iterations", serde_json::json!(result.iterations)),
        ("variant", serde_json::json!(format!("{:?}", result.variant).to_lowercase())),
        ("distinct_radii", serde_json::json!(schedule.distinct_radii)),
        ("flipped_faces", serde_json::json!(m.flipped_faces)),
        ("max_vertex_distance_to_reference", serde_json::json!(m.max_vertex_distance_to_reference)),
        ("initial_mean_kink_angle_deg", serde_json::json!(result.initial_metrics.mean_kink_angle_deg)),
        ("initial_max_kink_angle_deg", serde_json::json!(result.initial_metrics.max_kink_angle_deg)),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_string(), v))
    .collect();
    if let Some(g) = m.max_gap {
        extra.insert("max_gap".into(), serde_json::json!(g));
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
    (report, files)
}
