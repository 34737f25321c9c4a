//! How far panels stray from the reference surface: sampled over their tessellation.

use glam::DVec3;

use super::panel::Panel;
use super::tessellate::project_to_sphere;
use crate::geometry::closest::TriangleBvh;

/// The most points sampled on one panel. A glass panel's tessellation has fewer; only a
/// degenerate face's panel comes near the tessellation's cap, and then an even subset keeps the
/// measure's work bounded.
pub const MAX_SAMPLES: usize = 16384;

/// Points sampled on a panel: its tessellation vertices and its triangle centroids projected
/// onto the panel's sphere (evenly thinned to at most about [`MAX_SAMPLES`]).
pub fn panel_samples(panel: &Panel) -> Vec<DVec3> {
    let stride = (panel.positions.len() + panel.triangles.len()).div_ceil(MAX_SAMPLES).max(1);
    let mut pts: Vec<DVec3> = panel.positions.iter().step_by(stride).copied().collect();
    let base = panel.positions[0];
    for t in panel.triangles.iter().step_by(stride) {
        let c = (panel.positions[t[0] as usize] + panel.positions[t[1] as usize] + panel.positions[t[2] as usize]) / 3.0;
        pts.push(project_to_sphere(&panel.sphere, base, c));
    }
    pts
}

/// Largest distance from the panel's samples ([`panel_samples`]) to the reference.
pub fn max_deviation(panel: &Panel, reference: &TriangleBvh) -> f64 {
    panel_samples(panel).into_iter().map(|p| reference.distance(p)).fold(0.0, f64::max)
}

/// Largest deviation over all panels, relative to `diag` (the reference's bounding-box
/// diagonal; absolute when it is 0).
pub fn max_distance_to_reference(panels: &[Panel], reference: &TriangleBvh, diag: f64) -> f64 {
    let d = panels.iter().map(|p| max_deviation(p, reference)).fold(0.0, f64::max);
    if diag > 0.0 {
        d / diag
    } else {
        d
    }
}
