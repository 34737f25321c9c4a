//! What an ST mesh with adapted face size promises (Sec. 3), measured on the result
//! ([`super::metrics`]): every vertex on the spheres of its faces (≤ [`EXACT`] of the diagonal:
//! the spherical panels close up at the vertices) and no folded face (a face whose normal points
//! against the reference's at its centroid).

use crate::guarantees::{Guarantee, Verdict};

use super::metrics::StAdaptedMetrics;

/// Vertex–sphere residual, relative to the diagonal.
pub const EXACT: f64 = 1e-8;

/// The verdict of an ST result.
pub fn verdict(m: &StAdaptedMetrics) -> Verdict {
    Verdict::new(vec![
        Guarantee::at_most("max_vertex_sphere_residual", m.max_vertex_sphere_residual, EXACT, "of the diagonal"),
        Guarantee::count_at_most("folded_faces", m.flipped_faces, 0),
    ])
}
