//! The stage of SQ meshes with support structure (Sec. 5): runs [`crate::sq::compute`] as far as
//! the parameters' `until` asks and streams every stage live, with one progress count across
//! them: the lines of the congruence while they optimize (Sec. 5.1), the cross field, the quad
//! mesh as remeshed and while it fairs into Q′, the panels while the final sphere optimization
//! runs (Sec. 5.2), then the panels, support structure and node axes; the energy of every term
//! on every iteration; the files and the summary (method "sq").
//!
//! When the mean curvature changes sign (Sec. 6.3), the stage sends H at the reference's
//! vertices (snapshot [`REFUSED_STAGE`]) before its error, so the app can show where.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::StageError;
use crate::congruence::central_spheres::JetParams;
use crate::export::congruence::{congruence_glb, CongruenceJson, CongruenceSegments};
use crate::export::report::{InputCounts, OutputCounts};
use crate::export::{write_mesh_obj, ExportFile, Metrics, Report};
use crate::geometry::mesh::PolyMesh;
use crate::geometry::sphere::Sphere;
use crate::panels::build_live_panels;
use crate::panels::edge_arcs::EdgeArcs;
use crate::panels::sphere_mesh::{BoundaryArcRule, SphereMesh};
use crate::pipeline::fields::{field, Energy, Field};
use crate::pipeline::panel_output::{
    export_panels, f32s, panel_fields, support_fields, PanelExport,
};
use crate::pipeline::sink::{report, Sink};
use crate::progress::{ignore, Clock, Progress};
use crate::reference::Reference;
use crate::solver::TermStats;
use crate::sq::metrics::CongruenceFigures;
use crate::sq::params::{SqParams, Until};
use crate::sq::segments::{grid_spacing, line_segments, LINE_LENGTH};
use crate::sq::sq_mesh::SqMeshFigures;
use crate::sq::{compute, SqCongruence, SqError, SqEvent, SqResult};
use crate::stats::mean;

/// Stage name of the method in the worker protocol (the design link's `method=sq`).
pub const STAGE: &str = "sq";
/// Snapshot of H at the reference vertices, sent when SQ refuses the surface (Sec. 6.3).
pub const REFUSED_STAGE: &str = "sq.refused";
/// Least time between two live snapshots (ms); every iteration still sends its energies.
pub const SNAPSHOT_INTERVAL_MS: f64 = 100.0;
/// Chord tolerance of the live panels, relative to the diagonal (coarser than the export's).
pub const LIVE_PANEL_TOLERANCE: f64 = 2e-3;

/// What the UI shows after the run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SqSummary {
    pub report: Report,
    /// Of the central congruence of the fitted r, and of the optimized one.
    pub initial: CongruenceFigures,
    pub figures: CongruenceFigures,
    /// How exact the SQ mesh is, when the run got there.
    #[serde(default)]
    pub mesh: Option<SqMeshFigures>,
}

/// The energies of an iteration: the total first, then every term (with `switched_on_only`,
/// the terms of nonzero weight: the final optimization's phases use different subsets of one
/// problem's terms).
fn energies(terms: &[TermStats], switched_on_only: bool) -> Vec<Energy> {
    let on = |t: &&TermStats| !switched_on_only || t.weight > 0.0;
    let total: f64 = terms.iter().filter(on).map(|t| t.energy).sum();
    let mut out = vec![Energy {
        name: "total".into(),
        value: total,
    }];
    out.extend(terms.iter().filter(on).map(|t| Energy {
        name: t.name.clone(),
        value: t.energy,
    }));
    out
}

/// The edges of a mesh of polygons as point pairs.
pub fn mesh_edge_segments(mesh: &PolyMesh) -> Vec<(DVec3, DVec3)> {
    crate::geometry::mesh::topology::Topology::new(mesh)
        .edges()
        .iter()
        .map(|&[a, b]| (mesh.positions[a as usize], mesh.positions[b as usize]))
        .collect()
}

/// Runs the method on `reference`, streaming every stage to `sink`; returns the summary after
/// sending the display fields and the files.
pub fn run(
    reference: &Reference,
    params: &SqParams,
    clock: Clock,
    sink: &mut dyn Sink,
) -> Result<SqSummary, StageError> {
    let start_ms = sink.now_ms();
    let diag = reference.diagonal();
    let mut last_snapshot = f64::NEG_INFINITY;
    let (mut points, mut length) = (Vec::new(), 0.0);
    let mut faces: Vec<crate::geometry::mesh::Face> = Vec::new();
    // One count across the stages: iterations done, and at most how many there will be.
    let [warm, full, projection] = params.sphere_iterations;
    let later = match params.until {
        Until::Congruence => 0,
        Until::Remesh => params.fairing_iterations + 1,
        Until::Final => params.fairing_iterations + 1 + warm + full + 2 * projection + 1,
    };
    let mut planned = params.lc_iterations + params.torsal_iterations + later;
    let mut done = 0usize;
    let mut lc_done = 0usize;
    // Iterations of earlier starts of the congruence (a restart from constant radii).
    let mut base = 0usize;
    // The first live snapshot of Q′ and of the panels goes out at once, later ones when due.
    let (mut first_fairing, mut first_spheres) = (true, true);
    let mut on_event = |e: SqEvent| -> Result<(), crate::progress::Cancelled> {
        let mut due = |sink: &mut dyn Sink| {
            let now = sink.now_ms();
            let due = now - last_snapshot >= SNAPSHOT_INTERVAL_MS;
            if due {
                last_snapshot = now;
            }
            due
        };
        match e {
            SqEvent::Progress(p) => report(
                sink,
                STAGE,
                Progress::new(p.step, done.min(planned), planned),
                Vec::new(),
                start_ms,
            ),
            SqEvent::Started { points: p, lines } => {
                points = p.to_vec();
                length = LINE_LENGTH * grid_spacing(params.grid, &points);
                let initial = line_segments(&points, lines, length);
                sink.snapshot(
                    STAGE,
                    0,
                    vec![
                        segments_field(field::SQ_INITIAL_LINES, &initial),
                        segments_field(field::SQ_LINES, &initial),
                    ],
                );
                last_snapshot = sink.now_ms();
                report(
                    sink,
                    STAGE,
                    Progress::new("line_congruence", 0, planned),
                    Vec::new(),
                    start_ms,
                )
            }
            SqEvent::Iteration {
                step,
                iteration,
                terms,
                lines,
            } => {
                // Step 1 may converge early: the count goes on from where it stopped.
                if step == crate::sq::optimization::SqStep::LineCongruence {
                    lc_done = base + iteration;
                    done = lc_done;
                } else {
                    planned = lc_done + params.torsal_iterations + later;
                    done = lc_done + iteration;
                }
                let go = report(
                    sink,
                    STAGE,
                    Progress::new(step.key(), done, planned),
                    energies(terms, false),
                    start_ms,
                );
                if go.is_ok() && due(sink) {
                    sink.snapshot(
                        STAGE,
                        done as u32,
                        vec![segments_field(
                            field::SQ_LINES,
                            &line_segments(&points, &lines, length),
                        )],
                    );
                }
                go
            }
            SqEvent::Restarted { start, lines } => {
                base = done;
                planned = done + params.lc_iterations + params.torsal_iterations + later;
                sink.snapshot(
                    STAGE,
                    done as u32,
                    vec![segments_field(
                        field::SQ_LINES,
                        &line_segments(&points, lines, length),
                    )],
                );
                report(
                    sink,
                    STAGE,
                    Progress::new(start.key(), done, planned),
                    Vec::new(),
                    start_ms,
                )
            }
            SqEvent::Congruence(c) => {
                done = lc_done + c.torsal_iterations;
                planned = done + later;
                sink.snapshot(
                    STAGE,
                    done as u32,
                    display_fields(&CongruenceSegments::of(c)),
                );
                report(
                    sink,
                    STAGE,
                    Progress::new("cross_field", done, planned),
                    Vec::new(),
                    start_ms,
                )
            }
            SqEvent::Remeshed { mesh } => {
                faces = mesh.faces.clone();
                sink.snapshot(
                    STAGE,
                    done as u32,
                    vec![segments_field(
                        field::SQ_QUAD_MESH,
                        &mesh_edge_segments(mesh),
                    )],
                );
                Ok(())
            }
            SqEvent::Fairing {
                iteration,
                terms,
                positions,
            } => {
                done += 1;
                let go = report(
                    sink,
                    STAGE,
                    Progress::new("fairing", done, planned),
                    energies(terms, false),
                    start_ms,
                );
                if go.is_ok()
                    && (std::mem::take(&mut first_fairing) | due(sink))
                    && !faces.is_empty()
                {
                    let mesh = PolyMesh::new(positions.to_vec(), faces.clone());
                    sink.snapshot(
                        STAGE,
                        iteration as u32,
                        vec![segments_field(
                            field::SQ_QUAD_MESH,
                            &mesh_edge_segments(&mesh),
                        )],
                    );
                }
                go
            }
            SqEvent::QuadMesh(q) => {
                faces = q.mesh.faces.clone();
                done += 1;
                sink.snapshot(
                    STAGE,
                    done as u32,
                    vec![segments_field(
                        field::SQ_QUAD_MESH,
                        &mesh_edge_segments(&q.mesh),
                    )],
                );
                report(
                    sink,
                    STAGE,
                    Progress::new("quad_mesh", done, planned),
                    Vec::new(),
                    start_ms,
                )
            }
            SqEvent::Spheres {
                phase,
                terms,
                positions,
                spheres,
                ..
            } => {
                done += 1;
                let go = report(
                    sink,
                    STAGE,
                    Progress::new(phase.key(), done.min(planned), planned),
                    energies(terms, true),
                    start_ms,
                );
                if go.is_ok() && (std::mem::take(&mut first_spheres) | due(sink)) {
                    sink.snapshot(
                        STAGE,
                        done as u32,
                        live_panels(positions, &faces, spheres, diag),
                    );
                }
                go
            }
        }
    };
    let result = match compute(reference, params, clock, &mut on_event) {
        Ok(r) => r,
        Err(
            e @ (SqError::MeanCurvatureSignChange { .. } | SqError::MeanCurvatureNearZero { .. }),
        ) => {
            // Exact H at the vertices of a B-spline reference (cached for the app's colour map).
            if let Ok(c) = reference.curvature(&JetParams::default(), &mut ignore) {
                let h = c.vertices.iter().map(|v| v.mean as f32).collect();
                sink.snapshot(
                    REFUSED_STAGE,
                    0,
                    vec![Field::f32(field::MEAN_CURVATURE, 1, h)],
                );
            }
            return Err(e.into());
        }
        Err(e) => return Err(e.into()),
    };
    let segments = CongruenceSegments::of(&result.congruence);
    let (report, files) = export(reference, &result, params, &segments, clock);
    let mut fields = display_fields(&segments);
    if let Some(q) = &result.quad_mesh {
        let mesh = result
            .sq_mesh
            .as_ref()
            .map_or(&q.mesh, |f| &f.mesh.sphere_mesh.mesh);
        fields.push(segments_field(
            field::SQ_QUAD_MESH,
            &mesh_edge_segments(mesh),
        ));
    }
    if let Some(f) = &result.sq_mesh {
        fields.extend(panel_fields(&f.mesh.panels));
        fields.extend(support_fields(
            &f.mesh.support_geometry,
            &f.mesh.node_axis_segments(),
        ));
    }
    sink.snapshot(STAGE, planned as u32, fields);
    sink.files(STAGE, files);
    let c = &result.congruence;
    Ok(SqSummary {
        report,
        initial: c.initial_figures.clone(),
        figures: c.figures.clone(),
        mesh: result.sq_mesh.as_ref().map(|f| f.mesh.figures),
    })
}

/// Panels of the current spheres, coarsely tessellated, for the live view.
fn live_panels(
    positions: &[DVec3],
    faces: &[crate::geometry::mesh::Face],
    spheres: &[Sphere],
    diag: f64,
) -> Vec<Field> {
    if faces.is_empty() || faces.len() != spheres.len() {
        return Vec::new();
    }
    let sm = SphereMesh::new(
        PolyMesh::new(positions.to_vec(), faces.to_vec()),
        spheres.to_vec(),
        BoundaryArcRule::Parallel(DVec3::ZERO),
    );
    let mut fields = panel_fields(&build_live_panels(
        &sm,
        LIVE_PANEL_TOLERANCE * diag,
        EdgeArcs::Intersection,
    ));
    fields.push(segments_field(
        field::SQ_QUAD_MESH,
        &mesh_edge_segments(&sm.mesh),
    ));
    fields
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
        Field::f32(
            field::SQ_CROSS_FIELD_ANGLE,
            1,
            s.cross_field_angle_deg.iter().map(|&a| a as f32).collect(),
        ),
        segments_field(field::SQ_NO_REAL_QUADS, &s.no_real_quads),
    ]
}

/// The report (method "sq") of the congruence part of a run.
pub fn sq_report(reference: &Reference, result: &SqCongruence, params: &SqParams) -> Report {
    let (f, i) = (&result.figures, &result.initial_figures);
    let mut report = Report::new(STAGE);
    let mesh = reference.mesh();
    report.input = InputCounts {
        vertices: mesh.positions.len(),
        faces: reference.surface().face_count(),
    };
    report.output = OutputCounts {
        vertices: result.points.len(),
        faces: result.torsal.len(),
        panels: 0,
    };
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
    report.add_timing(
        "lc_iteration_median",
        result.lc_iteration_median_ms().unwrap_or(0.0),
    );
    report.add_timing(
        "torsal_iteration_median",
        result.torsal_iteration_median_ms().unwrap_or(0.0),
    );
    report.iterations = Some(result.lc_iterations + result.torsal_iterations);
    report.grid = Some(result.grid);
    report.theta_deg = Some(params.theta_deg);
    report.alpha_deg = Some(params.alpha_deg);
    report.radius_basis = Some(result.radius_basis);
    report.stopped_after = Some(params.until.key().into());
    report.warnings = result.warnings.iter().map(ToString::to_string).collect();
    report
}

/// The report and the files: `congruence.json`, `congruence.glb`; with the quad mesh
/// `mesh.obj` (Q′, or the SQ mesh's vertices and quads); with the SQ mesh `panels.glb`,
/// `panels.obj`, the schedule (`panels.csv`, `panels.json`, `support.csv`); and `report.json`.
pub fn export(
    reference: &Reference,
    result: &SqResult,
    params: &SqParams,
    segments: &CongruenceSegments,
    clock: Clock,
) -> (Report, Vec<ExportFile>) {
    let c = &result.congruence;
    let mut report = sq_report(reference, c, params);
    let ((u0, u1), (v0, v1)) = reference
        .spline()
        .map_or(((0.0, 1.0), (0.0, 1.0)), |s| s.domain());
    let json = CongruenceJson::of(c, params.theta_deg, params.alpha_deg, [[u0, u1], [v0, v1]]);
    let extras = serde_json::json!({
        "method": STAGE,
        "theta_deg": params.theta_deg,
        "alpha_deg": params.alpha_deg,
        "grid": c.grid,
        "metrics": &report.metrics,
    });
    let file = |name: &str, mime: &str, bytes: Vec<u8>| ExportFile {
        name: name.into(),
        mime: mime.into(),
        bytes,
    };
    let mut files = vec![
        file(
            "congruence.glb",
            "model/gltf-binary",
            congruence_glb(reference.mesh(), segments, extras),
        ),
        file(
            "congruence.json",
            "application/json",
            json.to_json().into_bytes(),
        ),
    ];
    for (step, ms) in &result.timings_ms {
        report.add_timing(step.clone(), *ms);
    }
    report.warnings = result.warnings.iter().map(ToString::to_string).collect();
    if let Some(q) = &result.quad_mesh {
        let m = &mut report.metrics;
        m.coverage = Some(q.coverage);
        let angles = result
            .sq_mesh
            .as_ref()
            .map_or(&q.edge_angles_deg, |f| &f.edge_angles_deg);
        m.mean_edge_torsal_angle_deg = Some(mean(angles));
        m.max_edge_torsal_angle_deg = Some(angles.iter().copied().fold(0.0, f64::max));
        let mesh = result
            .sq_mesh
            .as_ref()
            .map_or(&q.mesh, |f| &f.mesh.sphere_mesh.mesh);
        report.output = OutputCounts {
            vertices: mesh.vertex_count(),
            faces: mesh.face_count(),
            panels: 0,
        };
        files.push(file(
            "mesh.obj",
            "text/plain",
            write_mesh_obj(mesh, "sq_mesh").into_bytes(),
        ));
    }
    if let Some(f) = &result.sq_mesh {
        let g = &f.mesh.figures;
        let m = &mut report.metrics;
        m.congruence_min_torsal_plane_angle_deg = m.min_torsal_plane_angle_deg;
        m.max_vertex_sphere_residual = Some(g.max_vertex_sphere_residual);
        m.max_centre_face_planarity = Some(g.max_centre_face_planarity);
        m.max_torsal_plane_residual = Some(g.max_torsal_plane_residual);
        m.max_axis_normal_angle_deg = Some(g.max_axis_normal_angle_deg);
        m.mean_axis_normal_angle_deg = Some(g.mean_axis_normal_angle_deg);
        m.min_torsal_plane_angle_deg = Some(g.min_torsal_plane_angle_deg);
        m.max_vertex_distance_to_reference = Some(g.max_vertex_distance_to_reference);
        m.axes_from_spheres = Some(g.axes_from_spheres);
        let o = &f.outcome;
        m.final_iterations = Some([o.warm_up_iterations, o.iterations, o.projection_iterations]);
        report.add_timing(
            "final_iteration_median",
            result.final_iteration_median_ms().unwrap_or(0.0),
        );
        let axes = f.mesh.node_axis_segments();
        let timings: Vec<(String, f64)> = report
            .timings_ms
            .iter()
            .map(|(k, v)| (k.clone(), *v))
            .collect();
        let export = PanelExport::new(STAGE, &f.mesh.sphere_mesh, &f.mesh.panels, reference.diagonal(), params.radius_tolerance, report.metrics.clone(), &timings)
            .with_extras(serde_json::json!({ "theta_deg": params.theta_deg, "alpha_deg": params.alpha_deg, "faces": f.mesh.panels.len() }))
            .with_support(&f.mesh.support_geometry, &f.mesh.support_elements, &axes);
        let (panel_report, panel_files) = export_panels(reference, export, clock);
        report.metrics = panel_report.metrics;
        report.output = panel_report.output;
        report.timings_ms = panel_report.timings_ms;
        files.extend(panel_files.into_iter().filter(|f| f.name != "report.json"));
    }
    let total: f64 = c
        .timings_ms
        .iter()
        .chain(&result.timings_ms)
        .map(|(_, ms)| ms)
        .sum();
    report.timings_ms.insert("total".into(), total);
    // Every solver iteration of the run: the congruence's, Q′'s and the final optimization's.
    let fairing = result
        .quad_mesh
        .as_ref()
        .map_or(0, |q| q.fairing_iterations);
    let spheres = result.sq_mesh.as_ref().map_or(0, |f| {
        f.outcome.warm_up_iterations + f.outcome.iterations + f.outcome.projection_iterations
    });
    report.iterations = Some(c.lc_iterations + c.torsal_iterations + fairing + spheres);
    report.set_verdict(&result.verdict);
    files.push(file(
        "report.json",
        "application/json",
        report.to_json().into_bytes(),
    ));
    (report, files)
}
