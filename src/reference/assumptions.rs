//! What the sphere methods assume of the reference, checked before they run: mean curvature of
//! one sign (Sec. 6.3: central spheres flip through planes where H changes sign), no face folded
//! back onto its neighbour, no sliver faces (a sliver's sphere through its three corners is huge
//! and meets its neighbours at large kinks), facets no farther from the smooth surface than the
//! tolerance ε (smooth panels stay that far from them). After a run, kinks over
//! [`KINK_WARNING_DEG`] are reported too. A failed check is a warning the CLI, the report and the
//! app show alike.

// Negated float comparisons are deliberate: NaN counts as a kink and as a sliver.

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

/// A warning of a run, the one type every method reports: a failed assumption of the reference,
/// a fallback the method took, or a part of the result that falls short. The report, the CLI and
/// the app show its `Display`.
#[derive(Clone, Debug, PartialEq)]
pub enum Warning {
    /// H takes both signs (on `positive` and `negative` vertices).
    MeanCurvatureChangesSign { positive: usize, negative: usize },
    /// Edges whose faces fold onto each other.
    Folds { edges: usize },
    /// Faces thinner than [`SLIVER_ASPECT`].
    Slivers { faces: usize },
    /// The result's panels meet at more than [`KINK_WARNING_DEG`] at `edges` edges, where the
    /// reference's own facets meet at up to `reference_max_deg`.
    Kinks { edges: usize, max_deg: f64, reference_max_deg: f64 },
    /// The reference's median facet lies farther than the tolerance `epsilon` from the smooth
    /// surface through its vertices (its
    /// [`Reference::facet_sagitta`](crate::reference::Reference::facet_sagitta), `sagitta`; both
    /// relative to the diagonal).
    CoarserThanTolerance { sagitta: f64, epsilon: f64 },
    /// SQ (Sec. 5.1): H turns within one grid row of the boundary, on `share_percent` of the
    /// area; `left_out` of the `grid_points` of G are left out of the radius fit.
    MeanCurvatureTurnsNearBoundary { other_positive: bool, share_percent: f64, left_out: usize, grid_points: usize },
    /// SQ (Sec. 5.1): a speck of the other sign of H inside the patch, around `uv`, run through.
    MeanCurvatureSpeck {
        other_positive: bool,
        share_percent: f64,
        uv: [f64; 2],
        max_abs_mean: f64,
        /// How far it bends a panel the wrong way, relative to the diagonal.
        sagitta: f64,
        left_out: usize,
        grid_points: usize,
    },
    /// SQ: the surface is one sphere, so every central sphere is the surface itself.
    OneSphere,
    /// SQ (Sec. 6.3): the central congruence r = 1/H missed θ or α, so the congruence started from
    /// constant radii.
    CentralCongruenceReplaced {
        max_line_normal_angle_deg: f64,
        theta_deg: f64,
        quads_without_real_torsal_directions: usize,
        min_torsal_plane_angle_deg: f64,
        alpha_deg: f64,
    },
    /// SQ (Sec. 6.3): H changes sign or vanishes inside the patch, so the central spheres r = 1/H
    /// pass through planes there and the congruence starts from constant radii alone.
    CentralCongruenceUnbounded { positive_share: f64, negative_share: f64 },
    /// SQ (Sec. 5.2): the torsal field turns about an umbilic; a quad mesh along it needs
    /// singular vertices, whose support planes cannot meet at more than `bound_deg` (valence 3,
    /// valence 5), so the quad mesh follows the parameter lines.
    SingularTorsalField { valence_3: usize, valence_5: usize, bound_deg: [f64; 2] },
    /// SQ (Sec. 5.2): the integration of the torsal field folded fine triangles.
    FoldedFieldTriangles { triangles: usize },
    /// SQ (Sec. 5.2): the quad mesh covers only this share of the patch.
    PartialCoverage { coverage: f64 },
}

impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Warning::MeanCurvatureChangesSign { positive, negative } => write!(
                f,
                "H changes sign (H > 0 at {positive} vertices, H < 0 at {negative}): central spheres flip through planes there, \
                 so panels meet at large kinks; the sphere methods need H of one sign (Sec. 6.3)"
            ),
            Warning::Folds { edges } => write!(
                f,
                "the surface folds back at {edges} edge(s) (neighbouring faces at less than {FOLD_ANGLE_DEG}° to each other): \
                 repair the mesh, the panels there are meaningless"
            ),
            Warning::Slivers { faces } => write!(
                f,
                "{faces} sliver face(s) (height under {SLIVER_ASPECT:e} of their longest edge): their spheres are nearly planes \
                 and meet their neighbours at large kinks; remesh first"
            ),
            Warning::Kinks { edges, max_deg, reference_max_deg } if *reference_max_deg > KINK_WARNING_DEG => write!(
                f,
                "panels meet at kinks of up to {max_deg:.1}° ({edges} edge(s) over {KINK_WARNING_DEG}°), and the reference's own \
                 facets meet at up to {reference_max_deg:.1}°: the surface itself bends sharply there"
            ),
            Warning::Kinks { edges, max_deg, reference_max_deg } => write!(
                f,
                "panels meet at kinks of up to {max_deg:.1}° ({edges} edge(s) over {KINK_WARNING_DEG}°), although the reference's \
                 own facets meet at no more than {reference_max_deg:.1}°: the panels fold or kink where the surface is smooth, a \
                 defect of the result, not of the surface"
            ),
            Warning::CoarserThanTolerance { sagitta, epsilon } => write!(
                f,
                "the reference is coarser than the tolerance: its median facet lies {sagitta:.1e} of the diagonal ({:.1} ε) from \
                 the smooth surface through its vertices, and the panels, being smooth, stay that far from its facets; refine \
                 the reference or raise ε to at least {sagitta:.1e}",
                sagitta / epsilon
            ),
            Warning::MeanCurvatureTurnsNearBoundary { other_positive, share_percent, left_out, grid_points } => write!(
                f,
                "the mean curvature turns near the boundary (H {} 0 on {share_percent:.2} % of the area, within one grid row of the edge); \
                 {left_out} of the {grid_points} grid points there are left out of the radius fit",
                if *other_positive { '>' } else { '<' }
            ),
            Warning::MeanCurvatureSpeck { other_positive, share_percent, uv, max_abs_mean, sagitta, left_out, grid_points } => write!(
                f,
                "a speck of the other sign of the mean curvature: H {} 0 on {share_percent:.2} % of the area inside the patch, around \
                 (u, v) = ({:.3}, {:.3}), |H| up to {max_abs_mean:.2e}; it bends a panel the wrong way by at most {sagitta:.1e} of the diagonal, so \
                 spheres of the dominant sign still approximate it; {left_out} of the {grid_points} grid points there are left out of the \
                 radius fit",
                if *other_positive { '>' } else { '<' },
                uv[0],
                uv[1]
            ),
            Warning::OneSphere => f.write_str(
                "the surface is one sphere: every central sphere is the surface itself, so the panels all lie on that sphere and the node axes pass through its centre",
            ),
            Warning::CentralCongruenceReplaced {
                max_line_normal_angle_deg,
                theta_deg,
                quads_without_real_torsal_directions,
                min_torsal_plane_angle_deg,
                alpha_deg,
            } => write!(
                f,
                "the central congruence (r = 1/H) ended with lines up to {max_line_normal_angle_deg:.1}° off the normals (θ = {theta_deg}°), \
                 {quads_without_real_torsal_directions} grid quads without real torsal directions and torsal planes at ≥ \
                 {min_torsal_plane_angle_deg:.1}° (α = {alpha_deg}°); the congruence starts from constant radii instead (Sec. 6.3)"
            ),
            Warning::CentralCongruenceUnbounded { positive_share, negative_share } => write!(
                f,
                "H changes sign or vanishes inside the patch (H > 0 on {:.1} % of its area, H < 0 on {:.1} %): the central spheres \
                 r = 1/H pass through planes there, so the congruence is the normal congruence of constant radii (Sec. 6.3), \
                 whose torsal directions are the principal directions",
                100.0 * positive_share,
                100.0 * negative_share
            ),
            Warning::SingularTorsalField { valence_3, valence_5, bound_deg } => write!(
                f,
                "the torsal directions turn about a point (an umbilic): a quad mesh along them needs singular vertices, {valence_3} of valence 3 and {valence_5} of valence 5, where the support planes cannot meet at more than {}° and {}°; the final optimization does not yet reach its guarantees from such a mesh, so the quad mesh follows the parameter lines instead, which it starts from",
                bound_deg[0], bound_deg[1]
            ),
            Warning::FoldedFieldTriangles { triangles } => write!(
                f,
                "integrating the torsal field folded {triangles} fine triangles: the quad mesh leaves the torsal directions there"
            ),
            Warning::PartialCoverage { coverage } => write!(f, "the quad mesh covers {:.1} % of the patch", 100.0 * coverage),
        }
    }
}

/// The failed assumptions of `mesh` with its topology and curvature.
pub(crate) fn surface_warnings(mesh: &TriMesh, topo: &Topology, field: &CurvatureField) -> Vec<Warning> {
    let mut warnings = Vec::new();
    warnings.extend(sign_change(mesh, field));
    let folds = fold_edges(mesh, topo);
    if folds > 0 {
        warnings.push(Warning::Folds { edges: folds });
    }
    warnings.extend(sliver_warning(mesh));
    warnings
}

/// The sign change of H: the curvature summary's absolute test, or both signs beyond
/// [`SIGN_RELATIVE`] of max |H| on [`SIGN_FRACTION`] of the vertices each (a curved surface only:
/// max |H| · diag ≥ 10 × [`PLANAR_TOLERANCE`]).
fn sign_change(mesh: &TriMesh, field: &CurvatureField) -> Option<Warning> {
    let h = || field.vertices.iter().map(|c| c.mean).filter(|h| h.is_finite());
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
    (field.summary.h_changes_sign || (positive >= need && negative >= need)).then_some(Warning::MeanCurvatureChangesSign { positive, negative })
}

/// The kink warning of a result whose interior edges meet at `kinks_deg`, beside the reference's
/// own largest dihedral angle.
pub(crate) fn kink_warning(kinks_deg: &[f64], reference: &crate::reference::Reference) -> Option<Warning> {
    let edges = kinks_deg.iter().filter(|&&k| !(k <= KINK_WARNING_DEG)).count();
    let max_deg = kinks_deg.iter().copied().fold(0.0, f64::max);
    (edges > 0).then(|| Warning::Kinks { edges, max_deg, reference_max_deg: reference.max_dihedral_angle_deg() })
}

/// The coarseness warning of a reference for the tolerance `epsilon` (relative to the
/// diagonal): its [`Reference::facet_sagitta`](crate::reference::Reference::facet_sagitta)
/// exceeds ε (never for a B-spline reference).
pub fn coarseness_warning(reference: &crate::reference::Reference, epsilon: f64) -> Option<Warning> {
    let sagitta = reference.facet_sagitta();
    (sagitta > epsilon).then_some(Warning::CoarserThanTolerance { sagitta, epsilon })
}

/// The sliver warning of `mesh`, if it has slivers.
pub(crate) fn sliver_warning(mesh: &TriMesh) -> Option<Warning> {
    let faces = (0..mesh.face_count()).filter(|&f| is_sliver(mesh.face_points(f))).count();
    (faces > 0).then_some(Warning::Slivers { faces })
}

/// The warnings of a method that ran on `work`, a remesh of the reference when given: H and
/// folds are the reference's, slivers those of the mesh the method used.
pub(crate) fn method_warnings(reference: &crate::reference::Reference, field: &CurvatureField, work: Option<&TriMesh>) -> Vec<Warning> {
    let mut warnings = surface_warnings(reference.mesh(), reference.topology(), field);
    if let Some(work) = work {
        warnings.retain(|w| !matches!(w, Warning::Slivers { .. }));
        warnings.extend(sliver_warning(work));
    }
    warnings
}

/// Whether the triangle's height over its longest edge is below [`SLIVER_ASPECT`] (a repeated
/// corner counts: degenerate faces are slivers too).
pub(crate) fn is_sliver(p: [DVec3; 3]) -> bool {
    let l2 = (p[1] - p[0]).length_squared().max((p[2] - p[1]).length_squared()).max((p[0] - p[2]).length_squared());
    let twice_area = (p[1] - p[0]).cross(p[2] - p[0]).length();
    !(twice_area > SLIVER_ASPECT * l2)
}

/// Edges on which some two faces fold back: their third corners lie on the same side
/// of the edge, within [`FOLD_ANGLE_DEG`] (independent of the faces' orientation).
pub(crate) fn fold_edges(mesh: &TriMesh, topo: &Topology) -> usize {
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
                let c = mesh.triangles[f as usize].into_iter().find(|&v| v != *a && v != *b)?;
                let w = mesh.positions[c as usize] - pa;
                (w - w.dot(axis) * axis).try_normalize()
            })
            .collect();
        let folded = away.iter().enumerate().any(|(i, u)| away[i + 1..].iter().any(|w| u.dot(*w) > cos_fold));
        if folded {
            folds += 1;
        }
    }
    folds
}
