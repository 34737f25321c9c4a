//! ST meshes with support structure (Sec. 4): Ω, support depth, remeshing, and the metrics and
//! the histograms of Fig. 14; the panels, support structure, node axes, Ω and m and the second
//! envelope in the viewport.

use std::sync::Arc;

use egui::{Color32, RichText};
use glam::{Mat4, Vec3};
use serde::Serialize;

use super::method_view::{Drawn, Frame, MethodView};
use crate::congruence::support_structure::{AXIS_LENGTH_RANGE, SUPPORT_DEPTH_RANGE};
use crate::design_link::{Design, Method};
use crate::export::Report;
use crate::geometry::absolute_sphere::AbsoluteSphere;
use crate::panels::RADIUS_TOLERANCE_RANGE;
use crate::pipeline::fields::{field, find, Field, Part};
use crate::pipeline::protocol::{MethodId, MethodSummary, StageId, StageResult};
use crate::pipeline::stages::st_support::{StSupportStage, StSupportSummary};
use crate::remeshing::SizingKind;

/// The method's stage.
const STAGE: StageId = StageId::Method(MethodId::StSupport, Part::Main);
use crate::remeshing::Sizing;
use crate::st_support::report::StSupportSection;
use crate::st_support::StSupportParams;
use crate::web::app::panels::moulds::{before_after, optimize_moulds_checkbox, MouldMeshes};
use crate::web::app::panels::{max_distance_slider, sizing_controls, warnings, SizingMemory};
use crate::web::app::plots::{histogram, key_values};
use crate::web::app::state::{mesh_from_fields, AXES_FIELDS, PANEL_FIELDS, SUPPORT_FIELDS};
use crate::web::viewer::{Geometry, Layer, MeshData, Style};

/// The result as display meshes.
pub struct StSupportView {
    pub panels: Arc<MeshData>,
    pub moulds: Option<MouldMeshes>,
    pub support: Arc<MeshData>,
    pub axes: Arc<MeshData>,
    pub envelope: Option<Arc<MeshData>>,
    pub summary: Option<StSupportSummary>,
    /// The summary's report section, read once.
    pub section: Option<StSupportSection>,
}

impl StSupportView {
    pub fn from_fields(fields: &[Field], generation: &mut u64) -> Self {
        let envelope = find(fields, field::ENVELOPE_POSITIONS)
            .is_some()
            .then(|| mesh_from_fields(fields, generation, [field::ENVELOPE_POSITIONS, "", field::ENVELOPE_TRIANGLES, ""]));
        Self {
            panels: mesh_from_fields(fields, generation, PANEL_FIELDS),
            moulds: MouldMeshes::from_fields(fields, generation),
            support: mesh_from_fields(fields, generation, SUPPORT_FIELDS),
            axes: mesh_from_fields(fields, generation, AXES_FIELDS),
            envelope,
            summary: None,
            section: None,
        }
    }
}

/// The method's view: its result, the remeshing's ε and N, and what the viewport shows.
pub struct StSupportMethod {
    result: Option<StSupportView>,
    remesh_memory: SizingMemory,
    show_reference: bool,
    show_envelope: bool,
}

impl StSupportMethod {
    pub fn new(design: &Design) -> Self {
        Self { result: None, remesh_memory: SizingMemory::of(design.params::<StSupportStage>().remesh), show_reference: false, show_envelope: false }
    }
}

#[derive(Serialize)]
struct Automation {
    ready: bool,
    panels: usize,
}

impl MethodView for StSupportMethod {
    fn method(&self) -> Method {
        Method::Of(MethodId::StSupport)
    }
    fn name(&self) -> &'static str {
        "st_support"
    }
    fn owns(&self, stage: StageId) -> bool {
        stage == STAGE
    }
    fn start(&mut self) {
        self.result = None;
    }
    fn clear(&mut self) {
        self.result = None;
    }
    fn controls(&mut self, ui: &mut egui::Ui, design: &mut Design) -> bool {
        controls(ui, design.params_mut::<StSupportStage>(), &mut self.remesh_memory, &mut self.show_reference, &mut self.show_envelope)
    }
    fn results(&self, ui: &mut egui::Ui, _design: &Design) {
        if let Some(v) = &self.result {
            results(ui, v);
        }
    }
    fn snapshot(&mut self, _stage: StageId, _iteration: u32, fields: &[Field], generation: &mut u64) -> bool {
        self.result = Some(StSupportView::from_fields(fields, generation));
        false
    }
    fn finished(&mut self, result: StageResult) -> Option<Report> {
        let (StageResult::Method(MethodSummary::StSupport(summary)), Some(v)) = (result, self.result.as_mut()) else {
            return None;
        };
        let report = summary.report.clone();
        v.section = summary.section();
        v.summary = Some(*summary);
        Some(report)
    }
    fn draw(&self, frame: &Frame) -> Drawn {
        match &self.result {
            Some(st) => Drawn { layers: self.layers(st, frame), reference: self.show_reference, reference_colors: None, legend: None },
            None => Drawn::reference_only(),
        }
    }
    fn automation(&self) -> serde_json::Value {
        let summary = self.result.as_ref().and_then(|s| s.summary.as_ref());
        serde_json::to_value(Automation { ready: summary.is_some(), panels: summary.map_or(0, |s| s.report.output.panels) }).unwrap_or_default()
    }
    fn remesh_to(&self, design: &mut Design, faces: usize) {
        design.params_mut::<StSupportStage>().remesh = Sizing::UniformFaces(faces);
    }
    fn link_applied(&mut self, design: &Design) {
        self.remesh_memory.remember(design.params::<StSupportStage>().remesh);
    }
}

impl StSupportMethod {
    /// Panels (with their arcs), support structure, node axes, Ω and m, and the second envelope.
    fn layers(&self, st: &StSupportView, frame: &Frame) -> Vec<Layer> {
        let id = Mat4::IDENTITY;
        let surface = |m: &Arc<MeshData>, shading, color| Layer {
            geometry: Geometry::Mesh(m.clone()),
            model: id,
            style: Style::Surface { shading, color, color_map: None },
        };
        let mut layers = match st.moulds.as_ref().filter(|_| frame.moulds) {
            Some(m) => m.layers(frame.shading).collect(),
            None => vec![surface(&st.panels, frame.shading, [0.70, 0.80, 0.88, 1.0])],
        };
        layers.extend([
            Layer { geometry: Geometry::Mesh(st.panels.clone()), model: id, style: Style::Lines { color: frame.edge_color } },
            surface(&st.support, 0, [0.80, 0.55, 0.30, 1.0]),
            Layer { geometry: Geometry::Mesh(st.axes.clone()), model: id, style: Style::Lines { color: [0.85, 0.15, 0.12, 1.0] } },
        ]);
        if let Some(env) = st.envelope.as_ref().filter(|_| self.show_envelope) {
            layers.push(surface(env, 0, [0.55, 0.75, 0.55, 1.0]));
        }
        layers.extend(omega_layers(st.summary.as_ref().map(|s| s.omega), frame));
        layers
    }
}

/// Ω: m and Ω itself when real and not too large to see; a disc of the plane ⟨x, a⟩ = d under
/// the mesh centre when at infinity.
fn omega_layers(omega: Option<AbsoluteSphere>, frame: &Frame) -> Vec<Layer> {
    let (radius, translucent) = (frame.radius, Style::Translucent { color: [0.95, 0.75, 0.30, 0.15] });
    match omega {
        Some(AbsoluteSphere::Plane { axis, d }) => {
            let a = axis.as_vec3().normalize_or(Vec3::Z);
            let foot = frame.center + a * (d as f32 - frame.center.dot(a));
            let model = Mat4::from_scale_rotation_translation(Vec3::splat(radius * 1.2), glam::Quat::from_rotation_arc(Vec3::Z, a), foot);
            vec![Layer { geometry: Geometry::UnitDisc, model, style: translucent }]
        }
        Some(AbsoluteSphere::Sphere { center, r2 }) => {
            let m = center.as_vec3();
            let mut layers = vec![Layer {
                geometry: Geometry::UnitSphere,
                model: Mat4::from_translation(m) * Mat4::from_scale(Vec3::splat(radius * 0.02)),
                style: Style::Surface { shading: 1, color: [0.85, 0.15, 0.12, 1.0], color_map: None },
            }];
            if r2 > 0.0 && (r2.sqrt() as f32) < 20.0 * radius {
                let model = Mat4::from_translation(m) * Mat4::from_scale(Vec3::splat(r2.sqrt() as f32));
                layers.push(Layer { geometry: Geometry::UnitSphere, model, style: translucent });
            }
            layers
        }
        None => Vec::new(),
    }
}

/// The method's controls; true when a parameter changed.
fn controls(ui: &mut egui::Ui, params: &mut StSupportParams, memory: &mut SizingMemory, show_reference: &mut bool, show_envelope: &mut bool) -> bool {
    let before = params.clone();
    ui.checkbox(&mut params.optimize_radius, "optimize R (Fig. 16, right)");
    ui.add(egui::Slider::new(&mut params.support_depth, SUPPORT_DEPTH_RANGE.lo..=SUPPORT_DEPTH_RANGE.hi.min(0.1)).text("support depth"));
    ui.add(egui::Slider::new(&mut params.axis_length, AXIS_LENGTH_RANGE.lo..=AXIS_LENGTH_RANGE.hi.min(0.5)).text("axis length"));
    ui.add(
        egui::Slider::new(&mut params.radius_tolerance, RADIUS_TOLERANCE_RANGE.lo.max(1e-5)..=RADIUS_TOLERANCE_RANGE.hi.min(1e-1))
            .logarithmic(true)
            .text("radius tolerance"),
    );
    ui.label(RichText::new("lengths relative to the bbox diagonal").small());
    ui.label(RichText::new("Remesh first (Fig. 16, bottom)").small());
    sizing_controls(ui, "st-remesh", &mut params.remesh, memory, &[SizingKind::None, SizingKind::Adaptive, SizingKind::Faces]);
    max_distance_slider(ui, &mut params.max_distance);
    optimize_moulds_checkbox(ui, &mut params.optimize_moulds, "Rounds that move the vertices so that every panel has its mould's radius exactly, coarser each round, every sphere still orthogonal to Ω and the panels within 1.2× of their distance to the reference");
    ui.checkbox(show_reference, "show reference surface");
    ui.checkbox(show_envelope, "show second envelope");
    *params != before
}

/// Ω, the report metrics and the histograms of Fig. 14.
fn results(ui: &mut egui::Ui, view: &StSupportView) {
    let Some(sum) = view.summary.as_ref() else {
        return;
    };
    ui.separator();
    ui.strong("ST mesh with support structure");
    let omega = match sum.omega {
        AbsoluteSphere::Sphere { center, r2 } => {
            format!("m = ({:.3}, {:.3}, {:.3})\nR² = {:.4}{}", center.x, center.y, center.z, r2, if r2 < 0.0 { " (imaginary Ω)" } else { "" })
        }
        AbsoluteSphere::Plane { axis, d } => format!("plane at infinity: a = ({:.3}, {:.3}, {:.3}), d = {:.4}", axis.x, axis.y, axis.z, d),
    };
    ui.label(RichText::new(omega).monospace().small());
    let r = &sum.report;
    let Some(s) = view.section.as_ref() else { return };
    let m = r.metrics.clone().unwrap_or_default();
    let g = |x: f64| format!("{x:.3e}");
    let d = |x: f64| format!("{x:.3}°");
    let mut rows = vec![
        ("panels", r.output.panels.to_string()),
        ("distinct radii", sum.distinct_radii.to_string()),
        ("kink mean / max", format!("{} / {}", d(m.mean_kink_angle_deg), d(m.max_kink_angle_deg))),
        ("axis–normal mean / max", format!("{} / {}", d(s.mean_axis_normal_angle_deg), d(s.max_axis_normal_angle_deg))),
        ("vertex–sphere residual", g(s.max_vertex_sphere_residual)),
        ("orthogonality residual", g(s.max_orthogonality_residual)),
        ("node-axis offset", g(s.max_node_axis_offset)),
        ("distance to reference", m.max_distance_text()),
    ];
    rows.extend(before_after(s.moulds.moulds_before, s.moulds.mould_rounds.len(), r.moulds.as_ref()));
    rows.extend(s.moulds.refused().map(|why| ("mould snap", why)));
    key_values(ui, "st-support-metrics", &rows);
    ui.label(RichText::new("∠(v − m, n): m0 (green) and optimized m (red)").small());
    histogram(ui, &[(&sum.angles_m0, Color32::from_rgb(90, 190, 90)), (&sum.angles_m, Color32::from_rgb(220, 80, 70))], "°");
    ui.label(RichText::new(if matches!(sum.omega, AbsoluteSphere::Plane { .. }) { "distances dᵢ" } else { "Rᵢ² of the central spheres" }).small());
    histogram(ui, &[(&sum.r2, Color32::from_rgb(110, 150, 230))], "");
    warnings(ui, &r.warnings);
}
