//! Exports of a panelled mesh (issue 3, §4 and §6): GLB ([`glb`]), OBJ ([`obj`]), the panel
//! schedule as CSV and JSON ([`schedule`]) and the `report.json` shared by every method
//! ([`report`]). [`closest`] holds the closest-point queries (a triangle BVH) used for the
//! deviation from the reference.
//!
//! The geometry written is exactly what [`crate::panels::build_panels`] tessellated, plus the
//! support structure ([`SupportGeometry`], [`support_geometry`]) and the node axes as line
//! segments ([`node_axis_segments`]).

pub mod closest;
pub mod glb;
pub mod obj;
pub mod report;
pub mod schedule;

use std::collections::BTreeMap;
use std::io;
use std::path::Path;

use glam::DVec3;

use crate::mesh::TriMesh;
use crate::panels::Panel;
use crate::sphere_mesh::SupportStructure;

pub use glb::{absolute_sphere_extras, write_glb};
pub use obj::write_obj;
pub use report::{AbsoluteSphereReport, Metrics, Report};
pub use schedule::{build_schedule, count_distinct_radii, max_deviation, max_distance_to_reference, PanelSchedule};

/// Triangles of the support structure: one planar strip per edge.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SupportGeometry {
    pub positions: Vec<DVec3>,
    pub triangles: Vec<[u32; 3]>,
}

impl SupportGeometry {
    pub fn to_mesh(&self) -> TriMesh {
        TriMesh::new(self.positions.clone(), self.triangles.clone())
    }
}

/// The support elements as triangle strips (issue 3, §3): for every mesh edge, the planar strip
/// between its arc, with exactly the points the panels use, and the offset of those points by
/// `support.depth` toward the node axes' common point.
///
/// The offset direction at an arc point x is toward the point m′ where the edge's two node axes
/// meet (m for an ST mesh with support structure; the midpoint of their common perpendicular if
/// they are skew), signed like the axes; with parallel axes (Ω at infinity) it is the normalized
/// interpolation of the two axis directions. At the two vertices the offset runs exactly along
/// their node axes, so the strip is bounded by the arc, the two node-axis segments and the inner
/// curve. For an ST mesh the node axes lie in the arc's plane, so the strip is planar.
///
/// Each edge is taken once, from the panel with the lower face index. A depth ≤ 0 (or missing
/// node axes) gives no strip. The depth is not clamped: a depth beyond m folds the strip.
pub fn support_geometry(panels: &[Panel], support: &SupportStructure) -> SupportGeometry {
    let mut out = SupportGeometry::default();
    let depth = support.depth;
    if !depth.is_finite() || depth <= 0.0 {
        return out;
    }
    let mut seen: BTreeMap<(u32, u32), ()> = BTreeMap::new();
    for panel in panels {
        for k in 0..3 {
            let (a, b) = (panel.corners[k], panel.corners[(k + 1) % 3]);
            let key = (a.min(b), a.max(b));
            if seen.insert(key, ()).is_some() {
                continue;
            }
            let (Some(&(_, da)), Some(&(_, db))) =
                (support.node_axes.get(a as usize), support.node_axes.get(b as usize))
            else {
                continue;
            };
            let (Some(da), Some(db)) = (da.try_normalize(), db.try_normalize()) else { continue };
            let pts: Vec<DVec3> = panel.arc_vertices[k].iter().map(|&i| panel.positions[i as usize]).collect();
            let n = pts.len() - 1;
            let (p, q) = (pts[0], pts[n]);
            let focus = axes_meet(p, da, q, db);
            let base = out.positions.len() as u32;
            for (j, &x) in pts.iter().enumerate() {
                let d = if j == 0 {
                    da
                } else if j == n {
                    db
                } else {
                    match focus {
                        Some(m) => {
                            let sign = if da.dot(m - p) >= 0.0 { 1.0 } else { -1.0 };
                            ((m - x) * sign).try_normalize().unwrap_or(da)
                        }
                        None => da.lerp(db, j as f64 / n as f64).try_normalize().unwrap_or(da),
                    }
                };
                out.positions.push(x);
                out.positions.push(x + depth * d);
            }
            for j in 0..n as u32 {
                let (x0, y0, x1, y1) = (base + 2 * j, base + 2 * j + 1, base + 2 * j + 2, base + 2 * j + 3);
                out.triangles.push([x0, x1, y1]);
                out.triangles.push([x0, y1, y0]);
            }
        }
    }
    out
}

/// The point where the lines p + s·dp and q + t·dq meet (midpoint of their common perpendicular);
/// None when they are (nearly) parallel.
fn axes_meet(p: DVec3, dp: DVec3, q: DVec3, dq: DVec3) -> Option<DVec3> {
    let w = p - q;
    let (a, b, c) = (dp.dot(dp), dp.dot(dq), dq.dot(dq));
    let (d, e) = (dp.dot(w), dq.dot(w));
    let den = a * c - b * b;
    if den <= 1e-12 * a * c {
        return None;
    }
    let s = (b * e - c * d) / den;
    let t = (a * e - b * d) / den;
    let m = 0.5 * ((p + s * dp) + (q + t * dq));
    m.is_finite().then_some(m)
}

/// Node axes as line segments (v, v + length·d): from each vertex toward the support side, like
/// `StSupportResult::node_axis_segments`.
pub fn node_axis_segments(support: &SupportStructure, length: f64) -> Vec<(DVec3, DVec3)> {
    support
        .node_axes
        .iter()
        .filter_map(|&(v, d)| {
            let d = d.try_normalize()?;
            Some((v, v + length * d))
        })
        .collect()
}

/// Everything [`write_panel_files`] writes.
pub struct ExportInput<'a> {
    pub panels: &'a [Panel],
    pub support: Option<&'a SupportGeometry>,
    /// Node axes as segments (start, end), e.g. from [`node_axis_segments`].
    pub node_axes: Option<&'a [(DVec3, DVec3)]>,
    /// Goes to the GLB's `asset.extras` (e.g. Ω from [`absolute_sphere_extras`]).
    pub extras: serde_json::Value,
    /// The reference surface, for the deviation columns of the schedule.
    pub reference: &'a TriMesh,
    /// Radii are rounded to multiples of this before counting distinct ones.
    pub radius_tolerance: f64,
}

/// Writes `panels.glb`, `panels.obj`, `panels.csv` and `panels.json` into `dir` (created if
/// missing) and returns the schedule (for the report's `max_distance_to_reference`).
pub fn write_panel_files(dir: &Path, input: &ExportInput) -> io::Result<PanelSchedule> {
    std::fs::create_dir_all(dir)?;
    let glb = write_glb(input.panels, input.support, input.node_axes, input.extras.clone());
    std::fs::write(dir.join("panels.glb"), glb)?;
    std::fs::write(dir.join("panels.obj"), write_obj(input.panels, input.support, input.node_axes))?;
    let schedule = build_schedule(input.panels, input.reference, input.radius_tolerance);
    std::fs::write(dir.join("panels.csv"), schedule.to_csv())?;
    std::fs::write(dir.join("panels.json"), schedule.to_json())?;
    Ok(schedule)
}
