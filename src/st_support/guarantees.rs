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

use super::metrics::StSupportMetrics;

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
