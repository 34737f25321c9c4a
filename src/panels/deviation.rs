//! How far panels stray from the reference surface: sampled over their tessellation.

use glam::DVec3;

use super::panel::Panel;
use super::tessellate::project_to_sphere;
use crate::geometry::closest::{closest_point_on_triangle, TriangleBvh};

/// The most points sampled on one panel. A glass panel's tessellation has fewer; only a
/// degenerate face's panel comes near the tessellation's cap, and then an even subset keeps the
/// measure's work bounded.
pub const MAX_SAMPLES: usize = 16384;

/// Segments each arc is sampled at besides the tessellation: a nearly straight arc has few
/// tessellation vertices, while the reference may curve away from it between them.
pub const ARC_SEGMENTS: usize = 8;

/// Points sampled on a panel: its tessellation vertices and its triangle centroids projected
/// onto the panel's sphere (evenly thinned to at most about [`MAX_SAMPLES`]), and every arc at
/// [`ARC_SEGMENTS`] segments.
pub fn panel_samples(panel: &Panel) -> Vec<DVec3> {
    let stride = (panel.positions.len() + panel.triangles.len()).div_ceil(MAX_SAMPLES).max(1);
    let mut pts: Vec<DVec3> = panel.arcs.iter().flat_map(|a| a.sample(ARC_SEGMENTS)).collect();
    pts.extend(panel.positions.iter().step_by(stride).copied());
    let base = panel.positions[0];
    for t in panel.triangles.iter().step_by(stride) {
        let c = (panel.positions[t[0] as usize] + panel.positions[t[1] as usize] + panel.positions[t[2] as usize]) / 3.0;
        pts.push(project_to_sphere(&panel.sphere, base, c));
    }
    pts
}

/// Largest distance from the panel's samples ([`panel_samples`]) to the reference (infinite when
/// a sample has no closest point). Exact, with fewer searches: each starts from the last hit's
/// triangle, and a sample no farther from that triangle than the largest distance so far is not
/// searched, as it cannot raise the maximum.
pub fn max_deviation(panel: &Panel, reference: &TriangleBvh) -> f64 {
    max_deviation_above(panel, reference, 0.0)
}

/// Each panel's [`max_deviation`]; NaN for every panel of an empty reference (not measured).
pub fn panel_distances(panels: &[Panel], reference: &TriangleBvh) -> Vec<f64> {
    panels.iter().map(|p| if reference.is_empty() { f64::NAN } else { max_deviation(p, reference) }).collect()
}

/// max(`floor`, [`max_deviation`]): samples no farther than `floor` are not searched.
fn max_deviation_above(panel: &Panel, reference: &TriangleBvh, floor: f64) -> f64 {
    let mut max = floor;
    let mut last: Option<usize> = None;
    for p in panel_samples(panel) {
        let hit = match last {
            Some(t) => {
                let [a, b, c] = reference.triangle(t);
                if closest_point_on_triangle(p, a, b, c).0.distance(p) <= max {
                    continue;
                }
                reference.closest_point_from(p, t)
            }
            None => reference.closest_point(p),
        };
        let Some(hit) = hit else { return f64::INFINITY };
        max = max.max(hit.distance);
        last = Some(hit.triangle);
    }
    max
}

/// Largest deviation over all panels, relative to `diag` (the reference's bounding-box
/// diagonal; absolute when it is 0).
pub fn max_distance_to_reference(panels: &[Panel], reference: &TriangleBvh, diag: f64) -> f64 {
    let d = panels.iter().fold(0.0, |d, p| max_deviation_above(p, reference, d));
    if diag > 0.0 {
        d / diag
    } else {
        d
    }
}
