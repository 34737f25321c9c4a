//! How far panels stray from the reference surface: sampled over their tessellation, measured
//! to the surface itself (exactly on a B-spline reference, whose triangulation only guides the
//! search).

use glam::DVec3;

use super::panel::Panel;
use super::tessellate::project_to_sphere;
use crate::geometry::closest::{closest_point_on_triangle, ClosestHit, TriangleBvh};
use crate::reference::Reference;

/// What panels are measured against: a triangle mesh, or a [`Reference`], whose B-spline (if it
/// is one) lies up to its [`Reference::tessellation_error`] from the triangulation searched.
pub trait Surface {
    /// The triangulation searched.
    fn bvh(&self) -> &TriangleBvh;
    /// How much farther than from the triangulation a point may lie from the surface.
    fn slack(&self) -> f64;
    /// The distance from `p` to the surface, given its closest point on the triangulation.
    fn distance(&self, p: DVec3, hit: ClosestHit) -> f64;
}

impl Surface for TriangleBvh {
    fn bvh(&self) -> &TriangleBvh {
        self
    }
    fn slack(&self) -> f64 {
        0.0
    }
    fn distance(&self, _: DVec3, hit: ClosestHit) -> f64 {
        hit.distance
    }
}

impl Surface for Reference {
    fn bvh(&self) -> &TriangleBvh {
        Reference::bvh(self)
    }
    fn slack(&self) -> f64 {
        self.tessellation_error()
    }
    fn distance(&self, p: DVec3, hit: ClosestHit) -> f64 {
        self.distance_from_hit(p, hit)
    }
}

/// The most points sampled on one panel: an even subset of its tessellation beyond. A glass
/// panel at the default chord tolerance has a few hundred (250–660 on the hard roofs); a
/// degenerate face's panel (a huge sphere, crossing arcs) reaches the tessellation's cap, over
/// 15,000, and each point it strays by is measured on the reference itself.
pub const MAX_SAMPLES: usize = 2048;

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

/// Largest distance from the panel's samples ([`panel_samples`]) to the surface (infinite when
/// a sample has no closest point). Exact, with fewer searches: each starts from the last hit's
/// triangle, and a sample that cannot raise the maximum is not measured further: no farther
/// from that triangle, or from its closest triangle, than the largest distance so far less the
/// surface's [`Surface::slack`].
pub fn max_deviation(panel: &Panel, surface: &impl Surface) -> f64 {
    max_deviation_above(panel, surface, 0.0)
}

/// Each panel's [`max_deviation`]; NaN for every panel of an empty surface (not measured).
pub fn panel_distances(panels: &[Panel], surface: &impl Surface) -> Vec<f64> {
    panels.iter().map(|p| if surface.bvh().is_empty() { f64::NAN } else { max_deviation(p, surface) }).collect()
}

/// max(`floor`, [`max_deviation`]): samples that cannot come farther than `floor` are not
/// measured.
fn max_deviation_above(panel: &Panel, surface: &impl Surface, floor: f64) -> f64 {
    let (bvh, slack) = (surface.bvh(), surface.slack());
    let mut max = floor;
    let mut last: Option<usize> = None;
    for p in panel_samples(panel) {
        let hit = match last {
            Some(t) => {
                let [a, b, c] = bvh.triangle(t);
                if closest_point_on_triangle(p, a, b, c).0.distance(p) + slack <= max {
                    continue;
                }
                bvh.closest_point_from(p, t)
            }
            None => bvh.closest_point(p),
        };
        let Some(hit) = hit else { return f64::INFINITY };
        last = Some(hit.triangle);
        if hit.distance + slack > max {
            max = max.max(surface.distance(p, hit));
        }
    }
    max
}

/// Largest deviation over all panels, relative to `diag` (the reference's bounding-box
/// diagonal; absolute when it is 0).
pub fn max_distance_to_reference(panels: &[Panel], surface: &impl Surface, diag: f64) -> f64 {
    let d = panels.iter().fold(0.0, |d, p| max_deviation_above(p, surface, d));
    if diag > 0.0 {
        d / diag
    } else {
        d
    }
}
