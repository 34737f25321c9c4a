//! SQ meshes with support structure (Sec. 5): θ, α, the grid, the face count and the support
//! depth, RS, iterations and weights under "advanced"; one live energy plot per stage
//! (congruence, Q′, spheres), the figures of the congruence and of the SQ mesh, and what the
//! viewport shows (lines of Fig. 21, cross field of Fig. 23, quad mesh, panels, support
//! structure and node axes of Fig. 19, 25).

use std::sync::Arc;

use egui::{Color32, RichText};
use glam::Mat4;
use serde::Serialize;

use super::method_view::{Drawn, Frame, Legend, MethodView};
use crate::design_link::{Design, Method};
use crate::export::Report;
use crate::pipeline::fields::{field, find, Energy, Field, Part};
use crate::pipeline::protocol::{MethodId, MethodSummary, StageId, StageProgress, StageResult};
use crate::pipeline::stages::sq::SqStage;

/// The method's stage, and H at the vertices when it refuses the sign of H.
const STAGE: StageId = StageId::Method(MethodId::Sq, Part::Main);
const REFUSED_STAGE: StageId = StageId::Method(MethodId::Sq, Part::Refused);
use crate::congruence::support_structure::SUPPORT_DEPTH_RANGE;
use crate::sq::params::{
    RadiusStart, SqParams, Until, ALPHA_RANGE, FACES_RANGE, GRID_RANGE, ITERATIONS_RANGE, RADIUS_CONTROLS_RANGE, RADIUS_DEGREE_RANGE,
    RECOMPUTE_RANGE, THETA_RANGE, WEIGHT_RANGE,
};
use crate::sq::report::SqSection;
use crate::sq::sq_mesh::SqMeshFigures;
use crate::web::app::panels::moulds::{before_after, optimize_moulds_checkbox, MouldMeshes};
use crate::web::app::panels::{graded, max_distance_slider, warnings};
use crate::web::app::plots::{key_values, term_plot};
use crate::web::app::state::{mesh_from_fields, AXES_FIELDS, PANEL_FIELDS, SUPPORT_FIELDS};
use crate::web::colormap;
use crate::web::viewer::{ColorMap, Geometry, Layer, MeshData, ScalarData, Style};

/// The SQ run (Sec. 5) as it streams in: the lines of the central congruence, the lines as
/// they optimize, the energy of every term per iteration; when done, the torsal cross field by
/// angle bins, the quads without real torsal directions and the summary. On a refusal for the
/// sign of H, H at the reference vertices.
#[derive(Default)]
pub struct SqView {
    pub initial_lines: Option<Arc<MeshData>>,
    pub lines: Option<Arc<MeshData>>,
    pub line_iteration: u32,
    pub line_snapshots: u32,
    /// The cross field's arms, one mesh per angle bin ([`CROSS_FIELD_BINS`] over [lo, 90°]).
    pub cross_field: Vec<Arc<MeshData>>,
    pub cross_field_range: (f32, f32),
    pub cross_field_arms: usize,
    pub no_real_quads: Option<Arc<MeshData>>,
    /// Sec. 5.2: the quad mesh's edges (as remeshed, Q′, then the SQ mesh), the panels (live
    /// while the spheres optimize, then final), the support structure and the node axes.
    pub quad_mesh: Option<Arc<MeshData>>,
    pub panels: Option<Arc<MeshData>>,
    /// The final panels by mould.
    pub moulds: Option<MouldMeshes>,
    pub support: Option<Arc<MeshData>>,
    pub axes: Option<Arc<MeshData>>,
    /// (iteration, step, energy of every term and the total).
    pub energy: Vec<(u32, String, Vec<Energy>)>,
    /// H at the vertices when SQ refused its sign, and its diverging colour map's range.
    pub refused_h: Option<ColorMap>,
    pub summary: Option<SqFinished>,
}

/// Colour bins of the cross field by torsal-plane angle.
pub const CROSS_FIELD_BINS: usize = 6;

/// Line segments (point pairs) of field `name` as a display mesh of edges.
pub fn segments_mesh(fields: &[Field], name: &str, generation: &mut u64) -> Option<Arc<MeshData>> {
    Some(segment_mesh(find(fields, name).and_then(Field::as_f32)?.to_vec(), generation))
}

/// Point pairs as a display mesh of edges, with a fresh generation.
fn segment_mesh(positions: Vec<f32>, generation: &mut u64) -> Arc<MeshData> {
    *generation += 1;
    let edges = (0..(positions.len() / 3) as u32).collect();
    Arc::new(MeshData { generation: *generation, positions, normals: Vec::new(), triangles: Vec::new(), edges })
}

impl SqView {
    /// Takes what a snapshot of the stage carries (live snapshots carry the lines only).
    pub fn install(&mut self, fields: &[Field], iteration: u32, generation: &mut u64) {
        if let Some(m) = segments_mesh(fields, field::SQ_INITIAL_LINES, generation) {
            self.initial_lines = Some(m);
        }
        if let Some(m) = segments_mesh(fields, field::SQ_LINES, generation) {
            self.lines = Some(m);
            self.line_iteration = iteration;
            self.line_snapshots += 1;
        }
        if let Some(m) = segments_mesh(fields, field::SQ_NO_REAL_QUADS, generation) {
            self.no_real_quads = Some(m);
        }
        if let Some(m) = segments_mesh(fields, field::SQ_QUAD_MESH, generation) {
            self.quad_mesh = Some(m);
        }
        if find(fields, field::PANEL_POSITIONS).is_some() {
            self.panels = Some(mesh_from_fields(fields, generation, PANEL_FIELDS));
            self.moulds = MouldMeshes::from_fields(fields, generation);
        }
        if find(fields, field::SUPPORT_POSITIONS).is_some() {
            self.support = Some(mesh_from_fields(fields, generation, SUPPORT_FIELDS));
            self.axes = Some(mesh_from_fields(fields, generation, AXES_FIELDS));
        }
        let (Some(arms), Some(angles)) =
            (find(fields, field::SQ_CROSS_FIELD).and_then(Field::as_f32), find(fields, field::SQ_CROSS_FIELD_ANGLE).and_then(Field::as_f32))
        else {
            return;
        };
        let lo = angles.iter().copied().fold(90.0f32, f32::min).floor().min(89.0);
        let mut bins = vec![Vec::new(); CROSS_FIELD_BINS];
        for (k, &a) in angles.iter().enumerate() {
            let b = (((a - lo) / (90.0 - lo) * CROSS_FIELD_BINS as f32) as usize).min(CROSS_FIELD_BINS - 1);
            bins[b].extend_from_slice(&arms[6 * k..6 * k + 6]);
        }
        self.cross_field = bins.into_iter().map(|positions| segment_mesh(positions, generation)).collect();
        self.cross_field_range = (lo, 90.0);
        self.cross_field_arms = angles.len();
    }
}

/// A finished run: its report and the report's section, read once.
pub struct SqFinished {
    pub report: Report,
    pub section: SqSection,
}

/// The method's view: its run and what the viewport shows of it.
#[derive(Default)]
pub struct SqMethod {
    run: Option<SqView>,
    display: SqDisplay,
}

/// What the end-to-end tests read of a run.
#[derive(Serialize)]
struct Automation<'a> {
    line_snapshots: u32,
    line_iteration: u32,
    lines: usize,
    initial_lines: usize,
    cross_field_arms: usize,
    energies: usize,
    terms: Vec<String>,
    /// The progress steps that sent energies, in order of first appearance.
    energy_steps: Vec<String>,
    quad_mesh_edges: usize,
    panel_triangles: usize,
    support_triangles: usize,
    axes: usize,
    /// Panel meshes in mould colours (one per colour in use).
    mould_colours: usize,
    mesh: Option<SqMeshFigures>,
    refused: bool,
    ready: bool,
    report: Option<&'a Report>,
}

impl MethodView for SqMethod {
    fn method(&self) -> Method {
        Method::Of(MethodId::Sq)
    }
    fn name(&self) -> &'static str {
        "sq"
    }
    fn owns(&self, stage: StageId) -> bool {
        stage == STAGE || stage == REFUSED_STAGE
    }
    fn start(&mut self) {
        self.run = Some(SqView::default());
        // A new run shows its congruence again while it optimizes.
        let d = &mut self.display;
        (d.lines, d.cross_field, d.surface) = (true, true, true);
    }
    fn clear(&mut self) {
        self.run = None;
    }
    fn controls(&mut self, ui: &mut egui::Ui, design: &mut Design) -> bool {
        controls(ui, design.params_mut::<SqStage>(), &mut self.display)
    }
    fn results(&self, ui: &mut egui::Ui, _design: &Design) {
        if let Some(v) = &self.run {
            results(ui, v);
        }
    }
    fn snapshot(&mut self, stage: StageId, iteration: u32, fields: &[Field], generation: &mut u64) -> bool {
        let Some(v) = self.run.as_mut() else {
            return false;
        };
        if stage == REFUSED_STAGE {
            let values = find(fields, field::MEAN_CURVATURE).and_then(Field::as_f32).map(<[f32]>::to_vec).unwrap_or_default();
            *generation += 1;
            // A robust range, so that a few peaks do not wash the map out: the H = 0 curves show
            // between the blue and the red.
            let range = colormap::symmetric_range(&values);
            v.refused_h = Some(ColorMap { scalars: Arc::new(ScalarData { generation: *generation, values }), range, diverging: true });
        } else {
            v.install(fields, iteration, generation);
        }
        false
    }
    fn progress(&mut self, p: &StageProgress) {
        if let Some(v) = self.run.as_mut().filter(|_| p.stage == STAGE && !p.energies.is_empty()) {
            v.energy.push((p.iteration, p.detail.clone(), p.energies.clone()));
        }
    }
    fn finished(&mut self, result: StageResult) -> Option<Report> {
        let (StageResult::Method(MethodSummary::Sq(summary)), Some(v)) = (result, self.run.as_mut()) else {
            return None;
        };
        let section = summary.section()?;
        // With the SQ mesh done, the panels take the stage: the congruence and the reference step
        // back (each can be switched on again).
        if section.sq_mesh.is_some() {
            let d = &mut self.display;
            (d.lines, d.cross_field, d.surface) = (false, false, false);
        }
        v.summary = Some(SqFinished { report: summary.report.clone(), section });
        Some(summary.report)
    }
    fn draw(&self, frame: &Frame) -> Drawn {
        let Some(v) = &self.run else {
            return Drawn::reference_only();
        };
        // Refused for the sign of H (Sec. 6.3): the surface shows where H > 0 and H < 0.
        let refused_h = v.refused_h.clone();
        let legend = match &refused_h {
            Some(cm) => Some(Legend::Scale { title: "H (SQ needs one sign)", range: cm.range, diverging: true }),
            None if self.display.cross_field && v.cross_field_arms > 0 => {
                Some(Legend::Bins { title: "torsal-plane angle (°)", range: v.cross_field_range, bins: CROSS_FIELD_BINS })
            }
            None => None,
        };
        Drawn {
            layers: self.layers(v, frame),
            reference: self.display.surface || refused_h.is_some(),
            // The cross field has the legend; the surface shows H only to explain a refusal.
            reference_colors: Some(refused_h),
            legend,
        }
    }
    fn automation(&self) -> serde_json::Value {
        let state = self.run.as_ref().map(|v| Automation {
            line_snapshots: v.line_snapshots,
            line_iteration: v.line_iteration,
            lines: v.lines.as_ref().map_or(0, |m| m.edges.len() / 2),
            initial_lines: v.initial_lines.as_ref().map_or(0, |m| m.edges.len() / 2),
            cross_field_arms: v.cross_field_arms,
            energies: v.energy.len(),
            terms: v.energy.last().map(|(_, _, e)| e.iter().map(|e| e.name.clone()).collect()).unwrap_or_default(),
            energy_steps: v.energy.iter().fold(Vec::new(), |mut acc, (_, step, _)| {
                if !acc.contains(step) {
                    acc.push(step.clone());
                }
                acc
            }),
            quad_mesh_edges: v.quad_mesh.as_ref().map_or(0, |m| m.edges.len() / 2),
            panel_triangles: v.panels.as_ref().map_or(0, |m| m.triangles.len() / 3),
            support_triangles: v.support.as_ref().map_or(0, |m| m.triangles.len() / 3),
            axes: v.axes.as_ref().map_or(0, |m| m.edges.len() / 2),
            mould_colours: v.moulds.as_ref().map_or(0, MouldMeshes::colours),
            mesh: v.summary.as_ref().and_then(|s| s.section.sq_mesh.as_ref().map(|m| m.figures)),
            refused: v.refused_h.is_some(),
            ready: v.summary.is_some(),
            report: v.summary.as_ref().map(|s| &s.report),
        });
        serde_json::to_value(state).unwrap_or_default()
    }
}

impl SqMethod {
    /// Lines (Fig. 21), the cross field by angle bins (Fig. 23) and the quads without real
    /// torsal directions in red; the quad mesh, the panels, the support structure and the node
    /// axes (Fig. 19, 25).
    fn layers(&self, v: &SqView, frame: &Frame) -> Vec<Layer> {
        let id = Mat4::IDENTITY;
        let lines = |m: &Arc<MeshData>, color| Layer { geometry: Geometry::Mesh(m.clone()), model: id, style: Style::Lines { color } };
        let surface = |m: &Arc<MeshData>, shading, color| Layer {
            geometry: Geometry::Mesh(m.clone()),
            model: id,
            style: Style::Surface { shading, color, color_map: None },
        };
        let d = self.display;
        let mut layers = Vec::new();
        if d.initial_lines {
            layers.extend(v.initial_lines.as_ref().map(|m| lines(m, [0.55, 0.55, 0.60, 1.0])));
        }
        if d.lines {
            layers.extend(v.lines.as_ref().map(|m| lines(m, [0.15, 0.40, 0.95, 1.0])));
        }
        if d.cross_field {
            let bins = v.cross_field.len();
            layers.extend(v.cross_field.iter().enumerate().filter(|(_, m)| !m.edges.is_empty()).map(|(k, m)| lines(m, colormap::bin_color(k, bins))));
        }
        layers.extend(v.no_real_quads.as_ref().filter(|m| !m.edges.is_empty()).map(|m| lines(m, [0.95, 0.10, 0.10, 1.0])));
        if let Some(p) = v.panels.as_ref().filter(|_| d.panels) {
            match v.moulds.as_ref().filter(|_| frame.moulds) {
                Some(m) => layers.extend(m.layers(frame.shading)),
                None => layers.push(surface(p, frame.shading, [0.70, 0.80, 0.88, 1.0])),
            }
            layers.push(lines(p, frame.edge_color));
        }
        if d.quad_mesh && (v.panels.is_none() || !d.panels) {
            layers.extend(v.quad_mesh.as_ref().map(|m| lines(m, [0.95, 0.55, 0.20, 1.0])));
        }
        if d.support {
            layers.extend(v.support.as_ref().map(|m| surface(m, 0, [0.80, 0.55, 0.30, 1.0])));
        }
        if d.axes {
            layers.extend(v.axes.as_ref().map(|m| lines(m, [0.85, 0.15, 0.12, 1.0])));
        }
        layers
    }
}

/// What the viewport shows of an SQ run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SqDisplay {
    pub initial_lines: bool,
    pub lines: bool,
    pub cross_field: bool,
    pub surface: bool,
    pub quad_mesh: bool,
    pub panels: bool,
    pub support: bool,
    pub axes: bool,
}

impl Default for SqDisplay {
    fn default() -> Self {
        Self { initial_lines: false, lines: true, cross_field: true, surface: true, quad_mesh: true, panels: true, support: true, axes: true }
    }
}

/// The method's controls; true when a parameter changed.
fn controls(ui: &mut egui::Ui, params: &mut SqParams, display: &mut SqDisplay) -> bool {
    let before = params.clone();
    ui.label(RichText::new("Needs a B-spline reference (.json, or the vault sample)").small());
    ui.add(egui::Slider::new(&mut params.theta_deg, THETA_RANGE.range()).text("θ (°)"))
        .on_hover_text("Largest angle between a line of the congruence and the surface normal (Sec. 5.1)");
    ui.add(egui::Slider::new(&mut params.alpha_deg, ALPHA_RANGE.range()).text("α (°)"))
        .on_hover_text("Smallest angle between the two torsal planes of a grid quad (Sec. 5.1)");
    ui.add(egui::Slider::new(&mut params.grid, GRID_RANGE.lo..=GRID_RANGE.hi.min(60)).text("grid"))
        .on_hover_text("Points per direction of the sampling grid G");
    ui.add(egui::Slider::new(&mut params.faces, FACES_RANGE.lo.max(16)..=FACES_RANGE.hi).logarithmic(true).text("faces"))
        .on_hover_text("Quads the remesh along the torsal cross field aims at (Sec. 5.2)");
    ui.add(
        egui::Slider::new(&mut params.support_depth, SUPPORT_DEPTH_RANGE.lo.max(0.002)..=SUPPORT_DEPTH_RANGE.hi.min(0.1))
            .logarithmic(true)
            .text("support depth"),
    )
    .on_hover_text("Depth of the support elements, relative to the bounding-box diagonal");
    max_distance_slider(ui, &mut params.max_distance);
    optimize_moulds_checkbox(ui, &mut params.optimize_moulds, "Projections to exactness with every panel's curvature held at its mould's, coarser each round while exactness, θ and α hold and the vertices stay within 1.2× of their distance to the reference; every kept panel has its mould's radius exactly");
    egui::ComboBox::from_label("run until").selected_text(params.until.key()).show_ui(ui, |ui| {
        for u in Until::ALL {
            ui.selectable_value(&mut params.until, u, u.key());
        }
    });
    egui::CollapsingHeader::new("advanced").id_salt("sq-advanced").show(ui, |ui| advanced_controls(ui, params));
    ui.checkbox(&mut display.lines, "optimized lines");
    ui.checkbox(&mut display.initial_lines, "lines of the central congruence (before)");
    ui.checkbox(&mut display.cross_field, "torsal cross field");
    ui.checkbox(&mut display.surface, "reference surface");
    ui.checkbox(&mut display.quad_mesh, "quad mesh");
    ui.checkbox(&mut display.panels, "panels");
    ui.checkbox(&mut display.support, "support structure");
    ui.checkbox(&mut display.axes, "node axes");
    *params != before
}

/// The advanced controls: the start, the steps' iterations, the radius basis and the weights of
/// Tables 1–3.
fn advanced_controls(ui: &mut egui::Ui, params: &mut SqParams) {
    egui::ComboBox::from_label("starting congruence")
        .selected_text(params.start.key())
        .show_ui(ui, |ui| {
            for s in RadiusStart::ALL {
                ui.selectable_value(&mut params.start, s, s.key());
            }
        })
        .response
        .on_hover_text("auto: the central congruence r = 1/H, then constant radii when it misses θ or α (Sec. 5.1, 6.3)");
    ui.add(egui::Slider::new(&mut params.recompute_every, RECOMPUTE_RANGE.lo..=RECOMPUTE_RANGE.hi.min(50)).text("RS"))
        .on_hover_text("The torsal directions and planes are recomputed every RS iterations");
    ui.add(egui::Slider::new(&mut params.lc_iterations, 1..=ITERATIONS_RANGE.hi.min(500)).text("step 1 iterations"));
    ui.add(egui::Slider::new(&mut params.torsal_iterations, 1..=ITERATIONS_RANGE.hi.min(500)).text("step 2 iterations"));
    ui.add(
        egui::Slider::new(&mut params.final_iterations, ITERATIONS_RANGE.lo..=ITERATIONS_RANGE.hi.min(50))
            .text("last iterations without angle and fairness"),
    );
    let mut degree = params.radius_basis.degree;
    ui.add(egui::Slider::new(&mut degree, RADIUS_DEGREE_RANGE.lo..=RADIUS_DEGREE_RANGE.hi.min(7)).text("radius degree"));
    params.radius_basis.degree = degree;
    params.radius_basis.controls = params.radius_basis.controls.max(degree + 1);
    ui.add(
        egui::Slider::new(&mut params.radius_basis.controls, degree + 1..=RADIUS_CONTROLS_RANGE.hi.min(20)).text("radius coefficients per direction"),
    );
    ui.label(RichText::new("step 1 weights (Table 1)").small());
    let w = &mut params.lc_weights;
    weight(ui, &mut w.lc, "w_LC");
    weight(ui, &mut w.lc_orth, "w_LC_orth");
    ui.label(RichText::new("step 2 weights (Table 2)").small());
    let w = &mut params.torsal_weights;
    weight(ui, &mut w.lc, "w_LC");
    weight(ui, &mut w.lc_orth, "w_LC_orth");
    weight(ui, &mut w.torsal, "w_torsal");
    weight(ui, &mut w.angle, "w_angle");
    weight(ui, &mut w.fair, "w_fair");
    weight(ui, &mut w.reg, "w_reg");
    ui.label(RichText::new("final optimization (Eq. 10, Table 3)").small());
    ui.add(egui::Slider::new(&mut params.sphere_iterations[1], ITERATIONS_RANGE.lo..=ITERATIONS_RANGE.hi.min(500)).text("iterations"));
    let w = &mut params.sphere_weights;
    weight(ui, &mut w.sphere, "w_sphere");
    weight(ui, &mut w.supp, "w_supp");
    weight(ui, &mut w.torsal_plane, "w_torsal_plane");
    weight(ui, &mut w.prox_f, "w_prox_f");
    weight(ui, &mut w.prox_c, "w_prox_c");
    weight(ui, &mut w.fair, "w_fair");
    if ui.small_button("defaults").clicked() {
        let keep = (params.theta_deg, params.alpha_deg, params.grid, params.faces, params.until);
        *params = SqParams { theta_deg: keep.0, alpha_deg: keep.1, grid: keep.2, faces: keep.3, until: keep.4, ..SqParams::default() };
    }
}

fn weight(ui: &mut egui::Ui, w: &mut f64, label: &str) {
    ui.add(egui::Slider::new(w, WEIGHT_RANGE.lo..=WEIGHT_RANGE.hi.min(10.0)).logarithmic(true).text(label));
}

/// The live energy of every term and, when done, the figures before and after.
fn results(ui: &mut egui::Ui, v: &SqView) {
    ui.separator();
    ui.strong("SQ mesh with support structure (Sec. 5)");
    if v.refused_h.is_some() {
        ui.colored_label(Color32::from_rgb(240, 180, 80), "The surface is coloured by the sign of H: red H > 0, blue H < 0.");
    }
    for (title, steps) in ENERGY_PLOTS {
        let series: Vec<(u32, String, Vec<Energy>)> = v.energy.iter().filter(|(_, step, _)| steps.contains(&step.as_str())).cloned().collect();
        if !series.is_empty() {
            ui.label(RichText::new(format!("{title}: energy of every term per iteration (log scale)")).small());
            term_plot(ui, &series);
        }
    }
    let Some(sum) = &v.summary else {
        if v.lines.is_some() {
            ui.label(RichText::new(format!("lines at iteration {}", v.line_iteration)).small());
        }
        return;
    };
    congruence_figures(ui, sum);
    mesh_figures(ui, sum);
    warnings(ui, &sum.report.warnings);
}

/// The congruence's figures at the start and optimized (Sec. 5.1), each marked as the run's
/// verdict grades it (the limits the run had, not the sliders').
fn congruence_figures(ui: &mut egui::Ui, sum: &SqFinished) {
    let sec = &sum.section;
    let c = &sec.congruence;
    let (i, f) = (&c.initial, &c.figures);
    let r = &sum.report;
    let g = |x: f64| format!("{x:.2e}");
    let mark = |name: &str| graded(r, name);
    let tried: Vec<String> = c
        .attempts
        .iter()
        .map(|a| match &a.final_misses {
            Some(m) if m.is_empty() => format!("{} (meets every guarantee)", a.start.key()),
            Some(m) => format!("{} (missed {})", a.start.key(), m.join(", ")),
            None => format!("{} ({} misses on G)", a.start.key(), a.misses),
        })
        .collect();
    let mut rows = vec![
        ("start kept", format!("{} of {}", c.start.key(), tried.join(", then "))),
        (
            "max ∠(l, n), central → final",
            format!("{:.2}° → {:.2}°{}", i.max_line_normal_angle_deg, f.max_line_normal_angle_deg, mark("max_line_normal_angle_deg")),
        ),
        (
            "min torsal-plane angle",
            format!("{:.2}° → {:.2}°{}", i.min_torsal_plane_angle_deg, f.min_torsal_plane_angle_deg, mark("min_torsal_plane_angle_deg")),
        ),
        ("quads without real torsal directions", format!("{} → {}", i.quads_without_real_torsal_directions, f.quads_without_real_torsal_directions)),
        ("E_LC per term, step 1 / final", format!("{} / {}", g(c.lc_residual_step1), g(c.lc_residual))),
        ("radius fit error", g(c.radius_fit_error)),
        ("iterations", format!("{} + {}", c.line_congruence_iterations, c.torsal_iterations)),
    ];
    if let (Some(lc), Some(t)) = (r.timings_ms.get("lc_iteration_median"), r.timings_ms.get("torsal_iteration_median")) {
        rows.push(("median iteration, step 1 / 2", format!("{lc:.2} / {t:.2} ms")));
    }
    key_values(ui, "sq-metrics", &rows);
}

/// The SQ mesh's figures (Sec. 5.2), when the run got there, each marked as the run's verdict
/// grades it.
fn mesh_figures(ui: &mut egui::Ui, sum: &SqFinished) {
    let (sec, r) = (&sum.section, &sum.report);
    let panels = r.metrics.clone();
    let mark = |name: &str| graded(r, name);
    if let Some(mf) = sec.sq_mesh.as_ref().map(|m| &m.figures) {
        let quads = sec.quad_mesh.as_ref();
        ui.strong("SQ mesh (Sec. 5.2)");
        let e = |x: f64| format!("{x:.1e}");
        let mut rows = vec![
            ("faces", format!("{} quads, {:.1} % of the patch", r.output.faces, 100.0 * quads.map_or(0.0, |q| q.coverage))),
            ("vertex–sphere residual / diag", format!("{}{}", e(mf.max_vertex_sphere_residual), mark("max_vertex_sphere_residual"))),
            ("centre-face planarity / diag", format!("{}{}", e(mf.max_centre_face_planarity), mark("max_centre_face_planarity"))),
            ("torsal-plane residual", e(mf.max_torsal_plane_residual)),
            ("max ∠(node axis, n)", format!("{:.2}°{}", mf.max_axis_normal_angle_deg, mark("max_axis_normal_angle_deg"))),
            ("min support-plane angle", format!("{:.2}°{}", mf.min_torsal_plane_angle_deg, mark("min_support_plane_angle_deg"))),
            ("max distance to the reference", panels.as_ref().map_or("–".into(), |p| p.max_distance_text())),
            (
                "edges off the torsal directions",
                format!(
                    "{:.2}° mean, {:.2}° max",
                    quads.map_or(0.0, |q| q.mean_edge_torsal_angle_deg),
                    quads.map_or(0.0, |q| q.max_edge_torsal_angle_deg)
                ),
            ),
            ("distinct radii", panels.as_ref().map_or("–".into(), |p| p.distinct_radii.to_string())),
        ];
        let mesh = sec.sq_mesh.as_ref();
        rows.extend(before_after(mesh.and_then(|m| m.moulds.moulds_before), mesh.map_or(0, |m| m.moulds.mould_rounds.len()), r.moulds.as_ref()));
        rows.extend(mesh.and_then(|m| m.moulds.refused()).map(|why| ("mould snap", why)));
        if let Some(t) = r.timings_ms.get("final_iteration_median") {
            rows.push(("median final iteration", format!("{t:.2} ms")));
        }
        if let Some(t) = r.timings_ms.get("total") {
            rows.push(("total", format!("{t:.0} ms")));
        }
        key_values(ui, "sq-mesh-metrics", &rows);
    }
}

/// The energy plots: one per stage, with the progress steps that belong to it.
const ENERGY_PLOTS: [(&str, &[&str]); 3] =
    [("congruence", &["line_congruence", "torsal"]), ("Q′", &["fairing"]), ("spheres", &["warm_up", "spheres", "projection", "moulds"])];
