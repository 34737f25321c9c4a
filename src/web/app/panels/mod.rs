//! The side panel's shared sections and widgets: the reference's info, remeshing controls, the
//! verdict, the warnings and the moulds of every panel method. Each method's own controls and results are its view's
//! ([`super::views`]).

pub mod info;
pub mod moulds;

use crate::guarantees::Guarantee;
use crate::remeshing::{Sizing, SizingKind, DEFAULT_EPSILON, DEFAULT_FACES, EPSILON_RANGE, FACES_RANGE};

/// ε and N as last set, so that switching the sizing kind back and forth keeps them.
#[derive(Clone, Copy, Debug)]
pub struct SizingMemory {
    pub epsilon: f64,
    pub faces: usize,
}

impl SizingMemory {
    /// Remembers the values of `sizing`, defaults for the others.
    pub fn of(sizing: Sizing) -> Self {
        let mut m = Self { epsilon: DEFAULT_EPSILON, faces: DEFAULT_FACES };
        m.remember(sizing);
        m
    }

    pub fn remember(&mut self, sizing: Sizing) {
        match sizing {
            Sizing::Adaptive { epsilon } => self.epsilon = epsilon,
            Sizing::UniformFaces(n) => self.faces = n,
            Sizing::None => {}
        }
    }
}

/// Remeshing controls: kind, ε (log slider) or the face count.
pub fn sizing_controls(ui: &mut egui::Ui, id: &str, sizing: &mut Sizing, memory: &mut SizingMemory, kinds: &[SizingKind]) {
    let mut kind = SizingKind::of(*sizing);
    egui::ComboBox::from_id_salt(id).selected_text(kind.label()).show_ui(ui, |ui| {
        for &k in kinds {
            ui.selectable_value(&mut kind, k, k.label());
        }
    });
    let (mut epsilon, mut faces) = (memory.epsilon, memory.faces);
    match kind {
        SizingKind::Adaptive => {
            ui.add(
                egui::Slider::new(&mut epsilon, EPSILON_RANGE.lo.max(2e-5)..=EPSILON_RANGE.hi.min(1e-2))
                    .logarithmic(true)
                    .text("ε")
                    .custom_formatter(|x, _| format!("{x:.2e}")),
            )
            .on_hover_text("Distance tolerance of the influence zones, relative to the bbox diagonal (Sec. 3): smaller ε, smaller faces");
        }
        SizingKind::Faces => {
            // The methods' own cap: more faces are refused with an offer to remesh.
            ui.add(egui::Slider::new(&mut faces, FACES_RANGE.lo.max(50)..=crate::remeshing::MAX_METHOD_FACES).logarithmic(true).text("faces"));
        }
        SizingKind::None => {}
    }
    *sizing = kind.sizing(epsilon, faces);
    memory.remember(*sizing);
}

/// The panels' promised largest distance to the reference, relative to the bbox diagonal
/// ([`crate::panels::buildability::MAX_DISTANCE_RANGE`]): a result farther away misses it.
pub fn max_distance_slider(ui: &mut egui::Ui, max_distance: &mut f64) {
    let range = crate::panels::buildability::MAX_DISTANCE_RANGE;
    ui.add(
        egui::Slider::new(max_distance, range.lo.max(1e-4)..=range.hi.min(0.1))
            .logarithmic(true)
            .text("max distance")
            .custom_formatter(|x, _| format!("{x:.2e}")),
    )
    .on_hover_text(
        "The panels' promised largest distance to the reference, relative to the bbox diagonal: a result farther away misses its guarantees",
    );
}

/// A figure's mark as the run's verdict grades it: " ✔ (≤ 20°)" from the report's guarantee
/// `name`, or nothing when the method promises nothing of that figure. The app never grades a
/// figure itself: the report's limits are the run's, not the sliders' now.
pub fn graded(report: &crate::export::Report, name: &str) -> String {
    report.guarantees.iter().find(|g| g.name == name).map_or(String::new(), |g| format!(" {}", g.mark()))
}

/// The colour of a result that misses its guarantees.
pub const MISSED_COLOR: egui::Color32 = egui::Color32::from_rgb(235, 80, 70);
/// The colour of a result that meets them.
pub const MET_COLOR: egui::Color32 = egui::Color32::from_rgb(120, 200, 120);

/// A result's verdict as the app shows it, worded once when the result arrives (not at every
/// frame).
pub struct ShownVerdict {
    pub holds: bool,
    /// Each missed guarantee in a designer's words, and as the report names it.
    pub misses: Vec<(String, String)>,
    /// The status bar's line: the first miss in words and how many more.
    pub line: String,
    /// Every miss as the report names it.
    pub technical: String,
}

impl ShownVerdict {
    pub fn of(guarantees: &[Guarantee]) -> Self {
        let misses: Vec<(String, String)> = guarantees.iter().filter(|g| !g.holds).map(|g| (g.in_words(), g.to_string())).collect();
        let first = misses.first().map_or("", |m| m.0.as_str());
        let line = match misses.len() {
            0 | 1 => format!("The result misses its guarantees: {first}"),
            n => format!("The result misses {n} guarantees: {first}, and {} more (see the side panel)", n - 1),
        };
        let technical = misses.iter().map(|m| m.1.as_str()).collect::<Vec<_>>().join("; ");
        Self { holds: !guarantees.is_empty() && misses.is_empty(), misses, line, technical }
    }
}

/// The verdict at the top of the results: each missed guarantee in a designer's words (its
/// figure as the report names it on hover), or a check mark.
pub fn verdict(ui: &mut egui::Ui, v: &ShownVerdict) -> egui::Response {
    ui.scope(|ui| {
        if v.holds {
            ui.colored_label(MET_COLOR, "✔ Meets every guarantee (see the figures below)");
            return;
        }
        ui.colored_label(MISSED_COLOR, egui::RichText::new("✘ The result misses its guarantees:").strong());
        for (words, technical) in &v.misses {
            ui.colored_label(MISSED_COLOR, format!("• {words}")).on_hover_text(technical);
        }
    })
    .response
}

/// Above a failed result's downloads: that they come from it, and its misses.
pub fn missed_above_downloads(ui: &mut egui::Ui, v: &ShownVerdict) {
    ui.colored_label(MISSED_COLOR, egui::RichText::new(format!("✘ {}; build from these files at your own risk.", v.line)).small())
        .on_hover_text(&v.technical);
}

/// A report's warnings (failed assumptions of the reference, fallbacks), in amber.
pub fn warnings(ui: &mut egui::Ui, warnings: &[String]) {
    for w in warnings {
        ui.colored_label(egui::Color32::from_rgb(240, 180, 80), w);
    }
}
