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
}

impl Guarantee {
    pub(crate) fn at_most(name: &str, measured: f64, limit: f64, unit: &str) -> Self {
        Self { name: name.into(), measured, bound: Bound::AtMost, limit, unit: unit.into(), holds: measured <= limit }
    }

    pub(crate) fn at_least(name: &str, measured: f64, limit: f64, unit: &str) -> Self {
        Self { name: name.into(), measured, bound: Bound::AtLeast, limit, unit: unit.into(), holds: measured >= limit }
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
                if x.fract() == 0.0 && x.abs() < 1e15 { format!("{x:.0}") } else { format!("{x:.digits$}") }
            } else {
                format!("{x:.digits$e}")
            }
        };
        let fixed = self.unit.is_empty() || self.unit == "deg";
        let shown = |x: f64, d: usize| if fixed { format!("{x:.d$}") } else { format!("{x:.d$e}") };
        let digits = (2..9).find(|&d| shown(self.measured, d) != shown(self.limit, d)).unwrap_or(9);
        write!(f, "{} {}{} (must be {op} {}{})", self.name, number(self.measured, digits), unit, number(self.limit, 2), unit)
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
    }
}
