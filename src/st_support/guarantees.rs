//! What an ST mesh with support structure promises (Sec. 4), measured on the result
//! ([`super::metrics`]): every vertex on the spheres of its faces, every face sphere orthogonal
//! to Ω (Ω a plane: its centre in Ω), so that the node axes of the star's spheres pass through m
//! (Ω a plane: are parallel to its axis) and the support structure is torsion-free; each within
//! [`EXACT`] of the diagonal; and every panel bounded by arcs that do not cross, with its exact
//! surface, every support element planar without folding, every panel within the stated distance
//! of the reference ([`Buildability`]).

use crate::geometry::absolute_sphere::AbsoluteSphere;
use crate::guarantees::{Guarantee, Verdict};
use crate::panels::buildability::Buildability;
use crate::panels::deviation::panel_distances;
use crate::panels::exact_surface::ExactSurfaces;
use crate::reference::Reference;
use crate::units::Units;

use super::metrics::StSupportMetrics;
use super::params::StSupportParams;
use crate::congruence::support_structure::SupportStructure;
use crate::panels::panel::Panel;

/// What the verdict was measured on: the exact surfaces of the panels and support elements and
/// each panel's distance to the reference as loaded (also when the method remeshed it).
pub struct Measured {
    pub verdict: Verdict,
    pub exact: ExactSurfaces,
    pub deviations: Vec<f64>,
}

/// The delivered result: its panels and support structure, their figures and Ω.
pub struct Delivered<'a> {
    pub panels: &'a [Panel],
    pub support: &'a SupportStructure,
    pub metrics: &'a StSupportMetrics,
    pub omega: &'a AbsoluteSphere,
}

/// The verdict of the delivered result: the one measurement of its guarantees, independent of the
/// optimizer's variables; lengths in `units` beside their share of the diagonal.
pub fn measure(result: Delivered, reference: &Reference, params: &StSupportParams, units: Units) -> Measured {
    let exact = ExactSurfaces::of(result.panels, &result.support.elements);
    let deviations = panel_distances(result.panels, reference);
    let buildability = Buildability::measure(&exact, &deviations, true, reference.diagonal(), units);
    Measured { verdict: verdict(result.metrics, result.omega, &buildability, params.max_distance), exact, deviations }
}

/// Exact: vertex–sphere, orthogonality, centre-plane and node-axis residuals at most this
/// (relative to the diagonal; the orthogonality residual to its square).
pub const EXACT: f64 = 1e-9;

/// The verdict of an ST-support result against `omega`, its panels within `max_distance` of the
/// reference (relative to the diagonal).
pub fn verdict(m: &StSupportMetrics, omega: &AbsoluteSphere, panels: &Buildability, max_distance: f64) -> Verdict {
    let diag = "of the diagonal";
    let mut guarantees = vec![Guarantee::at_most("max_vertex_sphere_residual", m.max_vertex_sphere_residual, EXACT, diag)];
    match omega {
        AbsoluteSphere::Sphere { .. } => {
            guarantees.push(Guarantee::at_most("max_orthogonality_residual", m.max_orthogonality_residual, EXACT, "of the diagonal²"));
            guarantees.push(Guarantee::at_most("max_node_axis_offset", m.max_node_axis_offset, EXACT, diag));
        }
        AbsoluteSphere::Plane { .. } => {
            guarantees.push(Guarantee::at_most("max_center_plane_residual", m.max_center_plane_residual, EXACT, diag));
            // The sine of the angle between a node axis and Ω's axis.
            guarantees.push(Guarantee::at_most("max_node_axis_offset", m.max_node_axis_offset, EXACT, "(sine)"));
        }
    }
    guarantees.extend(panels.guarantees(max_distance));
    Verdict::new(guarantees)
}
