//! SQ meshes with support structure (Sec. 5), part 5.1: θ, α, the grid and RS, the weights under
//! "advanced"; the live energy of every term, the figures of the central and the optimized
//! congruence, and what the viewport shows (lines of Fig. 21, cross field of Fig. 23).

use egui::{Color32, RichText};

use crate::pipeline::stages::sq::STOPS_AFTER;
use crate::sq::params::{SqParams, ALPHA_RANGE, GRID_RANGE, THETA_RANGE};
use crate::web::app::plots::{key_values, term_plot};
use crate::web::app::state::SqView;

/// What the viewport shows of an SQ run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SqDisplay {
    pub initial_lines: bool,
    pub lines: bool,
    pub cross_field: bool,
    pub surface: bool,
}

impl Default for SqDisplay {
    fn default() -> Self {
        Self { initial_lines: false, lines: true, cross_field: true, surface: true }
    }
}

/// The method's controls; true when a parameter changed.
pub fn controls(ui: &mut egui::Ui, params: &mut SqParams, display: &mut SqDisplay) -> bool {
    let before = params.clone();
    ui.label(RichText::new("Needs a B-spline reference (.json, or the vault sample)").small());
    ui.add(egui::Slider::new(&mut params.theta_deg, THETA_RANGE.0..=THETA_RANGE.1).text("θ (°)"))
        .on_hover_text("Largest angle between a line of the congruence and the surface normal (Sec. 5.1)");
    ui.add(egui::Slider::new(&mut params.alpha_deg, ALPHA_RANGE.0..=ALPHA_RANGE.1).text("α (°)"))
        .on_hover_text("Smallest angle between the two torsal planes of a grid quad (Sec. 5.1)");
    ui.add(egui::Slider::new(&mut params.grid, GRID_RANGE.0..=GRID_RANGE.1.min(60)).text("grid"))
        .on_hover_text("Points per direction of the sampling grid G");
    egui::CollapsingHeader::new("advanced").id_salt("sq-advanced").show(ui, |ui| {
        ui.add(egui::Slider::new(&mut params.recompute_every, 1..=50).text("RS"))
            .on_hover_text("The torsal directions and planes are recomputed every RS iterations");
        ui.add(egui::Slider::new(&mut params.lc_iterations, 1..=500).text("step 1 iterations"));
        ui.add(egui::Slider::new(&mut params.torsal_iterations, 1..=500).text("step 2 iterations"));
        ui.add(egui::Slider::new(&mut params.final_iterations, 0..=50).text("last iterations without angle and fairness"));
        let mut degree = params.radius_basis.degree;
        ui.add(egui::Slider::new(&mut degree, 1..=7).text("radius degree"));
        params.radius_basis.degree = degree;
        params.radius_basis.controls = params.radius_basis.controls.max(degree + 1);
        ui.add(egui::Slider::new(&mut params.radius_basis.controls, degree + 1..=20).text("radius coefficients per direction"));
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
        if ui.small_button("defaults").clicked() {
            let keep = (params.theta_deg, params.alpha_deg, params.grid);
            *params = SqParams { theta_deg: keep.0, alpha_deg: keep.1, grid: keep.2, ..SqParams::default() };
        }
    });
    ui.checkbox(&mut display.lines, "optimized lines");
    ui.checkbox(&mut display.initial_lines, "lines of the central congruence (before)");
    ui.checkbox(&mut display.cross_field, "torsal cross field");
    ui.checkbox(&mut display.surface, "reference surface");
    *params != before
}

fn weight(ui: &mut egui::Ui, w: &mut f64, label: &str) {
    ui.add(egui::Slider::new(w, 0.0..=10.0).logarithmic(true).text(label));
}

/// The live energy of every term and, when done, the figures before and after.
pub fn results(ui: &mut egui::Ui, v: &SqView, params: &SqParams) {
    ui.separator();
    ui.strong("SQ congruence (Sec. 5.1)");
    if v.refused_h.is_some() {
        ui.colored_label(Color32::from_rgb(240, 180, 80), "The surface is coloured by the sign of H: red H > 0, blue H < 0.");
    }
    if !v.energy.is_empty() {
        ui.label(RichText::new("energy of every term per iteration (log scale)").small());
        term_plot(ui, &v.energy);
    }
    let Some(sum) = &v.summary else {
        if v.lines.is_some() {
            ui.label(RichText::new(format!("lines at iteration {}", v.line_iteration)).small());
        }
        return;
    };
    let (i, f) = (&sum.initial, &sum.figures);
    let r = &sum.report;
    let m = &r.metrics;
    let g = |x: Option<f64>| x.map_or("–".to_string(), |v| format!("{v:.2e}"));
    let ok = |good: bool| if good { "✔" } else { "✘" };
    let mut rows = vec![
        (
            "max ∠(l, n), central → final",
            format!(
                "{:.2}° → {:.2}° {} (θ {}°)",
                i.max_line_normal_angle_deg,
                f.max_line_normal_angle_deg,
                ok(f.max_line_normal_angle_deg <= params.theta_deg),
                params.theta_deg
            ),
        ),
        (
            "min torsal-plane angle",
            format!(
                "{:.2}° → {:.2}° {} (α {}°)",
                i.min_torsal_plane_angle_deg,
                f.min_torsal_plane_angle_deg,
                ok(f.min_torsal_plane_angle_deg >= params.alpha_deg),
                params.alpha_deg
            ),
        ),
        (
            "quads without real torsal directions",
            format!("{} → {}", i.quads_without_real_torsal_directions, f.quads_without_real_torsal_directions),
        ),
        ("E_LC per term, step 1 / final", format!("{} / {}", g(m.lc_residual_step1), g(m.lc_residual))),
        ("radius fit error", g(m.radius_fit_error)),
        ("iterations", format!("{} + {}", m.line_congruence_iterations.unwrap_or(0), m.torsal_iterations.unwrap_or(0))),
    ];
    if let (Some(lc), Some(t)) = (r.timings_ms.get("lc_iteration_median"), r.timings_ms.get("torsal_iteration_median")) {
        rows.push(("median iteration, step 1 / 2", format!("{lc:.2} / {t:.2} ms")));
    }
    key_values(ui, "sq-metrics", &rows);
    for w in &r.warnings {
        ui.colored_label(Color32::from_rgb(240, 180, 80), w);
    }
    ui.label(
        RichText::new(format!(
            "This version stops after the {STOPS_AFTER} stage: quad remeshing along the cross field and the final sphere optimization (Sec. 5.2) follow."
        ))
        .small(),
    );
}
