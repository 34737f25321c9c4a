//! The stage of SQ meshes with support structure (Sec. 5): runs [`crate::sq::compute`] as far as
//! the parameters' `until` asks and streams every stage live, with one progress count across
//! them: the lines of the congruence while they optimize (Sec. 5.1), the cross field, the quad
//! mesh as remeshed and while it fairs into Q′, the panels while the final sphere optimization
//! runs (Sec. 5.2), then the panels, support structure and node axes; the energy of every term
//! on every iteration; the files and the summary (method "sq").
//!
//! When the mean curvature changes sign (Sec. 6.3), the stage sends H at the reference's
//! vertices (snapshot part [`Part::Refused`]) before its error, so the app can show where.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::StageError;
use crate::congruence::central_spheres::JetParams;
use crate::export::glb::{write_lines_glb, LineSet};
use crate::export::report::{InputCounts, OutputCounts};
use crate::export::{report_file, write_mesh_obj, ExportFile, Report};
use crate::geometry::mesh::PolyMesh;
use crate::geometry::mesh::TriMesh;
use crate::geometry::sphere::Sphere;
use crate::panels::build_live_panels;
use crate::panels::edge_arcs::EdgeArcs;
use crate::panels::moulds::MouldAssignment;
use crate::panels::sphere_mesh::{BoundaryArcRule, SphereMesh};
use crate::pipeline::fields::{field, Energy, Field, Part};
use crate::pipeline::method::{Computed, Exported, Method, Request};
use crate::pipeline::panel_output::{export_panels, f32s, panel_fields, result_panel_fields, support_fields, with_moulds, PanelExport, Snapping};
use crate::pipeline::sink::{report, Sink};
use crate::progress::{ignore, Cancelled, Clock, Progress};
use crate::reference::Reference;
use crate::solver::TermStats;
use crate::sq::congruence_file::{CongruenceJson, CongruenceSegments};
use crate::sq::params::{SqParams, Until};
use crate::sq::report::SqSection;
use crate::sq::segments::{grid_spacing, line_segments, LINE_LENGTH};
use crate::sq::{compute, SqError, SqEvent, SqResult};

/// Least time between two live snapshots (ms); every iteration still sends its energies.
pub(crate) const SNAPSHOT_INTERVAL_MS: f64 = 100.0;
/// Chord tolerance of the live panels, relative to the diagonal (coarser than the export's).
pub(crate) const LIVE_PANEL_TOLERANCE: f64 = 2e-3;

/// The method in the pipeline.
pub struct SqStage;

/// What the UI shows after the run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SqSummary {
    pub report: Report,
}

impl SqSummary {
    /// The report's section, typed: the congruence's figures, the quad mesh's and the SQ mesh's
    /// where the run got there.
    pub fn section(&self) -> Option<SqSection> {
        self.report.section()
    }
}

/// The energies of an iteration: the total first, then every term (with `switched_on_only`,
/// the terms of nonzero weight: the final optimization's phases use different subsets of one
/// problem's terms).
fn energies(terms: &[TermStats], switched_on_only: bool) -> Vec<Energy> {
    let on = |t: &&TermStats| !switched_on_only || t.weight > 0.0;
    let total: f64 = terms.iter().filter(on).map(|t| t.energy).sum();
    let mut out = vec![Energy { name: "total".into(), value: total }];
    out.extend(terms.iter().filter(on).map(|t| Energy { name: t.name.clone(), value: t.energy }));
    out
}

/// The edges of a mesh of polygons as point pairs.
pub(crate) fn mesh_edge_segments(mesh: &PolyMesh) -> Vec<(DVec3, DVec3)> {
    crate::geometry::mesh::topology::Topology::new(mesh)
        .edges()
        .iter()
        .map(|&[a, b]| (mesh.positions[a as usize], mesh.positions[b as usize]))
        .collect()
}

impl Method for SqStage {
    const KEY: &'static str = "sq";
    const LABEL: &'static str = "SQ with support structure (Sec. 5)";
    type Params = SqParams;
    type Result = SqResult;
    type Summary = SqSummary;

    fn optimizes_moulds(params: &SqParams) -> bool {
        params.optimize_moulds
    }

    /// When the mean curvature changes sign (Sec. 6.3), sends H at the reference's vertices
    /// ([`Part::Refused`]) before its error, so the app can show where.
    fn compute(reference: &Reference, request: &Request<SqParams>, clock: Clock, sink: &mut dyn Sink) -> Result<Computed<SqResult>, StageError> {
        let params = &request.params;
        let mut stream = Stream::new(sink, params, reference.diagonal());
        let mut on_event = |e: SqEvent| stream.event(e);
        match compute(reference, params, &request.fabrication, clock, &mut on_event) {
            Ok(result) => Ok(Computed { result, iteration: stream.planned as u32 }),
            Err(e @ (SqError::MeanCurvatureSignChange { .. } | SqError::MeanCurvatureNearZero { .. })) => {
                // Exact H at the vertices of a B-spline reference (cached for the app's colour map).
                if let Ok(c) = reference.curvature(&JetParams::default(), &mut ignore) {
                    let h = c.vertices.iter().map(|v| v.mean as f32).collect();
                    stream.sink.snapshot(Part::Refused, 0, vec![Field::f32(field::MEAN_CURVATURE, 1, h)]);
                }
                Err(e.into())
            }
            Err(e) => Err(e.into()),
        }
    }

    /// The report (method "sq", its section [`SqSection`]) and the files: `congruence.json`,
    /// `congruence.glb`; with the quad mesh `mesh.obj` (Q′, or the SQ mesh's vertices and
    /// quads); with the SQ mesh `panels.glb`, `panels.obj`, the schedule (`panels.csv`,
    /// `panels.json`, `support.csv`); and `report.json`. The display: the congruence, the quad
    /// mesh, the panels in their moulds' colours, the support structure.
    fn export(reference: &Reference, result: &SqResult, request: &Request<SqParams>, clock: Clock) -> Exported {
        let segments = CongruenceSegments::of(&result.congruence);
        let (report, files, moulds) = exported(reference, result, request, &segments, clock);
        Exported { report, files, moulds }
    }

    fn display(result: &SqResult, moulds: Option<&MouldAssignment>) -> Vec<Field> {
        let mut display = display_fields(&CongruenceSegments::of(&result.congruence));
        if let Some(q) = &result.quad_mesh {
            let mesh = result.sq_mesh.as_ref().map_or(&q.mesh, |f| &f.mesh.sphere_mesh.mesh);
            display.push(segments_field(field::SQ_QUAD_MESH, &mesh_edge_segments(mesh)));
        }
        if let (Some(f), Some(moulds)) = (&result.sq_mesh, moulds) {
            display.extend(result_panel_fields(&f.mesh.panels, moulds));
            display.extend(support_fields(&f.mesh.support.geometry, &f.mesh.support.axis_segments()));
        }
        display
    }

    fn summary(_result: &SqResult, report: Report) -> SqSummary {
        SqSummary { report }
    }

    fn report(summary: &SqSummary) -> &Report {
        &summary.report
    }

    fn report_mut(summary: &mut SqSummary) -> &mut Report {
        &mut summary.report
    }

    fn describe(_result: &SqResult, report: &Report, request: &Request<SqParams>, out: &str) -> String {
        let line = describe(report, &request.params, out);
        let sq: SqSection = report.section().expect("the SQ report has its section");
        match sq.sq_mesh.as_ref().and_then(|m| m.moulds.refused()) {
            Some(why) => format!("{}; {why}", with_moulds(line, report)),
            None => with_moulds(line, report),
        }
    }
}

/// What the command line says of a run (as far as its `until`) that wrote its files to `out`.
fn describe(report: &Report, params: &SqParams, out: &str) -> String {
    let sq: SqSection = report.section().expect("the SQ report has its section");
    let panels = report.metrics.clone().unwrap_or_default();
    let quads = sq.quad_mesh.as_ref();
    match (params.until, &sq.sq_mesh) {
        (Until::Final, Some(mesh)) => {
            let f = &mesh.figures;
            format!(
                "wrote an SQ mesh of {} spherical quad panels with support structure to {}: vertex–sphere residual {:.1e}, centre-face \
                 planarity {:.1e}, torsal-plane residual {:.1e}; node axes within {:.2}° of the normals (θ = {}°); support planes meet at \
                 ≥ {:.2}° (α = {}°); max distance to the reference {}; edges off the torsal directions by {:.2}° on \
                 average; {} distinct radii; {:.0} ms.",
                report.output.panels,
                out,
                f.max_vertex_sphere_residual,
                f.max_centre_face_planarity,
                f.max_torsal_plane_residual,
                f.max_axis_normal_angle_deg,
                params.theta_deg,
                f.min_torsal_plane_angle_deg,
                params.alpha_deg,
                panels.max_distance_text(),
                quads.map_or(f64::NAN, |q| q.mean_edge_torsal_angle_deg),
                panels.distinct_radii,
                report.timings_ms.get("total").copied().unwrap_or(0.0),
            )
        }
        (Until::Final | Until::Remesh, _) => format!(
            "wrote the quad mesh Q′ ({} quads, {:.1} % of the patch, edges off the torsal directions by {:.2}° on average, at most {:.2}°) \
             and the congruence to {}.",
            report.output.faces,
            100.0 * quads.map_or(f64::NAN, |q| q.coverage),
            quads.map_or(f64::NAN, |q| q.mean_edge_torsal_angle_deg),
            quads.map_or(f64::NAN, |q| q.max_edge_torsal_angle_deg),
            out
        ),
        (Until::Congruence, _) => {
            let c = &sq.congruence;
            format!(
                "wrote the congruence of a {n}×{n} grid to {} (lines within {:.2}° of the normals, θ = {}°; torsal planes meet at ≥ {:.2}°, \
                 α = {}°; {} quads without real torsal directions; E_LC per term {:.2e}).",
                out,
                c.figures.max_line_normal_angle_deg,
                params.theta_deg,
                c.figures.min_torsal_plane_angle_deg,
                params.alpha_deg,
                c.figures.quads_without_real_torsal_directions,
                c.lc_residual,
                n = params.grid,
            )
        }
    }
}

/// What the stage streams while the method runs, with one progress count across its steps:
/// iterations done and at most how many there will be.
struct Stream<'a> {
    sink: &'a mut dyn Sink,
    params: &'a SqParams,
    start_ms: f64,
    diag: f64,
    last_snapshot: f64,
    /// The grid's points and the length the lines are drawn at.
    points: Vec<DVec3>,
    length: f64,
    /// The quad mesh's faces, for Q′ and the live panels.
    faces: Vec<crate::geometry::mesh::Face>,
    planned: usize,
    done: usize,
    lc_done: usize,
    /// Iterations of earlier starts of the congruence (a restart from constant radii).
    base: usize,
    /// Iterations after the congruence.
    later: usize,
    /// The first live snapshot of Q′ and of the panels goes out at once, later ones when due.
    first_fairing: bool,
    first_spheres: bool,
    /// Whether the sink wants live snapshots.
    live: bool,
}

impl<'a> Stream<'a> {
    fn new(sink: &'a mut dyn Sink, params: &'a SqParams, diag: f64) -> Self {
        let live = sink.wants_snapshots();
        let [warm, full, projection] = params.sphere_iterations;
        let later = match params.until {
            Until::Congruence => 0,
            Until::Remesh => params.fairing_iterations + 1,
            Until::Final => params.fairing_iterations + 1 + warm + full + 2 * projection + 1,
        };
        Self {
            start_ms: sink.now_ms(),
            sink,
            params,
            diag,
            last_snapshot: f64::NEG_INFINITY,
            points: Vec::new(),
            length: 0.0,
            faces: Vec::new(),
            planned: params.lc_iterations + params.torsal_iterations + later,
            done: 0,
            lc_done: 0,
            base: 0,
            later,
            first_fairing: true,
            first_spheres: true,
            live,
        }
    }

    /// Whether a live snapshot is due.
    fn due(&mut self) -> bool {
        let now = self.sink.now_ms();
        let due = self.live && now - self.last_snapshot >= SNAPSHOT_INTERVAL_MS;
        if due {
            self.last_snapshot = now;
        }
        due
    }

    fn report(&mut self, step: &str, energies: Vec<Energy>) -> Result<(), Cancelled> {
        report(self.sink, Progress::new(step, self.done.min(self.planned), self.planned), energies, self.start_ms)
    }

    fn lines(&mut self, iteration: usize, name: &'static str, lines: &[DVec3]) {
        if !self.live {
            return;
        }
        self.sink.snapshot(Part::Main, iteration as u32, vec![segments_field(name, &line_segments(&self.points, lines, self.length))]);
    }

    fn quad_mesh(&mut self, iteration: usize, mesh: &PolyMesh) {
        if !self.live {
            return;
        }
        self.sink.snapshot(Part::Main, iteration as u32, vec![segments_field(field::SQ_QUAD_MESH, &mesh_edge_segments(mesh))]);
    }

    fn event(&mut self, e: SqEvent) -> Result<(), Cancelled> {
        match e {
            SqEvent::Progress(p) => self.report(p.step, Vec::new()),
            SqEvent::Started { points, lines } => {
                self.points = points.to_vec();
                self.length = LINE_LENGTH * grid_spacing(self.params.grid, &self.points);
                let initial = line_segments(&self.points, lines, self.length);
                self.sink.snapshot(Part::Main, 0, vec![segments_field(field::SQ_INITIAL_LINES, &initial), segments_field(field::SQ_LINES, &initial)]);
                self.last_snapshot = self.sink.now_ms();
                self.report("line_congruence", Vec::new())
            }
            SqEvent::Iteration { step, iteration, terms, lines } => {
                // Step 1 may converge early: the count goes on from where it stopped.
                if step == crate::sq::optimization::SqStep::LineCongruence {
                    self.lc_done = self.base + iteration;
                    self.done = self.lc_done;
                } else {
                    self.planned = self.lc_done + self.params.torsal_iterations + self.later;
                    self.done = self.lc_done + iteration;
                }
                let go = self.report(step.key(), energies(terms, false));
                if go.is_ok() && self.due() {
                    self.lines(self.done, field::SQ_LINES, &lines);
                }
                go
            }
            SqEvent::Restarted { start, lines } => {
                self.base = self.done;
                self.planned = self.done + self.params.lc_iterations + self.params.torsal_iterations + self.later;
                self.lines(self.done, field::SQ_LINES, lines);
                self.report(start.key(), Vec::new())
            }
            SqEvent::Congruence(c) => {
                self.done = self.lc_done + c.torsal_iterations;
                self.planned = self.done + self.later;
                if self.live {
                    self.sink.snapshot(Part::Main, self.done as u32, display_fields(&CongruenceSegments::of(c)));
                }
                self.report("cross_field", Vec::new())
            }
            SqEvent::Remeshed { mesh } => {
                self.faces = mesh.faces.clone();
                self.quad_mesh(self.done, mesh);
                Ok(())
            }
            SqEvent::Fairing { iteration, terms, positions } => {
                self.done += 1;
                let go = self.report("fairing", energies(terms, false));
                if go.is_ok() && (self.live && std::mem::take(&mut self.first_fairing) | self.due()) && !self.faces.is_empty() {
                    self.quad_mesh(iteration, &PolyMesh::new(positions.to_vec(), self.faces.clone()));
                }
                go
            }
            SqEvent::QuadMesh(q) => {
                self.faces = q.mesh.faces.clone();
                self.done += 1;
                self.quad_mesh(self.done, &q.mesh);
                self.report("quad_mesh", Vec::new())
            }
            SqEvent::Spheres { phase, terms, positions, spheres, .. } => {
                self.done += 1;
                let go = self.report(phase.key(), energies(terms, true));
                if go.is_ok() && (self.live && std::mem::take(&mut self.first_spheres) | self.due()) {
                    let fields = live_panels(positions, &self.faces, spheres, self.diag);
                    self.sink.snapshot(Part::Main, self.done as u32, fields);
                }
                go
            }
        }
    }
}

/// Panels of the current spheres, coarsely tessellated, for the live view.
fn live_panels(positions: &[DVec3], faces: &[crate::geometry::mesh::Face], spheres: &[Sphere], diag: f64) -> Vec<Field> {
    if faces.is_empty() || faces.len() != spheres.len() {
        return Vec::new();
    }
    let sm = SphereMesh::new(PolyMesh::new(positions.to_vec(), faces.to_vec()), spheres.to_vec(), BoundaryArcRule::Parallel(DVec3::ZERO));
    let mut fields = panel_fields(&build_live_panels(&sm, LIVE_PANEL_TOLERANCE * diag, EdgeArcs::Intersection));
    fields.push(segments_field(field::SQ_QUAD_MESH, &mesh_edge_segments(&sm.mesh)));
    fields
}

/// Segments as a field of point pairs.
fn segments_field(name: &str, segments: &[(glam::DVec3, glam::DVec3)]) -> Field {
    Field::f32(name, 3, f32s(segments.iter().flat_map(|&(a, b)| [a, b])))
}

/// Lines (initial and optimized), the cross field with its angles, and the quads without real
/// torsal directions.
pub(crate) fn display_fields(s: &CongruenceSegments) -> Vec<Field> {
    vec![
        segments_field(field::SQ_INITIAL_LINES, &s.initial_lines),
        segments_field(field::SQ_LINES, &s.lines),
        segments_field(field::SQ_CROSS_FIELD, &s.cross_field),
        Field::f32(field::SQ_CROSS_FIELD_ANGLE, 1, s.cross_field_angle_deg.iter().map(|&a| a as f32).collect()),
        segments_field(field::SQ_NO_REAL_QUADS, &s.no_real_quads),
    ]
}

/// The report (with the run's verdict, [`SqResult::verdict_in`]), the files and the panels'
/// moulds (when there are panels).
fn exported(
    reference: &Reference,
    result: &SqResult,
    request: &Request<SqParams>,
    segments: &CongruenceSegments,
    clock: Clock,
) -> (Report, Vec<ExportFile>, Option<MouldAssignment>) {
    let params = &request.params;
    let verdict = result.verdict_in(params, request.fabrication.units);
    let c = &result.congruence;
    let section = SqSection::of(result, params);
    let ((u0, u1), (v0, v1)) = reference.spline().map_or(((0.0, 1.0), (0.0, 1.0)), |s| s.domain());
    let json = CongruenceJson::of(c, params.theta_deg, params.alpha_deg, [[u0, u1], [v0, v1]]);
    let extras = serde_json::json!({
        "method": SqStage::KEY,
        "theta_deg": params.theta_deg,
        "alpha_deg": params.alpha_deg,
        "grid": c.grid,
        "congruence": &section.congruence,
    });
    let mut files = vec![
        ExportFile::new("congruence.glb", "model/gltf-binary", congruence_glb(reference.mesh(), segments, extras)),
        ExportFile::new("congruence.json", "application/json", json.to_json().into_bytes()),
    ];
    let mut timings = c.timings_ms.clone();
    timings.push(("lc_iteration_median".into(), c.lc_iteration_median_ms().unwrap_or(0.0)));
    timings.push(("torsal_iteration_median".into(), c.torsal_iteration_median_ms().unwrap_or(0.0)));
    timings.extend(result.timings_ms.iter().cloned());
    let mesh = result.quad_mesh.as_ref().map(|q| result.sq_mesh.as_ref().map_or(&q.mesh, |f| &f.mesh.sphere_mesh.mesh));
    if let Some(mesh) = mesh {
        files.push(ExportFile::new("mesh.obj", "text/plain", write_mesh_obj(mesh, "sq_mesh").into_bytes()));
    }
    let mut moulds = None;
    let mut report = match &result.sq_mesh {
        Some(f) => {
            timings.push(("final_iteration_median".into(), result.final_iteration_median_ms().unwrap_or(0.0)));
            let export = PanelExport::new(
                SqStage::KEY,
                &f.mesh.sphere_mesh,
                &f.mesh.panels,
                reference.diagonal(),
                params.radius_tolerance,
                request.fabrication,
                &section,
                &timings,
            )
            .with_extras(serde_json::json!({ "theta_deg": params.theta_deg, "alpha_deg": params.alpha_deg, "faces": f.mesh.panels.len() }))
            .with_support(&f.mesh.support)
            .with_verdict(&verdict)
            .with_exact_surfaces(&f.exact)
            .with_deviations(&f.buildability.panel_distances)
            .with_moulds_before(f.moulds.as_ref().map(|m| &m.fits_before))
            .with_snapping(Snapping::of(f.moulds.as_ref().map(|m| &m.snap)));
            let (report, panel_files, assigned) = export_panels(reference, export, clock);
            files.extend(panel_files);
            moulds = Some(assigned);
            report
        }
        None => {
            let mut report = Report::new(SqStage::KEY);
            report.set_section(&section);
            report.add_timings(&timings);
            report
        }
    };
    report.input = InputCounts { vertices: reference.mesh().positions.len(), faces: reference.surface().face_count() };
    report.output = match mesh {
        Some(m) => OutputCounts { vertices: m.vertex_count(), faces: m.face_count(), panels: report.output.panels },
        None => OutputCounts { vertices: c.points.len(), faces: c.torsal.len(), panels: 0 },
    };
    let total: f64 = c.timings_ms.iter().chain(&result.timings_ms).map(|(_, ms)| ms).sum();
    report.timings_ms.insert("total".into(), total);
    report.warnings = result.warnings.iter().map(ToString::to_string).collect();
    report.set_verdict(&verdict);
    files.push(report_file(&report));
    (report, files, moulds)
}

/// `congruence.glb` (see the module docs).
pub(crate) fn congruence_glb(surface: &TriMesh, segments: &CongruenceSegments, extras: serde_json::Value) -> Vec<u8> {
    let sets = [
        LineSet { name: "lines", color: [0.10, 0.35, 0.85, 1.0], segments: &segments.lines },
        LineSet { name: "initial_lines", color: [0.55, 0.55, 0.55, 1.0], segments: &segments.initial_lines },
        LineSet { name: "cross_field", color: [0.90, 0.45, 0.10, 1.0], segments: &segments.cross_field },
        LineSet { name: "quads_without_real_torsal_directions", color: [0.90, 0.10, 0.10, 1.0], segments: &segments.no_real_quads },
    ];
    write_lines_glb(surface, &sets, extras)
}

impl From<SqError> for StageError {
    fn from(e: SqError) -> Self {
        match e {
            SqError::Cancelled => StageError::Cancelled,
            e => StageError::refused(&e, None),
        }
    }
}
