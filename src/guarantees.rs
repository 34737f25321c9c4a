//! What a method promises of its result, measured on the result: one [`Guarantee`] per promise
//! (a figure, its limit and whether it holds), and the [`Verdict`] of a run.
//!
//! A method measures its output with its metrics code, independently of its optimizer's
//! variables, and a run that misses a guarantee is a failure with its figures: the CLI exits with
//! [`MISSED_GUARANTEES_EXIT_CODE`], `report.json` says `meets_guarantees: false`, the app shows it
//! in red. Nothing calls a result exact or done that its verdict does not show.

use std::fmt;

use serde::{Deserialize, Serialize};

/// The CLI's exit code for a run that wrote its files but misses a guarantee (beside 0 done,
/// 1 output not written, 2 bad input or a refusal).
pub const MISSED_GUARANTEES_EXIT_CODE: u8 = 3;

/// Which side of its limit a figure must stay on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Bound {
    AtMost,
    AtLeast,
}

/// Reads a figure that JSON wrote as null (a NaN) back as NaN: `#[serde(deserialize_with)]` on
/// every f64 of a report that can be NaN.
pub(crate) fn f64_or_nan<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Option::<f64>::deserialize(d).map(|x| x.unwrap_or(f64::NAN))
}

/// One promise of a method about its result.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Guarantee {
    /// What is measured, in the report's words ("max_vertex_sphere_residual").
    pub name: String,
    /// The measured figure (NaN is written as null and never holds).
    #[serde(deserialize_with = "f64_or_nan")]
    pub measured: f64,
    pub bound: Bound,
    pub limit: f64,
    /// Its unit as shown to a user: "deg", "of the diagonal", "" for counts.
    pub unit: String,
    pub holds: bool,
    /// Why the figure could not be measured (then `measured` is NaN and it does not hold).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unmeasured: Option<String>,
    /// A length's figure and limit in model units ("0.105 m, limit 0.248 m"), beside its share
    /// of the diagonal.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub in_model_units: Option<String>,
}

impl Guarantee {
    fn new(name: &str, measured: f64, bound: Bound, limit: f64, unit: &str) -> Self {
        let holds = match bound {
            Bound::AtMost => measured <= limit,
            Bound::AtLeast => measured >= limit,
        };
        // A figure that is no number was not measured: it is a miss with a reason, never a NaN.
        let unmeasured = measured.is_nan().then(|| "its figure could not be measured".to_string());
        Self { name: name.into(), measured, bound, limit, unit: unit.into(), holds, unmeasured, in_model_units: None }
    }

    pub(crate) fn at_most(name: &str, measured: f64, limit: f64, unit: &str) -> Self {
        Self::new(name, measured, Bound::AtMost, limit, unit)
    }

    pub(crate) fn at_least(name: &str, measured: f64, limit: f64, unit: &str) -> Self {
        Self::new(name, measured, Bound::AtLeast, limit, unit)
    }

    /// A guarantee whose figure could not be measured, and why: a miss.
    pub(crate) fn unmeasured(self, reason: impl Into<String>) -> Self {
        Self { measured: f64::NAN, holds: false, unmeasured: Some(reason.into()), ..self }
    }

    /// The figure and limit in model units, shown beside the share of the diagonal.
    pub(crate) fn with_model_units(self, text: impl Into<String>) -> Self {
        Self { in_model_units: Some(text.into()), ..self }
    }

    /// ✔ or ✘ and the limit, as a figure's mark in the app ("✔ (≤ 20 deg)").
    pub fn mark(&self) -> String {
        let op = match self.bound {
            Bound::AtMost => "≤",
            Bound::AtLeast => "≥",
        };
        let limit = if self.unit.is_empty() || self.unit == "deg" { format!("{}", self.limit) } else { format!("{:.0e}", self.limit) };
        let unit = if self.unit == "deg" {
            "°".to_string()
        } else if self.unit.is_empty() {
            String::new()
        } else {
            format!(" {}", self.unit)
        };
        format!("{} ({op} {limit}{unit})", if self.holds { "✔" } else { "✘" })
    }

    /// A count that must not exceed `limit`.
    pub(crate) fn count_at_most(name: &str, measured: usize, limit: usize) -> Self {
        Self::at_most(name, measured as f64, limit as f64, "")
    }
}

impl fmt::Display for Guarantee {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let op = match self.bound {
            Bound::AtMost => "≤",
            Bound::AtLeast => "≥",
        };
        let unit = if self.unit.is_empty() { String::new() } else { format!(" {}", self.unit) };
        // Enough digits that a miss does not print as its limit.
        let number = |x: f64, digits: usize| {
            if self.unit.is_empty() || self.unit == "deg" {
                if x.fract() == 0.0 && x.abs() < 1e15 {
                    format!("{x:.0}")
                } else {
                    format!("{x:.digits$}")
                }
            } else {
                format!("{x:.digits$e}")
            }
        };
        let fixed = self.unit.is_empty() || self.unit == "deg";
        let shown = |x: f64, d: usize| if fixed { format!("{x:.d$}") } else { format!("{x:.d$e}") };
        if let Some(reason) = &self.unmeasured {
            return write!(f, "{} not measured: {} (must be {op} {}{})", self.name, reason, number(self.limit, 2), unit);
        }
        let digits = (2..9).find(|&d| shown(self.measured, d) != shown(self.limit, d)).unwrap_or(9);
        let lengths = self.in_model_units.as_ref().map_or(String::new(), |t| format!("; {t}"));
        write!(f, "{} {}{} (must be {op} {}{}{lengths})", self.name, number(self.measured, digits), unit, number(self.limit, 2), unit)
    }
}

/// A share of the diagonal (or of an area) as a percentage a designer reads, to `digits`
/// significant digits: "2.6 %", "0.0031 %", "3.1e-9 %".
fn percent_to(x: f64, digits: usize) -> String {
    let p = 100.0 * x;
    if !p.is_finite() {
        return "an unmeasurable amount".into();
    }
    if p != 0.0 && p.abs() < 1e-6 {
        return format!("{:.*e} %", digits - 1, p);
    }
    let magnitude = if p == 0.0 { 0 } else { p.abs().log10().floor() as i32 };
    let decimals = (digits as i32 - 1 - magnitude).max(0) as usize;
    format!("{p:.decimals$} %")
}

/// A figure and its limit as percentages ([`percent_to`]), with enough digits that a figure
/// that differs from its limit does not read as it.
fn percents(x: f64, limit: f64) -> (String, String) {
    let at = |d| (percent_to(x, d), percent_to(limit, d));
    (2..7).map(at).find(|(a, b)| a != b || x == limit).unwrap_or_else(|| at(7))
}

/// A share as a percentage to two significant digits.
fn percent(x: f64) -> String {
    percent_to(x, 2)
}

/// An angle in degrees, to a tenth.
fn degrees(x: f64) -> String {
    let s = format!("{x:.1}");
    format!("{}°", s.strip_suffix(".0").unwrap_or(&s))
}

impl Guarantee {
    /// The promise in words a designer reads, with the figure and what it must be: "panels are
    /// up to 2.6 % of the model's size off their spheres (must be exact)". The technical line
    /// ([`fmt::Display`]) names the figure as the report does.
    pub fn in_words(&self) -> String {
        let (m, l) = (self.measured, self.limit);
        let n = format!("{m:.0}");
        // "Exact" limits are the methods' numerical zero (≤ 1e-8 of the diagonal).
        let (pm, pl) = percents(m, l);
        let share = if self.bound == Bound::AtMost && l <= 1e-8 { "must be exact".to_string() } else { format!("must be at most {pl}") };
        let most_deg = format!("must be at most {}", degrees(l));
        let least_deg = format!("must be at least {}", degrees(l));
        let none = "must be none".to_string();
        // (what is measured, the sentence with its figure, what it must be)
        let (noun, sentence, must) = match self.name.as_str() {
            "max_vertex_sphere_residual" => (
                "how far panel corners are off their spheres",
                format!("panel corners are up to {} of the model's size off their spheres", percent(m)),
                share,
            ),
            "max_centre_face_planarity" => (
                "how far the sphere centres around a node are off one plane",
                format!("the sphere centres around a node are up to {} of the model's size off one plane", percent(m)),
                share,
            ),
            "max_center_plane_residual" => (
                "how far the sphere centres are off their common plane",
                format!("the sphere centres are up to {} of the model's size off their common plane", percent(m)),
                share,
            ),
            "max_node_axis_offset" if self.unit == "(sine)" => (
                "how far node axes are off parallel",
                format!("node axes are up to {} off parallel", degrees(m.clamp(-1.0, 1.0).asin().to_degrees())),
                "must be exact".into(),
            ),
            "max_node_axis_offset" => (
                "how far node axes miss their common point",
                format!("node axes miss their common point by up to {} of the model's size", percent(m)),
                share,
            ),
            "max_orthogonality_residual" => (
                "how far panel spheres are off orthogonal to the support's sphere Ω",
                format!("panel spheres are off orthogonal to the support's sphere Ω by {m:.1e} of the size squared"),
                "must be exact".into(),
            ),
            "max_distance_to_reference" => (
                "the panels' distance to the design surface",
                format!(
                    "panels are up to {pm} of the model's size from the design surface{}",
                    self.in_model_units.as_ref().map_or(String::new(), |t| format!(" ({t})"))
                ),
                format!("must be at most {pl}"),
            ),
            "coverage" => {
                ("how much of the surface the panels cover", format!("the panels cover {pm} of the surface"), format!("must be at least {pl}"))
            }
            "folded_faces" => ("folded faces", format!("{n} faces are folded over"), none),
            "panels_with_crossing_arcs" => ("panels whose arcs cross", format!("{n} panels have edge arcs that cross"), none),
            "panels_without_exact_surface" => ("panels without an exact surface", format!("{n} panels have no exact surface for CAD"), none),
            "support_elements_that_fold" => ("support elements that fold", format!("{n} support elements fold over"), none),
            "faces" => ("the faces", "the mesh has no faces".into(), "must have at least one".into()),
            "faces_not_quads" => ("faces that are not quads", format!("{n} faces are not quads"), none),
            "quads_without_real_torsal_directions" => (
                "grid quads without real torsal directions",
                format!("{n} grid quads have no real torsal directions, so no support can follow them"),
                none,
            ),
            "max_line_normal_angle_deg" => {
                ("the lines' angle to the normals", format!("the lines lean up to {} from the surface normals", degrees(m)), most_deg)
            }
            "max_axis_normal_angle_deg" => {
                ("the node axes' angle to the normals", format!("node axes lean up to {} from the surface normals", degrees(m)), most_deg)
            }
            "min_torsal_plane_angle_deg" => ("the torsal planes' angle", format!("torsal planes meet at angles down to {}", degrees(m)), least_deg),
            "min_support_plane_angle_deg" => {
                ("the support planes' angle", format!("support planes meet at angles down to {}", degrees(m)), least_deg)
            }
            "min_support_plane_angle_valence_3_deg" => (
                "the support planes' angle at nodes of three edges",
                format!("at nodes of three edges, support planes meet at angles down to {}", degrees(m)),
                least_deg,
            ),
            "min_support_plane_angle_valence_5_deg" => (
                "the support planes' angle at nodes of five edges",
                format!("at nodes of five edges, support planes meet at angles down to {}", degrees(m)),
                least_deg,
            ),
            _ => return self.to_string(),
        };
        match &self.unmeasured {
            Some(reason) => format!("{noun} could not be measured: {reason} ({must})"),
            None => format!("{sentence} ({must})"),
        }
    }
}

/// The guarantees of one run.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Verdict {
    pub guarantees: Vec<Guarantee>,
}

impl Verdict {
    pub fn new(guarantees: Vec<Guarantee>) -> Self {
        Self { guarantees }
    }

    /// Every guarantee holds (and there is at least one).
    pub fn holds(&self) -> bool {
        !self.guarantees.is_empty() && self.guarantees.iter().all(|g| g.holds)
    }

    pub fn failures(&self) -> impl Iterator<Item = &Guarantee> {
        self.guarantees.iter().filter(|g| !g.holds)
    }

    /// The missed guarantees in one line ("" when all hold).
    pub fn failure_text(&self) -> String {
        self.failures().map(|g| g.to_string()).collect::<Vec<_>>().join("; ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_verdict_holds_only_when_every_guarantee_does() {
        let ok = Guarantee::at_most("max_vertex_sphere_residual", 1e-12, 1e-8, "of the diagonal");
        let angle = Guarantee::at_least("min_support_plane_angle_deg", 44.5, 45.0, "deg");
        assert!(ok.holds && !angle.holds);
        assert!(Verdict::new(vec![ok.clone()]).holds());
        let v = Verdict::new(vec![ok, angle]);
        assert!(!v.holds());
        assert_eq!(v.failure_text(), "min_support_plane_angle_deg 44.50 deg (must be ≥ 45 deg)");
        assert!(!Verdict::default().holds(), "no guarantee measured is no verdict");
        assert!(!Guarantee::at_most("x", f64::NAN, 1.0, "").holds, "NaN never holds");
        assert!(!Guarantee::count_at_most("folded_faces", 2, 0).holds);
        let close = Guarantee::at_least("min_support_plane_angle_deg", 89.999_7, 90.0, "deg");
        assert_eq!(close.to_string(), "min_support_plane_angle_deg 89.9997 deg (must be ≥ 90 deg)");
        let nan = Guarantee::at_least("min_support_plane_angle_deg", f64::NAN, 75.0, "deg");
        assert!(!nan.holds && nan.unmeasured.is_some(), "a NaN is a miss with a reason");
        let why = nan.unmeasured("the support planes at vertex 7 meet in no line");
        assert_eq!(why.to_string(), "min_support_plane_angle_deg not measured: the support planes at vertex 7 meet in no line (must be ≥ 75 deg)");
        let d = Guarantee::at_most("max_distance_to_reference", 0.0123, 0.01, "of the diagonal").with_model_units("0.123 m, limit 0.1 m");
        assert_eq!(d.to_string(), "max_distance_to_reference 1.23e-2 of the diagonal (must be ≤ 1.00e-2 of the diagonal; 0.123 m, limit 0.1 m)");
    }

    #[test]
    fn a_guarantee_in_words_gives_its_figure_as_a_designer_reads_it() {
        let residual = Guarantee::at_most("max_vertex_sphere_residual", 2.59e-2, 1e-8, "of the diagonal");
        assert_eq!(residual.in_words(), "panel corners are up to 2.6 % of the model's size off their spheres (must be exact)");
        let tiny = Guarantee::at_most("max_centre_face_planarity", 3.1e-7, 1e-8, "of the diagonal");
        assert_eq!(tiny.in_words(), "the sphere centres around a node are up to 0.000031 % of the model's size off one plane (must be exact)");
        let angle = Guarantee::at_least("min_support_plane_angle_deg", 44.54, 45.0, "deg");
        assert_eq!(angle.in_words(), "support planes meet at angles down to 44.5° (must be at least 45°)");
        let nan = Guarantee::at_least("min_support_plane_angle_deg", f64::NAN, 75.0, "deg").unmeasured("the planes meet in no line");
        assert_eq!(nan.in_words(), "the support planes' angle could not be measured: the planes meet in no line (must be at least 75°)");
        let d = Guarantee::at_most("max_distance_to_reference", 0.0123, 0.01, "of the diagonal").with_model_units("0.123 m, limit 0.1 m");
        assert_eq!(d.in_words(), "panels are up to 1.2 % of the model's size from the design surface (0.123 m, limit 0.1 m) (must be at most 1.0 %)");
        let close = Guarantee::at_most("max_distance_to_reference", 0.001_14, 0.000_96, "of the diagonal");
        assert!(close.in_words().contains("up to 0.11 %") && close.in_words().contains("at most 0.096 %"), "{}", close.in_words());
        let closer = Guarantee::at_least("coverage", 0.9496, 0.95, "of the patch area");
        assert_eq!(closer.in_words(), "the panels cover 94.96 % of the surface (must be at least 95.00 %)");
        assert_eq!(Guarantee::count_at_most("panels_with_crossing_arcs", 3, 0).in_words(), "3 panels have edge arcs that cross (must be none)");
        let words = [residual, tiny, angle, nan, d].map(|g| g.in_words());
        assert!(words.iter().all(|w| !w.contains("NaN") && !w.contains("inf")), "{words:?}");
    }
}
