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
}
