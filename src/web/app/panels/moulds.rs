//! The moulds of a panel method's result, shared by every panel method: the model unit and the
//! mould settings (a fit tolerance δ, or a count K), the mould table with each mould's colour,
//! radius, panel count and largest fit deviation, and the moulds needed against δ.

use std::sync::Arc;

use egui::{Color32, Pos2, RichText, Sense, Vec2};
use glam::Mat4;

use crate::export::MouldReport;
use crate::panels::moulds::{mould_colour, Fabrication, MouldTarget, DEFAULT_MOULD_TOLERANCE, MOULD_COLOURS, MOULD_COUNT_RANGE};
use crate::pipeline::fields::{field, find, Field};
use crate::units::{format_length, Length, Units};
use crate::web::viewer::{Geometry, Layer, MeshData, Style};

/// A result's panels split by mould colour: one mesh per colour in use, built once per result.
pub struct MouldMeshes {
    meshes: Vec<(Arc<MeshData>, [f32; 4])>,
}

impl MouldMeshes {
    /// The panels of a result snapshot grouped by their vertices' moulds (None without moulds).
    pub fn from_fields(fields: &[Field], generation: &mut u64) -> Option<Self> {
        let moulds = find(fields, field::PANEL_MOULDS)?.as_u32()?;
        let positions = find(fields, field::PANEL_POSITIONS)?.as_f32()?;
        let normals = find(fields, field::PANEL_NORMALS).and_then(Field::as_f32).unwrap_or(&[]);
        let triangles = find(fields, field::PANEL_TRIANGLES)?.as_u32()?;
        let n = positions.len() / 3;
        if moulds.len() != n || normals.len() != positions.len() {
            return None;
        }
        let mut parts: Vec<MeshData> = (0..MOULD_COLOURS).map(|_| MeshData::default()).collect();
        let mut index = vec![u32::MAX; n];
        for t in triangles.chunks_exact(3) {
            if t.iter().any(|&v| v as usize >= n) {
                return None;
            }
            let part = &mut parts[moulds[t[0] as usize] as usize % MOULD_COLOURS];
            for &v in t {
                let v = v as usize;
                // A panel's vertices are its own, so a vertex falls in one part only.
                if index[v] == u32::MAX {
                    index[v] = (part.positions.len() / 3) as u32;
                    part.positions.extend_from_slice(&positions[3 * v..3 * v + 3]);
                    part.normals.extend_from_slice(&normals[3 * v..3 * v + 3]);
                }
                part.triangles.push(index[v]);
            }
        }
        let meshes = parts
            .into_iter()
            .enumerate()
            .filter(|(_, m)| !m.triangles.is_empty())
            .map(|(k, mut m)| {
                *generation += 1;
                m.generation = *generation;
                let [r, g, b] = mould_colour(k);
                (Arc::new(m), [r, g, b, 1.0])
            })
            .collect();
        Some(Self { meshes })
    }

    /// The colours in use.
    pub fn colours(&self) -> usize {
        self.meshes.len()
    }

    /// The panels in their moulds' colours.
    pub fn layers(&self, shading: u32) -> impl Iterator<Item = Layer> + '_ {
        self.meshes.iter().map(move |(m, color)| Layer {
            geometry: Geometry::Mesh(m.clone()),
            model: Mat4::IDENTITY,
            style: Style::Surface { shading, color: *color, color_map: None },
        })
    }
}

/// Moulds listed in the table (the rest are counted).
const TABLE_ROWS: usize = 24;

/// The unit and the moulds asked for, δ and K linked through the last result (`last`): each
/// shows the other's value, and switching starts from it. True when they changed (the method
/// reruns).
pub fn controls(ui: &mut egui::Ui, fabrication: &mut Fabrication, last: Option<&MouldReport>) -> bool {
    let before = *fabrication;
    ui.label(RichText::new("Moulds: panels of one radius share a mould").small());
    ui.horizontal(|ui| {
        ui.label("model unit");
        egui::ComboBox::from_id_salt("units").selected_text(fabrication.units.symbol()).show_ui(ui, |ui| {
            for u in Units::ALL {
                ui.selectable_value(&mut fabrication.units, u, u.symbol());
            }
        });
    });
    let by_count = matches!(fabrication.moulds, MouldTarget::Count(_));
    ui.horizontal(|ui| {
        if ui.radio(!by_count, "within δ").clicked() && by_count {
            // The δ the last result needed for its K moulds, in model units.
            fabrication.moulds = MouldTarget::Tolerance(match last {
                Some(m) if m.tolerance > 0.0 => Length::new(significant(m.tolerance), m.units),
                _ => DEFAULT_MOULD_TOLERANCE,
            });
        }
        if ui.radio(by_count, "K moulds").clicked() && !by_count {
            fabrication.moulds = MouldTarget::Count(last.map_or(8, |m| m.count.max(1)));
        }
    });
    match &mut fabrication.moulds {
        MouldTarget::Tolerance(t) => {
            let unit = t.unit.unwrap_or(fabrication.units);
            let mut value = t.value;
            let mut u = unit;
            ui.horizontal(|ui| {
                ui.add(egui::DragValue::new(&mut value).range(0.0..=1e6).speed(0.1).prefix("δ "));
                egui::ComboBox::from_id_salt("mould_unit").selected_text(u.symbol()).width(48.0).show_ui(ui, |ui| {
                    for x in Units::ALL {
                        ui.selectable_value(&mut u, x, x.symbol());
                    }
                });
                if let Some(m) = last {
                    ui.label(RichText::new(format!("→ K = {}", m.count)).small()).on_hover_text("the moulds of the last result at this δ");
                }
            });
            *t = Length::new(value, u);
        }
        MouldTarget::Count(k) => {
            ui.horizontal(|ui| {
                ui.add(egui::DragValue::new(k).range(MOULD_COUNT_RANGE.range()).prefix("K "));
                if let Some(m) = last {
                    ui.label(RichText::new(format!("→ δ = {}", format_length(m.tolerance, m.units))).small())
                        .on_hover_text("the smallest fit tolerance of the last result for K moulds");
                }
            });
        }
    }
    *fabrication != before
}

/// `value` rounded to four significant digits, for a control.
fn significant(value: f64) -> f64 {
    let scale = 10f64.powi(3 - value.abs().log10().floor() as i32);
    (value * scale).round() / scale
}

/// The row "moulds, before → after" of a result whose method moved its panels onto fewer
/// moulds (`before` from its report section, with its rounds).
pub fn before_after(before: Option<usize>, rounds: usize, moulds: Option<&MouldReport>) -> Option<(&'static str, String)> {
    let (before, after) = (before?, moulds?);
    Some(("moulds, before → after", format!("{before} → {} ({rounds} rounds)", after.count)))
}

/// The checkbox of a method's rounds toward fewer moulds, `how` saying what it keeps.
pub fn optimize_moulds_checkbox(ui: &mut egui::Ui, on: &mut bool, how: &str) {
    ui.checkbox(on, "then move the panels onto fewer moulds").on_hover_text(how);
}

/// The result's moulds: their count and tolerance, the table and the count against δ.
pub fn results(ui: &mut egui::Ui, moulds: &MouldReport) {
    let u = moulds.units;
    ui.strong("Moulds");
    ui.label(format!(
        "{} mould{} within δ = {} (largest fit deviation {})",
        moulds.count,
        if moulds.count == 1 { "" } else { "s" },
        format_length(moulds.tolerance, u),
        format_length(moulds.max_deviation, u)
    ));
    let panels = moulds.moulds.iter().map(|m| m.panels).sum();
    ui.label(RichText::new(moulds.snap.describe(panels, u)).small());
    egui::Grid::new("moulds_table").striped(true).show(ui, |ui| {
        ui.label("");
        ui.label(RichText::new(format!("radius ({u})")).small());
        ui.label(RichText::new("panels").small());
        ui.label(RichText::new(format!("max dev. ({u})")).small());
        ui.end_row();
        for m in moulds.moulds.iter().take(TABLE_ROWS) {
            let [r, g, b] = mould_colour(m.id as usize).map(|c| (c * 255.0) as u8);
            let (rect, _) = ui.allocate_exact_size(Vec2::splat(10.0), Sense::hover());
            ui.painter().rect_filled(rect, 2.0, Color32::from_rgb(r, g, b));
            ui.label(m.radius.map_or("flat".into(), |r| format!("{r:.4}")));
            ui.label(m.panels.to_string());
            ui.label(format!("{:.3e}", m.max_deviation));
            ui.end_row();
        }
    });
    if moulds.moulds.len() > TABLE_ROWS {
        ui.label(RichText::new(format!("… and {} more (moulds.csv)", moulds.moulds.len() - TABLE_ROWS)).small());
    }
    against_tolerance(ui, moulds);
}

/// Moulds against δ on log–log axes, the result's δ marked; before the panels moved onto fewer
/// moulds in grey, when they did.
fn against_tolerance(ui: &mut egui::Ui, moulds: &MouldReport) {
    let log = |c: &[(f64, usize)]| -> Vec<(f64, f64)> {
        c.iter().filter(|(t, n)| *t > 0.0 && *n > 0).map(|&(t, n)| (t.log10(), (n as f64).log10())).collect()
    };
    let (after, before) = (log(&moulds.against_tolerance), log(&moulds.against_tolerance_before));
    if after.len() < 2 {
        return;
    }
    let (rect, _) = ui.allocate_exact_size(Vec2::new(ui.available_width().min(260.0), 90.0), Sense::hover());
    let p = ui.painter();
    p.rect_filled(rect, 2.0, Color32::from_gray(30));
    let (x0, x1) = (after[0].0, after[after.len() - 1].0);
    let y1 = after.iter().chain(&before).map(|q| q.1).fold(0.0, f64::max).max(1e-9);
    let at = |(x, y): (f64, f64)| {
        Pos2::new(rect.left() + ((x - x0) / (x1 - x0)) as f32 * rect.width(), rect.bottom() - 4.0 - (y / y1) as f32 * (rect.height() - 18.0))
    };
    if before.len() >= 2 {
        p.add(egui::Shape::line(before.iter().map(|&q| at(q)).collect(), egui::Stroke::new(1.0, Color32::from_gray(140))));
    }
    p.add(egui::Shape::line(after.iter().map(|&q| at(q)).collect(), egui::Stroke::new(1.5, Color32::from_rgb(120, 190, 255))));
    if moulds.tolerance > 0.0 {
        let m = at((moulds.tolerance.log10(), (moulds.count.max(1) as f64).log10()));
        p.circle_filled(m, 3.5, Color32::from_rgb(255, 200, 80));
    }
    let font = egui::FontId::proportional(10.0);
    let u = moulds.units;
    let title =
        if before.len() >= 2 { format!("moulds against δ ({u}), log–log; grey: before") } else { format!("moulds against δ ({u}), log–log") };
    p.text(rect.left_top() + Vec2::new(2.0, 1.0), egui::Align2::LEFT_TOP, title, font.clone(), Color32::LIGHT_GRAY);
    p.text(
        rect.left_bottom() + Vec2::new(2.0, -1.0),
        egui::Align2::LEFT_BOTTOM,
        format!("{:.2e}", 10f64.powf(x0)),
        font.clone(),
        Color32::LIGHT_GRAY,
    );
    p.text(rect.right_bottom() + Vec2::new(-2.0, -1.0), egui::Align2::RIGHT_BOTTOM, format!("{:.2e}", 10f64.powf(x1)), font, Color32::LIGHT_GRAY);
}
