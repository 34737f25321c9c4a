//! What an ST mesh with adapted face size promises (Sec. 3), measured on the result
//! ([`super::metrics`] and the delivered panels, [`Buildability`]): every vertex on the spheres
//! of its faces (≤ [`EXACT`] of the diagonal: the spherical panels close up at the vertices), no
//! folded face (a face whose normal points against the reference's at its centroid), every panel
//! bounded by arcs that do not cross and with its exact surface, and every panel within 2ε of
//! the reference ([`super::params::StAdaptedParams::distance_bound`]).

use crate::guarantees::{Guarantee, Verdict};
use crate::panels::buildability::Buildability;
use crate::panels::exact_surface::ExactSurfaces;
use crate::reference::Reference;
use crate::units::Units;

use super::metrics::StAdaptedMetrics;
use super::params::StAdaptedParams;
use super::StAdaptedResult;

/// The verdict of the delivered result: the one measurement of its guarantees, on its panels and
/// their exact surfaces (returned, for the CAD files), independent of the optimizer's variables;
/// lengths in `units` beside their share of the diagonal.
pub fn measure(result: &StAdaptedResult, reference: &Reference, params: &StAdaptedParams, units: Units) -> (Verdict, ExactSurfaces) {
    let exact = ExactSurfaces::of(&result.panels, &[]);
    let buildability = Buildability::measure(&exact, &result.panel_deviations, false, result.diag, units);
    (verdict(&result.metrics, &buildability, params.distance_bound(reference.facet_sagitta())), exact)
}

/// Vertex–sphere residual, relative to the diagonal.
pub const EXACT: f64 = 1e-8;

/// The verdict of an ST result on its panels, `max_distance` relative to the diagonal.
pub fn verdict(m: &StAdaptedMetrics, panels: &Buildability, max_distance: f64) -> Verdict {
    let mut all = vec![
        Guarantee::at_most("max_vertex_sphere_residual", m.max_vertex_sphere_residual, EXACT, "of the diagonal"),
        Guarantee::count_at_most("folded_faces", m.flipped_faces, 0),
    ];
    all.extend(panels.guarantees(max_distance));
    Verdict::new(all)
}
