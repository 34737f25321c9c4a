//! ST meshes with adapted face size (Sec. 3): sizing, edge variant, and the live energy plot and
//! metrics of the run.

use egui::{Color32, RichText};

use super::{sizing_controls, SizingMemory};
use crate::design_link::SizingKind;
use crate::panels::edge_arcs::EdgeArcs;
use crate::st_adapted::params::StAdaptedParams;
use crate::web::app::plots::{energy_plot, key_values};
use crate::web::app::state::StAdaptedView;

/// The method's controls; true when a parameter changed.
pub fn controls(
    ui: &mut egui::Ui,
    params: &mut StAdaptedParams,
    memory: &mut SizingMemory,
    show_reference: &mut bool,
    show_remeshed: &mut bool,
) -> bool {
    let before = params.clone();
    sizing_controls(
        ui,
        "st-sizing",
        &mut params.sizing,
        memory,
        &SizingKind::ALL,
    );
    ui.horizontal(|ui| {
        ui.label("edges");
        ui.radio_value(
            &mut params.variant,
            EdgeArcs::Intersection,
            "(a) sphere intersections",
        )
        .on_hover_text("Fig. 12 (a): edges are the intersection circles of adjacent face spheres");
        ui.radio_value(
            &mut params.variant,
            EdgeArcs::BisectingPlanes,
            "(b) bisecting planes",
        )
        .on_hover_text(
            "Fig. 12 (b): each sphere is cut by the bisecting face planes; small gaps remain",
        );
    });
    ui.checkbox(show_reference, "show reference surface (sizing colours)");
    ui.checkbox(
        show_remeshed,
        "overlay the remeshed triangulation (before optimization)",
    );
    *params != before
}

/// The live energy plot and, when done, the report metrics.
pub fn results(ui: &mut egui::Ui, a: &StAdaptedView) {
    ui.separator();
    ui.strong("ST mesh, adapted face size");
    if let Some(m) = &a.remeshed {
        ui.label(
            RichText::new(format!(
                "remeshed: {} faces; panels at iteration {}",
                m.triangles.len() / 3,
                a.panel_iteration
            ))
            .small(),
        );
    }
    if !a.energy.is_empty() {
        ui.label(
            RichText::new("energy per iteration (log scale; weights change between stages)")
                .small(),
        );
        energy_plot(ui, &a.energy);
    }
    let Some(sum) = &a.summary else { return };
    super::verdict(ui, &sum.report);
    let g = |x: Option<f64>| x.map_or("–".to_string(), |v| format!("{v:.3e}"));
    let mut rows = vec![
        ("panels", sum.report.output.panels.to_string()),
        ("iterations", sum.iterations.to_string()),
        (
            "kink mean, initial → final",
            format!(
                "{:.3}° → {:.3}°",
                sum.initial.mean_kink_angle_deg, sum.metrics.mean_kink_angle_deg
            ),
        ),
        (
            "kink max, initial → final",
            format!(
                "{:.3}° → {:.3}°",
                sum.initial.max_kink_angle_deg, sum.metrics.max_kink_angle_deg
            ),
        ),
        (
            "vertex–sphere residual",
            g(Some(sum.metrics.max_vertex_sphere_residual)),
        ),
        (
            "distance to reference",
            g(Some(sum.metrics.max_distance_to_reference)),
        ),
    ];
    if let Some(gap) = sum.metrics.max_gap {
        rows.push(("max gap (b)", format!("{gap:.3e}")));
    }
    if let Some((lo, hi)) = sum.sizing_range {
        rows.push(("sizing g min / max", format!("{lo:.4} / {hi:.4}")));
    }
    if let Some(ms) = sum.report.timings_ms.get("angle_iteration_median") {
        rows.push(("median iteration", format!("{ms:.2} ms")));
    }
    key_values(ui, "st-adapted-metrics", &rows);
    if sum.metrics.flipped_faces > 0 {
        ui.colored_label(
            Color32::from_rgb(240, 180, 80),
            format!(
                "{} faces ended flipped against the reference.",
                sum.metrics.flipped_faces
            ),
        );
    }
    super::warnings(ui, &sum.report.warnings);
}
