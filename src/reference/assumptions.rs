//! What the sphere methods assume of the reference, checked before they run: mean curvature of
//! one sign (Sec. 6.3: central spheres flip through planes where H changes sign), no face folded
//! back onto its neighbour, no sliver faces (a sliver's sphere through its three corners is huge
//! and meets its neighbours at large kinks), facets no farther from the smooth surface than the
//! tolerance ε (smooth panels stay that far from them). After a run, kinks over
//! [`KINK_WARNING_DEG`] are reported too. A failed check is a warning the CLI, the report and the
//! app show alike.

// Negated float comparisons are deliberate: NaN counts as a kink and as a sliver.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use std::fmt;

use glam::DVec3;

use crate::congruence::central_spheres::{CurvatureField, PLANAR_TOLERANCE};
use crate::geometry::mesh::topology::Topology;
use crate::geometry::mesh::TriMesh;

/// Two faces on one edge fold back when their directions away from the edge make an angle below
/// this (degrees): the surface turns by more than 100° there, more than at a box's edge.
pub const FOLD_ANGLE_DEG: f64 = 80.0;
/// A triangle is a sliver when its height over its longest edge is below this.
pub const SLIVER_ASPECT: f64 = 1e-4;
/// H changes sign when both signs reach this fraction of max |H|, each on at least
/// [`SIGN_FRACTION`] of the vertices (besides the absolute test of the curvature summary, which
/// misses gently curved saddles).
pub const SIGN_RELATIVE: f64 = 0.25;
/// See [`SIGN_RELATIVE`].
pub const SIGN_FRACTION: f64 = 0.05;
/// Panels meeting at more than this (degrees) are reported.
pub const KINK_WARNING_DEG: f64 = 45.0;

/// One failed assumption.
#[derive(Clone, Debug, PartialEq)]
pub enum SurfaceWarning {
    /// H takes both signs (on `positive` and `negative` vertices).
    MeanCurvatureChangesSign { positive: usize, negative: usize },
    /// Edges whose faces fold onto each other.
    Folds { edges: usize },
    /// Faces thinner than [`SLIVER_ASPECT`].
    Slivers { faces: usize },
    /// The result's panels meet at more than [`KINK_WARNING_DEG`] at `edges` edges, where the
    /// reference's own facets meet at up to `reference_max_deg`.
    Kinks {
        edges: usize,
        max_deg: f64,
        reference_max_deg: f64,
    },
    /// The reference's median facet lies farther than the tolerance `epsilon` from the smooth
    /// surface through its vertices (its
    /// [`Reference::facet_sagitta`](crate::reference::Reference::facet_sagitta), `sagitta`; both
    /// relative to the diagonal).
    CoarserThanTolerance { sagitta: f64, epsilon: f64 },
}

impl fmt::Display for SurfaceWarning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SurfaceWarning::MeanCurvatureChangesSign { positive, negative } => write!(
                f,
                "H changes sign (H > 0 at {positive} vertices, H < 0 at {negative}): central spheres flip through planes there, \
                 so panels meet at large kinks; the sphere methods need H of one sign (Sec. 6.3)"
            ),
            SurfaceWarning::Folds { edges } => write!(
                f,
                "the surface folds back at {edges} edge(s) (neighbouring faces at less than {FOLD_ANGLE_DEG}° to each other): \
                 repair the mesh, the panels there are meaningless"
            ),
            SurfaceWarning::Slivers { faces } => write!(
                f,
                "{faces} sliver face(s) (height under {SLIVER_ASPECT:e} of their longest edge): their spheres are nearly planes \
                 and meet their neighbours at large kinks; remesh first"
            ),
            SurfaceWarning::Kinks { edges, max_deg, reference_max_deg } if *reference_max_deg > KINK_WARNING_DEG => write!(
                f,
                "panels meet at kinks of up to {max_deg:.1}° ({edges} edge(s) over {KINK_WARNING_DEG}°), and the reference's own \
                 facets meet at up to {reference_max_deg:.1}°: the surface itself bends sharply there"
            ),
            SurfaceWarning::Kinks { edges, max_deg, reference_max_deg } => write!(
                f,
                "panels meet at kinks of up to {max_deg:.1}° ({edges} edge(s) over {KINK_WARNING_DEG}°), although the reference's \
                 own facets meet at no more than {reference_max_deg:.1}°: the panels fold or kink where the surface is smooth, a \
                 defect of the result, not of the surface"
            ),
            SurfaceWarning::CoarserThanTolerance { sagitta, epsilon } => write!(
                f,
                "the reference is coarser than the tolerance: its median facet lies {sagitta:.1e} of the diagonal ({:.1} ε) from \
                 the smooth surface through its vertices, and the panels, being smooth, stay that far from its facets; refine \
                 the reference or raise ε to at least {sagitta:.1e}",
                sagitta / epsilon
            ),
        }
    }
}

/// The failed assumptions of `mesh` with its topology and curvature.
pub fn surface_warnings(
    mesh: &TriMesh,
    topo: &Topology,
    field: &CurvatureField,
) -> Vec<SurfaceWarning> {
    let mut warnings = Vec::new();
    warnings.extend(sign_change(mesh, field));
    let folds = fold_edges(mesh, topo);
    if folds > 0 {
        warnings.push(SurfaceWarning::Folds { edges: folds });
    }
    warnings.extend(sliver_warning(mesh));
    warnings
}

/// The sign change of H: the curvature summary's absolute test, or both signs beyond
/// [`SIGN_RELATIVE`] of max |H| on [`SIGN_FRACTION`] of the vertices each (a curved surface only:
/// max |H| · diag ≥ 10 × [`PLANAR_TOLERANCE`]).
fn sign_change(mesh: &TriMesh, field: &CurvatureField) -> Option<SurfaceWarning> {
    let h = || {
        field
            .vertices
            .iter()
            .map(|c| c.mean)
            .filter(|h| h.is_finite())
    };
    let max_abs = h().fold(0.0, |m: f64, x| m.max(x.abs()));
    let diag = mesh.bbox_diagonal();
    let threshold = if field.summary.h_changes_sign {
        crate::congruence::central_spheres::SIGN_CHANGE_THRESHOLD / diag.max(f64::MIN_POSITIVE)
    } else if max_abs * diag >= 10.0 * PLANAR_TOLERANCE {
        SIGN_RELATIVE * max_abs
    } else {
        return None;
    };
    let positive = h().filter(|&x| x > threshold).count();
    let negative = h().filter(|&x| x < -threshold).count();
    let need = ((SIGN_FRACTION * field.vertices.len() as f64).ceil() as usize).max(1);
    (field.summary.h_changes_sign || (positive >= need && negative >= need))
        .then_some(SurfaceWarning::MeanCurvatureChangesSign { positive, negative })
}

/// The kink warning of a result whose interior edges meet at `kinks_deg`, beside the reference's
/// own largest dihedral angle.
pub fn kink_warning(
    kinks_deg: &[f64],
    reference: &crate::reference::Reference,
) -> Option<SurfaceWarning> {
    let edges = kinks_deg
        .iter()
        .filter(|&&k| !(k <= KINK_WARNING_DEG))
        .count();
    let max_deg = kinks_deg.iter().copied().fold(0.0, f64::max);
    (edges > 0).then(|| SurfaceWarning::Kinks {
        edges,
        max_deg,
        reference_max_deg: reference.max_dihedral_angle_deg(),
    })
}

/// The coarseness warning of a reference for the tolerance `epsilon` (relative to the
/// diagonal): its [`Reference::facet_sagitta`](crate::reference::Reference::facet_sagitta)
/// exceeds ε (never for a B-spline reference).
pub fn coarseness_warning(
    reference: &crate::reference::Reference,
    epsilon: f64,
) -> Option<SurfaceWarning> {
    let sagitta = reference.facet_sagitta();
    (sagitta > epsilon).then_some(SurfaceWarning::CoarserThanTolerance { sagitta, epsilon })
}

/// The sliver warning of `mesh`, if it has slivers.
pub fn sliver_warning(mesh: &TriMesh) -> Option<SurfaceWarning> {
    let faces = (0..mesh.face_count())
        .filter(|&f| is_sliver(mesh.face_points(f)))
        .count();
    (faces > 0).then_some(SurfaceWarning::Slivers { faces })
}

/// The warnings of a method that ran on `work`, a remesh of the reference when given: H and
/// folds are the reference's, slivers those of the mesh the method used.
pub fn method_warnings(
    reference: &crate::reference::Reference,
    field: &CurvatureField,
    work: Option<&TriMesh>,
) -> Vec<SurfaceWarning> {
    let mut warnings = surface_warnings(reference.mesh(), reference.topology(), field);
    if let Some(work) = work {
        warnings.retain(|w| !matches!(w, SurfaceWarning::Slivers { .. }));
        warnings.extend(sliver_warning(work));
    }
    warnings
}

/// Whether the triangle's height over its longest edge is below [`SLIVER_ASPECT`] (a repeated
/// corner counts: degenerate faces are slivers too).
pub fn is_sliver(p: [DVec3; 3]) -> bool {
    let l2 = (p[1] - p[0])
        .length_squared()
        .max((p[2] - p[1]).length_squared())
        .max((p[0] - p[2]).length_squared());
    let twice_area = (p[1] - p[0]).cross(p[2] - p[0]).length();
    !(twice_area > SLIVER_ASPECT * l2)
}

/// Edges on which some two faces fold back: their third corners lie on the same side
/// of the edge, within [`FOLD_ANGLE_DEG`] (independent of the faces' orientation).
pub fn fold_edges(mesh: &TriMesh, topo: &Topology) -> usize {
    let cos_fold = FOLD_ANGLE_DEG.to_radians().cos();
    let mut folds = 0;
    for (e, [a, b]) in topo.edges().iter().enumerate() {
        let faces = topo.edge_faces(e);
        if faces.len() < 2 {
            continue;
        }
        let (pa, pb) = (mesh.positions[*a as usize], mesh.positions[*b as usize]);
        let Some(axis) = (pb - pa).try_normalize() else {
            continue;
        };
        let away: Vec<DVec3> = faces
            .iter()
            .filter_map(|&(f, _)| {
                let c = mesh.triangles[f as usize]
                    .into_iter()
                    .find(|&v| v != *a && v != *b)?;
                let w = mesh.positions[c as usize] - pa;
                (w - w.dot(axis) * axis).try_normalize()
            })
            .collect();
        let folded = away
            .iter()
            .enumerate()
            .any(|(i, u)| away[i + 1..].iter().any(|w| u.dot(*w) > cos_fold));
        if folded {
            folds += 1;
        }
    }
    folds
}
