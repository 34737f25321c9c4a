//! ST meshes with adapted face size (Sec. 3): sizing, edge variant, and the live energy plot and
//! metrics of the run; the sizing field, the remeshed triangulation and the panels as they
//! optimize.

use std::sync::Arc;

use egui::{Color32, RichText};
use glam::Mat4;
use serde::Serialize;

use super::method_view::{Drawn, Frame, MethodView};
use crate::design_link::{ColorBy, Design, Method};
use crate::export::Report;
use crate::panels::edge_arcs::EdgeArcs;
use crate::pipeline::fields::{field, find, Field, Part};
use crate::pipeline::protocol::{MethodId, MethodSummary, StageId, StageProgress, StageResult};
use crate::pipeline::stages::st_adapted::{StAdaptedStage, StAdaptedSummary};
use crate::remeshing::SizingKind;

/// The method's stage and the parts of its stream before the panels.
const STAGE: StageId = StageId::Method(MethodId::StAdapted, Part::Main);
const SIZING_STAGE: StageId = StageId::Method(MethodId::StAdapted, Part::Sizing);
const REMESHED_STAGE: StageId = StageId::Method(MethodId::StAdapted, Part::Remeshed);
use crate::remeshing::Sizing;
use crate::st_adapted::params::StAdaptedParams;
use crate::web::app::panels::moulds::{before_after, optimize_moulds_checkbox, MouldMeshes};
use crate::web::app::panels::{sizing_controls, warnings, SizingMemory};
use crate::web::app::plots::{energy_plot, key_values};
use crate::web::app::state::{mesh_from_fields, MESH_FIELDS, PANEL_FIELDS};
use crate::web::viewer::{Geometry, Layer, MeshData, Style};

/// The run as it streams in: sizing field, remeshed triangulation, the latest panels and the
/// energy of every iteration.
#[derive(Default)]
pub struct StAdaptedView {
    /// g at the reference vertices.
    pub sizing: Option<Vec<f32>>,
    pub remeshed: Option<Arc<MeshData>>,
    pub panels: Option<Arc<MeshData>>,
    /// The final panels by mould.
    pub moulds: Option<MouldMeshes>,
    /// Iteration of the panels shown, and how many panel snapshots arrived.
    pub panel_iteration: u32,
    pub panel_snapshots: u32,
    /// (iteration, optimizer stage, total energy).
    pub energy: Vec<(u32, String, f64)>,
    pub summary: Option<StAdaptedSummary>,
}

/// The method's view: its run, the remeshing's ε and N kept while the kind changes, and what
/// the viewport shows besides the panels.
pub struct StAdaptedMethod {
    run: Option<StAdaptedView>,
    sizing_memory: SizingMemory,
    show_reference: bool,
    show_remeshed: bool,
}

impl StAdaptedMethod {
    pub fn new(design: &Design) -> Self {
        Self { run: None, sizing_memory: SizingMemory::of(design.params::<StAdaptedStage>().sizing), show_reference: false, show_remeshed: false }
    }
}

/// What the end-to-end tests read of a run.
#[derive(Serialize)]
struct Automation<'a> {
    sizing: usize,
    remeshed_faces: usize,
    panel_iteration: u32,
    panel_snapshots: u32,
    panel_triangles: usize,
    energies: usize,
    ready: bool,
    panels: usize,
    timings_ms: Option<&'a std::collections::BTreeMap<String, f64>>,
    /// Panel meshes by mould colour, and the moulds before the rounds toward fewer (when one
    /// was kept).
    mould_colours: usize,
    moulds_before: Option<usize>,
}

impl MethodView for StAdaptedMethod {
    fn method(&self) -> Method {
        Method::Of(MethodId::StAdapted)
    }
    fn name(&self) -> &'static str {
        "st_adapted"
    }
    fn owns(&self, stage: StageId) -> bool {
        [STAGE, SIZING_STAGE, REMESHED_STAGE].contains(&stage)
    }
    fn start(&mut self) {
        self.run = Some(StAdaptedView::default());
    }
    fn clear(&mut self) {
        self.run = None;
    }
    fn controls(&mut self, ui: &mut egui::Ui, design: &mut Design) -> bool {
        controls(ui, design.params_mut::<StAdaptedStage>(), &mut self.sizing_memory, &mut self.show_reference, &mut self.show_remeshed)
    }
    fn results(&self, ui: &mut egui::Ui, _design: &Design) {
        if let Some(run) = &self.run {
            results(ui, run);
        }
    }
    fn snapshot(&mut self, stage: StageId, iteration: u32, fields: &[Field], generation: &mut u64) -> bool {
        let Some(a) = self.run.as_mut() else {
            return false;
        };
        if stage == SIZING_STAGE {
            a.sizing = find(fields, field::SIZING).and_then(Field::as_f32).map(<[f32]>::to_vec);
            return true;
        }
        if stage == REMESHED_STAGE {
            a.remeshed = Some(mesh_from_fields(fields, generation, MESH_FIELDS));
        } else {
            a.panels = Some(mesh_from_fields(fields, generation, PANEL_FIELDS));
            a.moulds = MouldMeshes::from_fields(fields, generation);
            a.panel_iteration = iteration;
            a.panel_snapshots += 1;
        }
        false
    }
    fn progress(&mut self, p: &StageProgress) {
        if let (Some(a), Some(total), true) = (self.run.as_mut(), p.energies.first(), p.stage == STAGE) {
            a.energy.push((p.iteration, p.detail.clone(), total.value));
        }
    }
    fn finished(&mut self, result: StageResult) -> Option<Report> {
        let (StageResult::Method(MethodSummary::StAdapted(summary)), Some(a)) = (result, self.run.as_mut()) else {
            return None;
        };
        let report = summary.report.clone();
        a.summary = Some(*summary);
        Some(report)
    }
    fn draw(&self, frame: &Frame) -> Drawn {
        let Some(a) = &self.run else {
            return Drawn::reference_only();
        };
        let shown = a.panels.is_some() || a.remeshed.is_some();
        let surface = |m: &Arc<MeshData>| Layer {
            geometry: Geometry::Mesh(m.clone()),
            model: Mat4::IDENTITY,
            style: Style::Surface { shading: frame.shading, color: [0.70, 0.80, 0.88, 1.0], color_map: None },
        };
        let lines = |m: &Arc<MeshData>, color| Layer { geometry: Geometry::Mesh(m.clone()), model: Mat4::IDENTITY, style: Style::Lines { color } };
        let mut layers = Vec::new();
        match (&a.panels, &a.remeshed) {
            (Some(p), _) => match a.moulds.as_ref().filter(|_| frame.moulds) {
                Some(m) => layers.extend(m.layers(frame.shading).chain([lines(p, frame.edge_color)])),
                None => layers.extend([surface(p), lines(p, frame.edge_color)]),
            },
            (None, Some(r)) => layers.push(surface(r)),
            (None, None) => {}
        }
        // The remeshed triangulation: alone until the first panels arrive, then on request.
        if let Some(r) = a.remeshed.as_ref().filter(|_| self.show_remeshed || a.panels.is_none()) {
            layers.push(lines(r, [0.95, 0.55, 0.20, 1.0]));
        }
        Drawn { layers, reference: !shown || self.show_reference, reference_colors: None, legend: None }
    }
    fn automation(&self) -> serde_json::Value {
        let state = self.run.as_ref().map(|a| Automation {
            sizing: a.sizing.as_ref().map_or(0, Vec::len),
            remeshed_faces: a.remeshed.as_ref().map_or(0, |m| m.triangles.len() / 3),
            panel_iteration: a.panel_iteration,
            panel_snapshots: a.panel_snapshots,
            panel_triangles: a.panels.as_ref().map_or(0, |m| m.triangles.len() / 3),
            energies: a.energy.len(),
            ready: a.summary.is_some(),
            panels: a.summary.as_ref().map_or(0, |s| s.report.output.panels),
            timings_ms: a.summary.as_ref().map(|s| &s.report.timings_ms),
            mould_colours: a.moulds.as_ref().map_or(0, MouldMeshes::colours),
            moulds_before: a
                .summary
                .as_ref()
                .and_then(|s| s.report.section::<crate::st_adapted::report::StAdaptedSection>())
                .and_then(|s| s.moulds.moulds_before),
        });
        serde_json::to_value(state).unwrap_or_default()
    }
    fn remesh_to(&self, design: &mut Design, faces: usize) {
        design.params_mut::<StAdaptedStage>().sizing = Sizing::UniformFaces(faces);
    }
    fn iterations(&self) -> usize {
        self.run.as_ref().map_or(0, |a| a.energy.len())
    }
    fn colors(&self) -> ColorBy {
        ColorBy::Sizing
    }
    fn sizing(&self) -> Option<&[f32]> {
        self.run.as_ref()?.sizing.as_deref()
    }
    fn link_applied(&mut self, design: &Design) {
        self.sizing_memory.remember(design.params::<StAdaptedStage>().sizing);
    }
}

/// The method's controls; true when a parameter changed.
fn controls(ui: &mut egui::Ui, params: &mut StAdaptedParams, memory: &mut SizingMemory, show_reference: &mut bool, show_remeshed: &mut bool) -> bool {
    let before = params.clone();
    sizing_controls(ui, "st-sizing", &mut params.sizing, memory, &SizingKind::ALL);
    ui.horizontal(|ui| {
        ui.label("edges");
        ui.radio_value(&mut params.variant, EdgeArcs::Intersection, "(a) sphere intersections")
            .on_hover_text("Fig. 12 (a): edges are the intersection circles of adjacent face spheres; where one would cross the panel's other arcs, the edge is cut by the bisecting plane instead, with a small gap");
        ui.radio_value(&mut params.variant, EdgeArcs::BisectingPlanes, "(b) bisecting planes")
            .on_hover_text("Fig. 12 (b): each sphere is cut by the bisecting face planes; small gaps remain");
    });
    optimize_moulds_checkbox(ui, &mut params.optimize_moulds, "Rounds that pull every panel's curvature to a coarser mould's, keeping the largest kink within 1.2× and the panels within 2ε; then every panel gets its mould's radius exactly");
    ui.checkbox(show_reference, "show reference surface (sizing colours)");
    ui.checkbox(show_remeshed, "overlay the remeshed triangulation (before optimization)");
    *params != before
}

/// The live energy plot and, when done, the report metrics.
fn results(ui: &mut egui::Ui, a: &StAdaptedView) {
    ui.separator();
    ui.strong("ST mesh, adapted face size");
    if let Some(m) = &a.remeshed {
        ui.label(RichText::new(format!("remeshed: {} faces; panels at iteration {}", m.triangles.len() / 3, a.panel_iteration)).small());
    }
    if !a.energy.is_empty() {
        ui.label(RichText::new("energy per iteration (log scale; weights change between stages)").small());
        energy_plot(ui, &a.energy);
    }
    let Some(sum) = &a.summary else { return };
    let g = |x: Option<f64>| x.map_or("–".to_string(), |v| format!("{v:.3e}"));
    let mut rows = vec![
        ("panels", sum.report.output.panels.to_string()),
        ("iterations", sum.iterations.to_string()),
        ("kink mean, initial → final", format!("{:.3}° → {:.3}°", sum.initial.mean_kink_angle_deg, sum.metrics.mean_kink_angle_deg)),
        ("kink max, initial → final", format!("{:.3}° → {:.3}°", sum.initial.max_kink_angle_deg, sum.metrics.max_kink_angle_deg)),
        ("vertex–sphere residual", g(Some(sum.metrics.max_vertex_sphere_residual))),
        ("distance to reference", sum.report.metrics.as_ref().map_or("–".into(), |m| m.max_distance_text())),
    ];
    if sum.metrics.bisected_edges > 0 {
        rows.push(("edges cut by bisecting planes", sum.metrics.bisected_edges.to_string()));
    }
    if let Some(gap) = sum.metrics.max_gap {
        rows.push(("max gap", format!("{gap:.3e} of the diagonal")));
    }
    if let Some((lo, hi)) = sum.sizing_range {
        rows.push(("sizing g min / max", format!("{lo:.4} / {hi:.4}")));
    }
    let section: Option<crate::st_adapted::report::StAdaptedSection> = sum.report.section();
    let rounds = section.as_ref().map_or(0, |s| s.moulds.mould_rounds.len());
    rows.extend(before_after(section.as_ref().and_then(|s| s.moulds.moulds_before), rounds, sum.report.moulds.as_ref()));
    if let Some(ms) = sum.report.timings_ms.get("angle_iteration_median") {
        rows.push(("median iteration", format!("{ms:.2} ms")));
    }
    key_values(ui, "st-adapted-metrics", &rows);
    if sum.metrics.flipped_faces > 0 {
        ui.colored_label(Color32::from_rgb(240, 180, 80), format!("{} faces ended flipped against the reference.", sum.metrics.flipped_faces));
    }
    warnings(ui, &sum.report.warnings);
}
