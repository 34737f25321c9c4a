//! The gaps of variant (b) (Fig. 12 bottom): where adjacent panels cut their own spheres with
//! the bisecting plane of their faces, their two arcs of an edge differ between its vertices.

use super::panel::Panel;
use crate::geometry::mesh::topology::Topology;

/// Gap samples per edge: 31 chord points strictly between the vertices.
pub const GAP_SAMPLES: usize = 33;

/// The gap of one interior edge between the arcs of its two panels (variant (b), Fig. 12).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EdgeGap {
    /// Mesh vertex ids, lower first.
    pub edge: [u32; 2],
    /// Face ids of the two panels, in panel order.
    pub faces: [usize; 2],
    /// Largest distance between the two arcs over the sampled chord points (see [`arc_gaps`]).
    pub gap: f64,
    /// The edge's chord length.
    pub edge_length: f64,
}

/// The gaps between the two panel arcs of every interior (two-panel) edge, in edge order.
///
/// **Definition** (Fig. 12 bottom): for the chord points x₀ = p + t (q − p), t = j/(samples − 1),
/// j = 1 … samples − 2, each arc's point above x₀ ([`super::arc::Arc::point_over_chord`]: on the
/// line through x₀ orthogonal to the chord in the arc's plane) is taken, and the gap is the
/// largest distance between the two arcs' points. For variant (b) both arcs lie in the edge's
/// bisecting plane, so this is the largest difference, along that line, between where it meets
/// the two spheres on the panel side. Variant (a) panels give 0 (one shared arc). `samples` < 3
/// is taken as 3 (the chord midpoint only). `topology` is the sphere mesh's: panel f is face f.
pub fn arc_gaps(panels: &[Panel], topology: &Topology, samples: usize) -> Vec<EdgeGap> {
    let samples = samples.max(3);
    topology
        .interior_edges()
        .map(|(e, f, g)| {
            let [lo, hi] = topology.edges()[e];
            // Both arcs from vertex lo to hi, so that equal t means the same chord point.
            let sides = topology.edge_faces(e);
            let [a, b] = [sides[0], sides[1]].map(|(i, k)| {
                let (p, k) = (&panels[i as usize], k as usize);
                if p.corners[k] == lo {
                    p.arcs[k]
                } else {
                    p.arcs[k].reversed()
                }
            });
            let gap = (1..samples - 1)
                .map(|j| {
                    let t = j as f64 / (samples - 1) as f64;
                    a.point_over_chord(t).distance(b.point_over_chord(t))
                })
                .fold(0.0, f64::max);
            EdgeGap { edge: [lo, hi], faces: [f as usize, g as usize], gap, edge_length: a.chord_length() }
        })
        .collect()
}

/// The largest of [`arc_gaps`] (0 without interior edges), absolute, and the largest gap divided
/// by its edge's length.
pub fn max_arc_gap(panels: &[Panel], topology: &Topology, samples: usize) -> (f64, f64) {
    arc_gaps(panels, topology, samples).iter().fold((0.0, 0.0), |(g, r), e| (g.max(e.gap), r.max(e.gap / e.edge_length)))
}
