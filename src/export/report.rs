//! `report.json`: the run report every method writes, typed. Schema [`REPORT_SCHEMA`]:
//!
//! ```json
//! {"schema": 3,
//!  "method": "st-support",
//!  "input":  {"vertices": N, "faces": N},
//!  "output": {"vertices": N, "faces": N, "panels": N},
//!  "metrics": {"mean_kink_angle_deg": x, "max_kink_angle_deg": x,
//!              "max_distance_to_reference": x, "distinct_radii": N,
//!              "units": "m", "diagonal": x, "max_distance": x},
//!  "moulds": {"units": "m", "target": {...}, "tolerance": x, "tolerance_relative": x,
//!             "count": N, "max_deviation": x, "moulds": [{"id", "radius", ...}],
//!             "against_tolerance": [[tolerance, count], ...]},
//!  "st-support": {...},
//!  "timings_ms": {"<stage>": x, ...},
//!  "warnings": ["..."],
//!  "meets_guarantees": true, "guarantees": [{"name": "...", "measured": x, ...}]}
//! ```
//!
//! `metrics` is the shared section: what every panel method measures on its panels (left out
//! when a run made none, e.g. SQ stopped after its congruence). The method's own section sits
//! under its name (`"st"`, `"st-support"`, `"sq"`), written by the method from its own type; this
//! file knows no method. Lengths are relative to the bounding-box diagonal, except those of
//! `moulds` and `metrics.diagonal` / `metrics.max_distance`, which are in model units (`units`);
//! angles are in degrees. Timings are in milliseconds, keyed by stage name (sorted). Non-finite numbers
//! are written as null.

use std::collections::BTreeMap;
use std::io;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::export::schedule::MouldRecord;
use crate::guarantees::{f64_or_nan, Guarantee, Verdict};
use crate::panels::moulds::{MouldTarget, SnapLimit};
use crate::units::Units;

/// The layout version of `report.json`, raised whenever a key moves. 3: model units and the
/// shared `moulds`; 2: the shared `metrics` and one section per method (1 had one flat
/// `metrics` of every method's keys).
pub const REPORT_SCHEMA: u32 = 3;

/// Vertex and face counts of the input mesh.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct InputCounts {
    pub vertices: usize,
    pub faces: usize,
}

/// Vertex, face and panel counts of the result (the mesh with spherical faces).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct OutputCounts {
    pub vertices: usize,
    pub faces: usize,
    pub panels: usize,
}

/// The shared section: what the export measures on every method's panels (lengths relative to
/// the diagonal of the mesh the method ran on, angles in degrees). How exactly the vertices lie
/// on their spheres is each method's own figure, in its section.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PanelMetrics {
    /// Kink angles between adjacent panels over the interior edges.
    #[serde(deserialize_with = "f64_or_nan")]
    pub mean_kink_angle_deg: f64,
    #[serde(deserialize_with = "f64_or_nan")]
    pub max_kink_angle_deg: f64,
    /// Sampled over the panel surfaces, to the reference as loaded (the schedule's).
    #[serde(deserialize_with = "f64_or_nan")]
    pub max_distance_to_reference: f64,
    /// Distinct panel radii after rounding to the radius tolerance (planes count as one more).
    pub distinct_radii: usize,
    /// What one model unit is; the diagonal and the largest distance in model units.
    #[serde(default)]
    pub units: Units,
    #[serde(default, deserialize_with = "f64_or_nan")]
    pub diagonal: f64,
    #[serde(default, deserialize_with = "f64_or_nan")]
    pub max_distance: f64,
}

impl PanelMetrics {
    /// The panels' largest distance to the reference in model units, with its share of the
    /// diagonal ("0.02083 m, 4.85e-4 of the diagonal").
    pub fn max_distance_text(&self) -> String {
        let relative = format!("{:.2e} of the diagonal", self.max_distance_to_reference);
        if self.max_distance.is_finite() {
            format!("{}, {relative}", crate::units::format_length(self.max_distance, self.units))
        } else {
            relative
        }
    }
}

/// The shared moulds section: the fewest moulds the panels need within the fit tolerance
/// ([`crate::panels::moulds`]), lengths in model units.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MouldReport {
    pub units: Units,
    /// As asked: a tolerance, or a count.
    pub target: MouldTarget,
    /// The fit tolerance δ (the smallest one for the count, when a count was asked).
    pub tolerance: f64,
    pub tolerance_relative: f64,
    pub count: usize,
    /// The largest fit deviation of any panel (≤ `tolerance`).
    pub max_deviation: f64,
    pub moulds: Vec<MouldRecord>,
    /// Moulds needed against the tolerance: (tolerance, count) pairs, ascending.
    pub against_tolerance: Vec<(f64, usize)>,
    /// The same before the method moved its panels onto fewer moulds (empty when it did not).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub against_tolerance_before: Vec<(f64, usize)>,
    /// The panels cut from their mould with no deviation, and why the others are not.
    #[serde(default)]
    pub snap: SnapReport,
}

/// How many panels have exactly their mould's radius (measured on the panels, to
/// [`crate::panels::moulds::SNAPPED`] of the diagonal), and the others by reason.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SnapReport {
    pub snapped: usize,
    pub not_snapped: Vec<SnapMisses>,
}

impl SnapReport {
    /// In words: how many of `panels` have exactly their mould's radius, and why the others
    /// do not, with their largest fit deviation (in `units`).
    pub fn describe(&self, panels: usize, units: Units) -> String {
        let mut text = format!("{} of {panels} panel{} snapped to their mould's radius", self.snapped, if panels == 1 { "" } else { "s" });
        for m in &self.not_snapped {
            text += &format!("; {} not ({}, up to {} off)", m.panels, m.reason.describe(), crate::units::format_length(m.max_deviation, units));
        }
        text
    }
}

/// The panels not snapped for one reason: how many, and by how much they miss (their largest
/// fit deviation and radius difference from their mould, model units).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SnapMisses {
    pub reason: SnapLimit,
    pub panels: usize,
    pub max_deviation: f64,
    /// None when a flat panel or mould makes the difference infinite.
    pub max_radius_miss: Option<f64>,
}

/// The exact surfaces written to `panels.step`: how many panels and support elements are exact
/// patches, and those that are not, with why.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ExactSurfacesReport {
    pub panels: usize,
    pub support_elements: usize,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub refused: Vec<RefusedSurface>,
}

/// What has no exact patch.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum SurfaceKind {
    #[serde(rename = "panel")]
    Panel,
    #[serde(rename = "support element")]
    SupportElement,
}

impl std::fmt::Display for SurfaceKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            SurfaceKind::Panel => "panel",
            SurfaceKind::SupportElement => "support element",
        })
    }
}

/// A panel or support element without an exact patch, and why.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RefusedSurface {
    pub kind: SurfaceKind,
    pub id: usize,
    pub reason: String,
}

impl ExactSurfacesReport {
    pub fn of(exact: &crate::panels::exact_surface::ExactSurfaces) -> Self {
        let refused = |kind: SurfaceKind, list: &[Result<_, crate::panels::exact_surface::ExactSurfaceError>]| -> Vec<RefusedSurface> {
            list.iter()
                .enumerate()
                .filter_map(|(id, r): (usize, &Result<crate::geometry::rational_bezier::RationalPatch, _>)| {
                    r.as_ref().err().map(|e| RefusedSurface { kind, id, reason: e.to_string() })
                })
                .collect()
        };
        let mut all = refused(SurfaceKind::Panel, &exact.panels);
        all.extend(refused(SurfaceKind::SupportElement, &exact.support));
        Self {
            panels: exact.panels.iter().filter(|p| p.is_ok()).count(),
            support_elements: exact.support.iter().filter(|p| p.is_ok()).count(),
            refused: all,
        }
    }

    /// "240 panels and 449 support elements as rational NURBS surfaces …", and what is missing.
    pub fn describe(&self) -> String {
        let mut text =
            format!("{} panels and {} support elements as rational NURBS surfaces on their spheres and planes", self.panels, self.support_elements);
        if !self.refused.is_empty() {
            let ids: Vec<String> = self.refused.iter().take(5).map(|r| format!("{} {} ({})", r.kind, r.id, r.reason)).collect();
            text += &format!("; {} without one: {}{}", self.refused.len(), ids.join(", "), if self.refused.len() > 5 { ", …" } else { "" });
        }
        text
    }
}

/// The report of one run.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Report {
    /// [`REPORT_SCHEMA`].
    #[serde(default)]
    pub schema: u32,
    pub method: String,
    pub input: InputCounts,
    pub output: OutputCounts,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub metrics: Option<PanelMetrics>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub moulds: Option<MouldReport>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub exact_surfaces: Option<ExactSurfacesReport>,
    /// The method's own section, under its name ([`Self::set_section`], [`Self::section`]).
    #[serde(flatten)]
    pub sections: BTreeMap<String, serde_json::Value>,
    pub timings_ms: BTreeMap<String, f64>,
    /// What a user should know about the run (e.g. a boundary strip of the other sign of H).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    /// Whether the result meets every guarantee of its method ([`crate::guarantees`]), and
    /// each guarantee with its measured figure; left out by a method that measures none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub meets_guarantees: Option<bool>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub guarantees: Vec<Guarantee>,
}

impl Report {
    pub fn new(method: impl Into<String>) -> Self {
        Self { schema: REPORT_SCHEMA, method: method.into(), ..Self::default() }
    }

    /// Writes the method's own section, under its name.
    pub fn set_section(&mut self, section: &impl Serialize) {
        let value = serde_json::to_value(section).expect("a report section serializes");
        self.sections.insert(self.method.clone(), value);
    }

    /// The method's own section, read as its type; None when absent or of another shape.
    pub fn section<T: serde::de::DeserializeOwned>(&self) -> Option<T> {
        serde_json::from_value(self.sections.get(&self.method)?.clone()).ok()
    }

    /// Records step timings (ms, in order; a repeated step adds up).
    pub(crate) fn add_timings(&mut self, timings: &[(String, f64)]) {
        for (step, ms) in timings {
            self.add_timing(step.clone(), *ms);
        }
    }

    /// Records the verdict of the run.
    pub fn set_verdict(&mut self, verdict: &Verdict) {
        self.meets_guarantees = Some(verdict.holds());
        self.guarantees = verdict.guarantees.clone();
    }

    /// The missed guarantees in one line, "" when there are none.
    pub fn failure_text(&self) -> String {
        Verdict::new(self.guarantees.clone()).failure_text()
    }

    /// Records a stage time (ms); a repeated stage adds up.
    pub fn add_timing(&mut self, stage: impl Into<String>, ms: f64) {
        *self.timings_ms.entry(stage.into()).or_insert(0.0) += ms;
    }

    /// Pretty-printed JSON with a trailing newline.
    pub fn to_json(&self) -> String {
        let mut s = serde_json::to_string_pretty(self).expect("the report serializes");
        s.push('\n');
        s
    }

    pub fn from_json(text: &str) -> serde_json::Result<Self> {
        serde_json::from_str(text)
    }

    /// Writes `dir/report.json` (creating `dir`); returns the path.
    pub fn write(&self, dir: &Path) -> io::Result<PathBuf> {
        std::fs::create_dir_all(dir)?;
        let path = dir.join("report.json");
        std::fs::write(&path, self.to_json())?;
        Ok(path)
    }
}
