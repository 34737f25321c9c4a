//! SQ meshes with support structure (Sec. 5): θ, α, the grid, the face count and the support
//! depth, RS, iterations and weights under "advanced"; one live energy plot per stage
//! (congruence, Q′, spheres), the figures of the congruence and of the SQ mesh, and what the
//! viewport shows (lines of Fig. 21, cross field of Fig. 23, quad mesh, panels, support
//! structure and node axes of Fig. 19, 25).

use egui::{Color32, RichText};

use crate::pipeline::fields::Energy;
use crate::sq::params::{
    RadiusStart, SqParams, Until, ALPHA_RANGE, FACES_RANGE, GRID_RANGE, THETA_RANGE,
};
use crate::web::app::plots::{key_values, term_plot};
use crate::web::app::state::SqView;

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
        Self {
            initial_lines: false,
            lines: true,
            cross_field: true,
            surface: true,
            quad_mesh: true,
            panels: true,
            support: true,
            axes: true,
        }
    }
}

/// The method's controls; true when a parameter changed.
pub fn controls(ui: &mut egui::Ui, params: &mut SqParams, display: &mut SqDisplay) -> bool {
    let before = params.clone();
    ui.label(RichText::new("Needs a B-spline reference (.json, or the vault sample)").small());
    ui.add(egui::Slider::new(&mut params.theta_deg, THETA_RANGE.range()).text("θ (°)"))
        .on_hover_text(
            "Largest angle between a line of the congruence and the surface normal (Sec. 5.1)",
        );
    ui.add(egui::Slider::new(&mut params.alpha_deg, ALPHA_RANGE.range()).text("α (°)"))
        .on_hover_text("Smallest angle between the two torsal planes of a grid quad (Sec. 5.1)");
    ui.add(egui::Slider::new(&mut params.grid, GRID_RANGE.lo..=GRID_RANGE.hi.min(60)).text("grid"))
        .on_hover_text("Points per direction of the sampling grid G");
    ui.add(
        egui::Slider::new(&mut params.faces, FACES_RANGE.lo.max(16)..=FACES_RANGE.hi)
            .logarithmic(true)
            .text("faces"),
    )
    .on_hover_text("Quads the remesh along the torsal cross field aims at (Sec. 5.2)");
    ui.add(
        egui::Slider::new(&mut params.support_depth, 0.002..=0.1)
            .logarithmic(true)
            .text("support depth"),
    )
    .on_hover_text("Depth of the support elements, relative to the bounding-box diagonal");
    egui::ComboBox::from_label("run until")
        .selected_text(params.until.key())
        .show_ui(ui, |ui| {
            for u in Until::ALL {
                ui.selectable_value(&mut params.until, u, u.key());
            }
        });
    egui::CollapsingHeader::new("advanced").id_salt("sq-advanced").show(ui, |ui| {
        egui::ComboBox::from_label("starting congruence")
            .selected_text(params.start.key())
            .show_ui(ui, |ui| {
                for s in RadiusStart::ALL {
                    ui.selectable_value(&mut params.start, s, s.key());
                }
            })
            .response
            .on_hover_text("auto: the central congruence r = 1/H, then constant radii when it misses θ or α (Sec. 5.1, 6.3)");
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
        ui.label(RichText::new("final optimization (Eq. 10, Table 3)").small());
        ui.add(egui::Slider::new(&mut params.sphere_iterations[1], 0..=500).text("iterations"));
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
    });
    ui.checkbox(&mut display.lines, "optimized lines");
    ui.checkbox(
        &mut display.initial_lines,
        "lines of the central congruence (before)",
    );
    ui.checkbox(&mut display.cross_field, "torsal cross field");
    ui.checkbox(&mut display.surface, "reference surface");
    ui.checkbox(&mut display.quad_mesh, "quad mesh");
    ui.checkbox(&mut display.panels, "panels");
    ui.checkbox(&mut display.support, "support structure");
    ui.checkbox(&mut display.axes, "node axes");
    *params != before
}

fn weight(ui: &mut egui::Ui, w: &mut f64, label: &str) {
    ui.add(
        egui::Slider::new(w, 0.0..=10.0)
            .logarithmic(true)
            .text(label),
    );
}

/// The live energy of every term and, when done, the figures before and after.
pub fn results(ui: &mut egui::Ui, v: &SqView, params: &SqParams) {
    ui.separator();
    ui.strong("SQ mesh with support structure (Sec. 5)");
    if v.refused_h.is_some() {
        ui.colored_label(
            Color32::from_rgb(240, 180, 80),
            "The surface is coloured by the sign of H: red H > 0, blue H < 0.",
        );
    }
    for (title, steps) in ENERGY_PLOTS {
        let series: Vec<(u32, String, Vec<Energy>)> = v
            .energy
            .iter()
            .filter(|(_, step, _)| steps.contains(&step.as_str()))
            .cloned()
            .collect();
        if !series.is_empty() {
            ui.label(
                RichText::new(format!(
                    "{title}: energy of every term per iteration (log scale)"
                ))
                .small(),
            );
            term_plot(ui, &series);
        }
    }
    let Some(sum) = &v.summary else {
        if v.lines.is_some() {
            ui.label(RichText::new(format!("lines at iteration {}", v.line_iteration)).small());
        }
        return;
    };
    let sec = &sum.section;
    let c = &sec.congruence;
    let (i, f) = (&c.initial, &c.figures);
    let r = &sum.report;
    super::verdict(ui, r);
    let panels = r.metrics.clone();
    let g = |x: f64| format!("{x:.2e}");
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
            format!(
                "{} → {}",
                i.quads_without_real_torsal_directions, f.quads_without_real_torsal_directions
            ),
        ),
        (
            "E_LC per term, step 1 / final",
            format!("{} / {}", g(c.lc_residual_step1), g(c.lc_residual)),
        ),
        ("radius fit error", g(c.radius_fit_error)),
        (
            "iterations",
            format!("{} + {}", c.line_congruence_iterations, c.torsal_iterations),
        ),
    ];
    if let (Some(lc), Some(t)) = (
        r.timings_ms.get("lc_iteration_median"),
        r.timings_ms.get("torsal_iteration_median"),
    ) {
        rows.push((
            "median iteration, step 1 / 2",
            format!("{lc:.2} / {t:.2} ms"),
        ));
    }
    key_values(ui, "sq-metrics", &rows);
    if let Some(mf) = sec.sq_mesh.as_ref().map(|m| &m.figures) {
        let quads = sec.quad_mesh.as_ref();
        ui.strong("SQ mesh (Sec. 5.2)");
        let e = |x: f64| format!("{x:.1e}");
        let mut rows = vec![
            (
                "faces",
                format!(
                    "{} quads, {:.1} % of the patch",
                    r.output.faces,
                    100.0 * quads.map_or(0.0, |q| q.coverage)
                ),
            ),
            (
                "vertex–sphere residual / diag",
                format!(
                    "{} {}",
                    e(mf.max_vertex_sphere_residual),
                    ok(mf.max_vertex_sphere_residual <= 1e-8)
                ),
            ),
            (
                "centre-face planarity / diag",
                format!(
                    "{} {}",
                    e(mf.max_centre_face_planarity),
                    ok(mf.max_centre_face_planarity <= 1e-8)
                ),
            ),
            (
                "torsal-plane residual",
                format!(
                    "{} {}",
                    e(mf.max_torsal_plane_residual),
                    ok(mf.max_torsal_plane_residual <= 1e-8)
                ),
            ),
            (
                "max ∠(node axis, n)",
                format!(
                    "{:.2}° {} (θ {}°)",
                    mf.max_axis_normal_angle_deg,
                    ok(mf.max_axis_normal_angle_deg <= params.theta_deg),
                    params.theta_deg
                ),
            ),
            (
                "min support-plane angle",
                format!(
                    "{:.2}° {} (α {}°)",
                    mf.min_torsal_plane_angle_deg,
                    ok(mf.min_torsal_plane_angle_deg >= params.alpha_deg),
                    params.alpha_deg
                ),
            ),
            (
                "max distance to the reference / diag",
                panels
                    .as_ref()
                    .map_or("–".into(), |p| g(p.max_distance_to_reference)),
            ),
            (
                "edges off the torsal directions",
                format!(
                    "{:.2}° mean, {:.2}° max",
                    quads.map_or(0.0, |q| q.mean_edge_torsal_angle_deg),
                    quads.map_or(0.0, |q| q.max_edge_torsal_angle_deg)
                ),
            ),
            (
                "distinct radii",
                panels
                    .as_ref()
                    .map_or("–".into(), |p| p.distinct_radii.to_string()),
            ),
        ];
        if let Some(t) = r.timings_ms.get("final_iteration_median") {
            rows.push(("median final iteration", format!("{t:.2} ms")));
        }
        if let Some(t) = r.timings_ms.get("total") {
            rows.push(("total", format!("{t:.0} ms")));
        }
        key_values(ui, "sq-mesh-metrics", &rows);
    }
    super::warnings(ui, &r.warnings);
}

/// The energy plots: one per stage, with the progress steps that belong to it.
const ENERGY_PLOTS: [(&str, &[&str]); 3] = [
    ("congruence", &["line_congruence", "torsal"]),
    ("Q′", &["fairing"]),
    ("spheres", &["warm_up", "spheres", "projection"]),
];
