//! ST meshes with support structure (Sec. 4): Ω, support depth, remeshing, and the metrics and
//! the histograms of Fig. 14.

use egui::{Color32, RichText};

use super::{sizing_controls, SizingMemory};
use crate::design_link::SizingKind;
use crate::geometry::absolute_sphere::AbsoluteSphere;
use crate::st_support::StSupportParams;
use crate::web::app::plots::{histogram, key_values};
use crate::web::app::state::StSupportView;

/// The method's controls; true when a parameter changed.
pub fn controls(
    ui: &mut egui::Ui,
    params: &mut StSupportParams,
    memory: &mut SizingMemory,
    show_reference: &mut bool,
    show_envelope: &mut bool,
) -> bool {
    let before = params.clone();
    ui.checkbox(&mut params.optimize_radius, "optimize R (Fig. 16, right)");
    ui.add(egui::Slider::new(&mut params.support_depth, 0.0..=0.1).text("support depth"));
    ui.add(egui::Slider::new(&mut params.axis_length, 0.0..=0.5).text("axis length"));
    ui.add(
        egui::Slider::new(&mut params.radius_tolerance, 1e-5..=1e-1)
            .logarithmic(true)
            .text("radius tolerance"),
    );
    ui.label(RichText::new("lengths relative to the bbox diagonal").small());
    ui.label(RichText::new("Remesh first (Fig. 16, bottom)").small());
    sizing_controls(
        ui,
        "st-remesh",
        &mut params.remesh,
        memory,
        &[SizingKind::None, SizingKind::Adaptive, SizingKind::Faces],
    );
    ui.checkbox(show_reference, "show reference surface");
    ui.checkbox(show_envelope, "show second envelope");
    *params != before
}

/// Ω, the report metrics and the histograms of Fig. 14.
pub fn results(ui: &mut egui::Ui, view: &StSupportView) {
    let Some(sum) = view.summary.as_ref() else {
        return;
    };
    ui.separator();
    ui.strong("ST mesh with support structure");
    let omega = match sum.omega {
        AbsoluteSphere::Sphere { center, r2 } => {
            format!(
                "m = ({:.3}, {:.3}, {:.3})\nR² = {:.4}{}",
                center.x,
                center.y,
                center.z,
                r2,
                if r2 < 0.0 { " (imaginary Ω)" } else { "" }
            )
        }
        AbsoluteSphere::Plane { axis, d } => format!(
            "plane at infinity: a = ({:.3}, {:.3}, {:.3}), d = {:.4}",
            axis.x, axis.y, axis.z, d
        ),
    };
    ui.label(RichText::new(omega).monospace().small());
    let r = &sum.report;
    let (s, m) = (&sum.section, r.metrics.clone().unwrap_or_default());
    let g = |x: f64| format!("{x:.3e}");
    let d = |x: f64| format!("{x:.3}°");
    key_values(
        ui,
        "st-support-metrics",
        &[
            ("panels", r.output.panels.to_string()),
            ("distinct radii", sum.distinct_radii.to_string()),
            (
                "kink mean / max",
                format!("{} / {}", d(m.mean_kink_angle_deg), d(m.max_kink_angle_deg)),
            ),
            (
                "axis–normal mean / max",
                format!(
                    "{} / {}",
                    d(s.mean_axis_normal_angle_deg),
                    d(s.max_axis_normal_angle_deg)
                ),
            ),
            ("vertex–sphere residual", g(s.max_vertex_sphere_residual)),
            ("orthogonality residual", g(s.max_orthogonality_residual)),
            ("node-axis offset", g(s.max_node_axis_offset)),
            ("distance to reference", g(m.max_distance_to_reference)),
        ],
    );
    ui.label(RichText::new("∠(v − m, n): m0 (green) and optimized m (red)").small());
    histogram(
        ui,
        &[
            (&sum.angles_m0, Color32::from_rgb(90, 190, 90)),
            (&sum.angles_m, Color32::from_rgb(220, 80, 70)),
        ],
        "°",
    );
    ui.label(
        RichText::new(if matches!(sum.omega, AbsoluteSphere::Plane { .. }) {
            "distances dᵢ"
        } else {
            "Rᵢ² of the central spheres"
        })
        .small(),
    );
    histogram(ui, &[(&sum.r2, Color32::from_rgb(110, 150, 230))], "");
    super::warnings(ui, &r.warnings);
}
