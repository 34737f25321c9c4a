//! The panel schedule: what a fabricator needs per panel, as CSV and JSON.
//!
//! Per panel: id (= face index), vertex ids and coordinates, the sphere (centre and radius, or
//! for a plane an empty radius and its unit normal), per edge the arc's circle (centre, normal,
//! radius; radius empty for a straight edge), area, and the maximum deviation from the reference
//! surface. Overall: the number of distinct radii after rounding to `radius_tolerance`.
//!
//! Conventions:
//! - radii are absolute values; the JSON also has the signed radius (its sign is the sphere's
//!   orientation, see [`crate::sphere`]);
//! - a panel has 3 or 4 corners; edge k runs from vertex k to vertex k+1 (mod the corner count),
//!   counter-clockwise about its circle normal (see [`crate::panels`]). The CSV has columns for
//!   as many corners as the largest panel (cells of missing corners are empty);
//! - deviation is the largest distance to the reference triangle mesh over the panel's
//!   tessellation vertices and its triangle centroids projected onto the panel sphere (the true
//!   panel surface), in model units; the schedule also gives the maximum relative to the
//!   reference's bounding-box diagonal;
//! - distinct radii: spherical panels are grouped by round(|r| / radius_tolerance); all planar
//!   panels count as one more "radius" (a flat mould), reported separately as `planar_panels`;
//! - moulds ([`crate::panels::moulds`]): the fewest mould radii within the fit tolerance, each
//!   panel's mould id and its fit deviation (the largest distance of its boundary from the mould
//!   placed tangent at its centre); lengths in the design's `units`.

use std::collections::BTreeSet;
use std::fmt::Write;

use serde::{Deserialize, Serialize};

use crate::congruence::support_structure::SupportElement;
use crate::panels::arc::Arc;
use crate::panels::deviation::max_deviation;
use crate::panels::moulds::MouldAssignment;
use crate::panels::panel::Panel;
use crate::reference::Reference;
use crate::units::Units;

/// A panel's sphere in the schedule.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SphereRecord {
    /// Normalized coefficients of ψ(x) = a|x|² − ⟨b, x⟩ + c.
    pub a: f64,
    pub b: [f64; 3],
    pub c: f64,
    pub plane: bool,
    /// Centre; null for a plane.
    pub center: Option<[f64; 3]>,
    /// |r|; null for a plane.
    pub radius: Option<f64>,
    pub signed_radius: Option<f64>,
    /// Unit normal of a plane (its outward side); null for a sphere.
    pub normal: Option<[f64; 3]>,
}

/// One edge arc in the schedule.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ArcRecord {
    /// Mesh vertex ids: the arc runs from `from` to `to`.
    pub from: u32,
    pub to: u32,
    /// Circle centre (chord midpoint for a straight edge).
    pub center: [f64; 3],
    /// Unit normal of the circle's plane; the arc is counter-clockwise about it.
    pub normal: [f64; 3],
    /// Circle radius; null for a straight edge.
    pub radius: Option<f64>,
    pub straight: bool,
    /// Angle swept, in degrees (0 when straight).
    pub sweep_deg: f64,
    pub length: f64,
}

/// One panel in the schedule.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PanelRecord {
    pub id: usize,
    /// The corners (3 or 4), in order.
    pub vertex_ids: Vec<u32>,
    pub vertices: Vec<[f64; 3]>,
    pub sphere: SphereRecord,
    /// Edge k from corner k to corner k + 1.
    pub edges: Vec<ArcRecord>,
    pub area: f64,
    /// Largest distance to the reference, model units.
    pub max_deviation: f64,
    /// Tessellation triangles of this panel.
    pub triangles: usize,
    /// Its mould (an id of [`PanelSchedule::moulds`]) and the largest distance of its boundary
    /// from that mould, model units.
    #[serde(default)]
    pub mould: u32,
    #[serde(default)]
    pub mould_deviation: f64,
    /// Whether its sphere has exactly its mould's radius (cut from it with no deviation).
    #[serde(default)]
    pub mould_snapped: bool,
}

/// One mould: every panel of this radius is cut from it, either way up.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MouldRecord {
    pub id: u32,
    /// Model units; null for a flat mould.
    pub radius: Option<f64>,
    pub curvature: f64,
    pub panels: usize,
    /// The largest fit deviation of its panels, model units.
    pub max_deviation: f64,
}

impl MouldRecord {
    pub fn of(moulds: &MouldAssignment) -> Vec<MouldRecord> {
        moulds
            .moulds
            .iter()
            .enumerate()
            .map(|(id, m)| MouldRecord { id: id as u32, radius: m.radius, curvature: m.curvature, panels: m.panels, max_deviation: m.max_deviation })
            .collect()
    }

    /// The mould table as CSV: a header and one row each.
    pub fn to_csv(records: &[MouldRecord], units: Units) -> String {
        let mut out = format!("mould,radius_{units},curvature_per_{units},panels,max_deviation_{units}\n");
        for r in records {
            let _ = write!(out, "{},", r.id);
            opt(&mut out, r.radius);
            let _ = writeln!(out, ",{},{},{}", r.curvature, r.panels, r.max_deviation);
        }
        out
    }
}

/// The whole schedule.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PanelSchedule {
    pub panel_count: usize,
    pub radius_tolerance: f64,
    /// Distinct |r| after rounding to `radius_tolerance`, planar panels counting as one more.
    pub distinct_radii: usize,
    pub planar_panels: usize,
    pub total_area: f64,
    /// Bounding-box diagonal of the reference.
    pub reference_diagonal: f64,
    /// Largest panel deviation, model units.
    pub max_deviation: f64,
    /// `max_deviation / reference_diagonal` (the report's `max_distance_to_reference`).
    pub max_deviation_relative: f64,
    /// The distinct |r| (rounded to `radius_tolerance`), ascending.
    #[serde(default)]
    pub radii: Vec<f64>,
    pub panels: Vec<PanelRecord>,
    /// The support structure's planar elements (methods with support structure).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub support_elements: Vec<SupportRecord>,
    /// What one model unit is.
    #[serde(default)]
    pub units: Units,
    /// The fit tolerance of the moulds, model units.
    #[serde(default)]
    pub mould_tolerance: f64,
    #[serde(default)]
    pub moulds: Vec<MouldRecord>,
}

/// One planar support element in the schedule: its plane and its corners.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SupportRecord {
    pub id: usize,
    /// The mesh edge (vertex ids) it stands on.
    pub edge: [u32; 2],
    /// Its plane: a point (the centre of the edge's circle) and the unit normal.
    pub plane_point: [f64; 3],
    pub plane_normal: [f64; 3],
    /// The edge's two vertices, then the inner corners on the node axes of the second and the
    /// first vertex.
    pub corners: [[f64; 3]; 4],
    /// Radii of the outer (edge) arc and the inner arc.
    pub outer_radius: f64,
    pub inner_radius: f64,
}

impl SupportRecord {
    pub fn of(elements: &[SupportElement]) -> Vec<SupportRecord> {
        elements
            .iter()
            .enumerate()
            .map(|(id, e)| SupportRecord {
                id,
                edge: e.edge,
                plane_point: e.circle.center.to_array(),
                plane_normal: e.circle.normal.to_array(),
                corners: e.corners.map(|c| c.to_array()),
                outer_radius: e.circle.radius,
                inner_radius: e.inner_circle.radius,
            })
            .collect()
    }

    /// CSV of the records: a header and one row each.
    pub fn to_csv(records: &[SupportRecord]) -> String {
        let mut out = String::from("id,v0_id,v1_id,plane_x,plane_y,plane_z,normal_x,normal_y,normal_z");
        for k in 0..4 {
            let _ = write!(out, ",c{k}_x,c{k}_y,c{k}_z");
        }
        out.push_str(",outer_radius,inner_radius\n");
        for r in records {
            let [p, n] = [r.plane_point, r.plane_normal];
            let _ = write!(out, "{},{},{},{},{},{},{},{},{}", r.id, r.edge[0], r.edge[1], p[0], p[1], p[2], n[0], n[1], n[2]);
            for c in &r.corners {
                let _ = write!(out, ",{},{},{}", c[0], c[1], c[2]);
            }
            let _ = writeln!(out, ",{},{}", r.outer_radius, r.inner_radius);
        }
        out
    }
}

/// Number of distinct radii: `Some(r)` values grouped by round(|r|/tolerance) (exact |r| when
/// tolerance ≤ 0 or not finite), plus one for any `None` (planes). Non-finite radii count as
/// planes.
pub fn count_distinct_radii(radii: impl IntoIterator<Item = Option<f64>>, tolerance: f64) -> usize {
    let mut keys: BTreeSet<u64> = BTreeSet::new();
    let mut plane = false;
    for r in radii {
        match r.filter(|r| r.is_finite()) {
            None => plane = true,
            Some(r) => {
                let r = r.abs();
                let key = if tolerance > 0.0 && tolerance.is_finite() { (r / tolerance).round() } else { r };
                if key.is_finite() {
                    keys.insert(key.to_bits());
                } else {
                    plane = true;
                }
            }
        }
    }
    keys.len() + usize::from(plane)
}

/// The distinct |r| of `radii` (planes left out), rounded to `tolerance`, ascending.
pub fn distinct_radii(radii: impl IntoIterator<Item = Option<f64>>, tolerance: f64) -> Vec<f64> {
    let mut keys: BTreeSet<u64> = BTreeSet::new();
    let round = tolerance > 0.0 && tolerance.is_finite();
    for r in radii.into_iter().flatten().filter(|r| r.is_finite()) {
        let r = r.abs();
        let v = if round { (r / tolerance).round() * tolerance } else { r };
        keys.insert(v.to_bits());
    }
    keys.into_iter().map(f64::from_bits).collect()
}

fn arc_record(arc: &Arc, from: u32, to: u32) -> ArcRecord {
    let straight = arc.is_straight();
    ArcRecord {
        from,
        to,
        center: arc.circle.center.to_array(),
        normal: arc.circle.normal.to_array(),
        radius: (!straight).then_some(arc.circle.radius),
        straight,
        sweep_deg: arc.sweep().to_degrees(),
        length: arc.length(),
    }
}

fn sphere_record(p: &Panel) -> SphereRecord {
    let s = p.sphere;
    let plane = p.is_planar();
    let signed = if plane { None } else { s.signed_radius() };
    SphereRecord {
        a: s.a,
        b: s.b.to_array(),
        c: s.c,
        plane,
        center: if plane { None } else { s.center().map(|c| c.to_array()) },
        radius: signed.map(f64::abs),
        signed_radius: signed,
        normal: plane.then(|| s.b.normalize_or_zero().to_array()),
    }
}

/// Builds the schedule of `panels` against the `reference` surface (every panel on mould 0 of
/// no table: [`PanelSchedule::with_moulds`] adds them).
pub fn build_schedule(panels: &[Panel], reference: &Reference, radius_tolerance: f64) -> PanelSchedule {
    build_schedule_with(panels, reference, radius_tolerance, None)
}

/// [`build_schedule`] with each panel's [`max_deviation`] from `reference` given (when the
/// method measured them already; one per panel).
pub fn build_schedule_with(panels: &[Panel], reference: &Reference, radius_tolerance: f64, deviations: Option<&[f64]>) -> PanelSchedule {
    let deviations = deviations.filter(|d| d.len() == panels.len());
    let diag = reference.diagonal();
    let records: Vec<PanelRecord> = panels
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let c = &p.corners;
            let n = c.len();
            PanelRecord {
                id: p.face,
                vertex_ids: c.clone(),
                vertices: p.positions[..n].iter().map(|x| x.to_array()).collect(),
                sphere: sphere_record(p),
                edges: (0..n).map(|k| arc_record(&p.arcs[k], c[k], c[(k + 1) % n])).collect(),
                area: p.area,
                max_deviation: match deviations {
                    Some(d) => d[i],
                    None if reference.bvh().is_empty() => f64::NAN,
                    None => max_deviation(p, reference),
                },
                triangles: p.triangles.len(),
                mould: 0,
                mould_deviation: 0.0,
                mould_snapped: false,
            }
        })
        .collect();
    let max_dev = records.iter().map(|r| r.max_deviation).fold(0.0, f64::max);
    let radii = distinct_radii(records.iter().map(|r| r.sphere.radius), radius_tolerance);
    PanelSchedule {
        radii,
        support_elements: Vec::new(),
        panel_count: records.len(),
        radius_tolerance,
        distinct_radii: count_distinct_radii(records.iter().map(|r| r.sphere.radius), radius_tolerance),
        planar_panels: records.iter().filter(|r| r.sphere.plane).count(),
        total_area: records.iter().map(|r| r.area).sum(),
        reference_diagonal: diag,
        max_deviation: max_dev,
        max_deviation_relative: if diag > 0.0 { max_dev / diag } else { max_dev },
        panels: records,
        units: Units::default(),
        mould_tolerance: 0.0,
        moulds: Vec::new(),
    }
}

fn opt(out: &mut String, v: Option<f64>) {
    if let Some(v) = v {
        let _ = write!(out, "{v}");
    }
}

fn opt3(out: &mut String, v: Option<[f64; 3]>) {
    match v {
        Some([x, y, z]) => {
            let _ = write!(out, "{x},{y},{z}");
        }
        None => out.push_str(",,"),
    }
}

impl PanelSchedule {
    /// The schedule with its moulds (one per panel in `moulds`, in panel order) in `units`, and
    /// which panels have exactly their mould's radius.
    pub fn with_moulds(mut self, moulds: &MouldAssignment, snapped: &[bool], units: Units) -> Self {
        for (i, (r, (&m, &d))) in self.panels.iter_mut().zip(moulds.panel_mould.iter().zip(&moulds.panel_deviation)).enumerate() {
            r.mould = m;
            r.mould_deviation = d;
            r.mould_snapped = snapped.get(i).copied().unwrap_or(false);
        }
        self.units = units;
        self.mould_tolerance = moulds.tolerance;
        self.moulds = MouldRecord::of(moulds);
        self
    }

    /// Corners of the largest panel (3 when there are none).
    pub(crate) fn max_corners(&self) -> usize {
        self.panels.iter().map(|r| r.vertex_ids.len()).max().unwrap_or(3)
    }

    /// CSV header for panels of up to `corners` corners (one line, no trailing newline).
    pub fn csv_header(corners: usize) -> String {
        let mut h: Vec<String> = vec!["id".into()];
        let xyz = |h: &mut Vec<String>, name: &str| h.extend(["x", "y", "z"].map(|c| format!("{name}_{c}")));
        h.extend((0..corners).map(|k| format!("v{k}_id")));
        for k in 0..corners {
            xyz(&mut h, &format!("v{k}"));
        }
        xyz(&mut h, "sphere_center");
        h.push("sphere_radius".into());
        xyz(&mut h, "plane_normal");
        for k in 0..corners {
            xyz(&mut h, &format!("edge{k}_center"));
            xyz(&mut h, &format!("edge{k}_normal"));
            h.push(format!("edge{k}_radius"));
        }
        h.push("area".into());
        h.push("max_deviation".into());
        h.push("mould".into());
        h.push("mould_deviation".into());
        h.push("mould_snapped".into());
        h.join(",")
    }

    /// The schedule as CSV: a header and one row per panel, with columns for the largest
    /// panel's corners. Missing values (plane radius and centre, sphere normal, straight-edge
    /// radius, the corners and edges a triangle lacks among quads) are empty cells. Overall
    /// values are not in the CSV; they are in the JSON.
    pub fn to_csv(&self) -> String {
        let corners = self.max_corners();
        let mut out = Self::csv_header(corners);
        out.push('\n');
        for r in &self.panels {
            let _ = write!(out, "{}", r.id);
            for k in 0..corners {
                match r.vertex_ids.get(k) {
                    Some(v) => {
                        let _ = write!(out, ",{v}");
                    }
                    None => out.push(','),
                }
            }
            for k in 0..corners {
                match r.vertices.get(k) {
                    Some(v) => {
                        let _ = write!(out, ",{},{},{}", v[0], v[1], v[2]);
                    }
                    None => out.push_str(",,,"),
                }
            }
            out.push(',');
            opt3(&mut out, r.sphere.center);
            out.push(',');
            opt(&mut out, r.sphere.radius);
            out.push(',');
            opt3(&mut out, r.sphere.normal);
            for k in 0..corners {
                match r.edges.get(k) {
                    Some(e) => {
                        let _ = write!(out, ",{},{},{},{},{},{},", e.center[0], e.center[1], e.center[2], e.normal[0], e.normal[1], e.normal[2]);
                        opt(&mut out, e.radius);
                    }
                    None => out.push_str(",,,,,,,"),
                }
            }
            let _ = write!(out, ",{},", r.area);
            opt(&mut out, Some(r.max_deviation).filter(|d| d.is_finite()));
            let _ = writeln!(out, ",{},{},{}", r.mould, r.mould_deviation, u8::from(r.mould_snapped));
        }
        out
    }

    /// The schedule as pretty-printed JSON (non-finite numbers become null).
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("the schedule serializes")
    }
}
