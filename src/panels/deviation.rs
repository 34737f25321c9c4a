//! How far panels stray from the reference surface: sampled over their tessellation.

use glam::DVec3;

use super::panel::Panel;
use super::tessellate::project_to_sphere;
use crate::geometry::closest::TriangleBvh;

/// Points sampled on a panel: its tessellation vertices and its triangle centroids projected
/// onto the panel's sphere.
pub fn panel_samples(panel: &Panel) -> Vec<DVec3> {
    let mut pts = panel.positions.clone();
    let base = panel.positions[0];
    for t in &panel.triangles {
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
