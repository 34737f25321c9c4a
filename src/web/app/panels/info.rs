//! The reference: counts, the curvature summary, and the central sphere of a picked vertex.

use egui::{Color32, RichText};

use crate::geometry::sphere::Sphere;
use crate::pipeline::fields::{field, find, Field};
use crate::units::{format_length, Units};
use crate::web::app::plots::key_values;
use crate::web::app::state::{CurvatureView, Scene};

/// The reference section (lengths in model units `units`); returns the object picked of a file
/// holding several.
pub fn show(ui: &mut egui::Ui, loaded: Option<&Scene>, selected: Option<usize>, units: Units) -> Option<usize> {
    ui.strong("Reference");
    let Some(l) = loaded else {
        ui.label("loading…");
        return None;
    };
    let mut picked = None;
    if l.info.objects.len() > 1 {
        let current = l.info.object.unwrap_or(0);
        let label = |k: usize| l.info.objects.get(k).map_or(String::new(), |o| format!("{k}: {} ({})", o.name, o.kind));
        egui::ComboBox::from_id_salt("file-object").selected_text(label(current)).width(250.0).show_ui(ui, |ui| {
            for (k, o) in l.info.objects.iter().enumerate() {
                if ui.selectable_label(k == current, label(k)).on_hover_text(&o.summary).clicked() && k != current {
                    picked = Some(k);
                }
            }
        });
    }
    let s = &l.info.stats;
    key_values(
        ui,
        "info",
        &[
            ("source", l.info.source.label()),
            ("vertices", s.vertices.to_string()),
            ("faces", s.faces.to_string()),
            ("boundary loops", s.boundary_loops.to_string()),
            ("non-manifold edges", s.non_manifold_edges.to_string()),
            ("bbox diagonal", format_length(l.info.bbox_diagonal, units)),
        ],
    );
    if let Some(sum) = l.curvature.as_ref().and_then(|c| c.summary.as_ref()) {
        ui.add_space(4.0);
        ui.strong("Curvature");
        key_values(
            ui,
            "curvature",
            &[
                ("H min / max", format!("{:.4} / {:.4}", sum.min_h, sum.max_h)),
                ("H mean", format!("{:.4}", sum.mean_h)),
                ("boundary vertices", sum.boundary_vertices.to_string()),
                ("H ≈ 0 vertices", sum.planar_vertices.to_string()),
                ("low-degree / failed fits", format!("{} / {}", sum.low_degree_fits, sum.failed_fits)),
            ],
        );
        if sum.h_changes_sign {
            ui.colored_label(
                Color32::from_rgb(240, 180, 80),
                "H changes sign: central spheres flip through planes there; the sphere methods need H of one sign.",
            );
        }
        if sum.planar_vertices > 0 {
            ui.label(RichText::new(format!("{} vertices have H ≈ 0: their central spheres are planes.", sum.planar_vertices)).small());
        }
    }
    match (selected, l.curvature.as_ref()) {
        (Some(v), Some(c)) => {
            ui.add_space(4.0);
            ui.strong(format!("Vertex {v}"));
            if let Some(text) = vertex_text(c, v, units) {
                ui.label(RichText::new(text).monospace().small());
            }
        }
        _ => {
            ui.label(RichText::new("Click the surface to see a vertex's central sphere.").small());
        }
    }
    picked
}

/// The central sphere (Def. 2.9) of vertex `v`, as sent by the curvature stage.
pub fn central_sphere(c: &CurvatureView, v: usize) -> Option<Sphere> {
    let s = find(&c.fields, field::CENTRAL_SPHERES)?.as_f32()?.get(5 * v..5 * v + 5)?;
    Some(Sphere::from_array([s[0], s[1], s[2], s[3], s[4]].map(f64::from)))
}

/// Centre and signed radius of a central sphere; None for a plane (H ≈ 0).
pub fn center_radius(s: &Sphere) -> Option<(glam::DVec3, f64)> {
    if s.a.abs() < 1e-9 {
        return None;
    }
    Some((s.center()?, 0.5 / s.a))
}

fn vertex_text(c: &CurvatureView, v: usize, units: Units) -> Option<String> {
    let val = |k| find(&c.fields, k).and_then(Field::as_f32).and_then(|x| x.get(v).copied());
    let (h, k1, k2) = (val(field::MEAN_CURVATURE)?, val(field::K1)?, val(field::K2)?);
    let desc = match center_radius(&central_sphere(c, v)?) {
        Some((center, r)) => format!("centre ({:.3}, {:.3}, {:.3})\nradius {}", center.x, center.y, center.z, format_length(r.abs(), units)),
        None => "central sphere is a plane (H ≈ 0)".into(),
    };
    let boundary = find(&c.fields, field::BOUNDARY).and_then(Field::as_u32).and_then(|b| b.get(v).copied()) == Some(1);
    Some(format!("H  {h:.5}\nκ1 {k1:.5}\nκ2 {k2:.5}\n{desc}{}", if boundary { "\n(boundary vertex: one-sided fit)" } else { "" }))
}
