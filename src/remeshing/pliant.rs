//! Pliant remeshing (Kobbelt et al. 2000, as used in paper Sec. 3) driven by a sizing field g.
//!
//! The normalized length of an edge e is l(e) = |e| / g(π(e)), π(e) the closest point of the
//! reference to the edge midpoint (for a uniform field no query is needed). Starting from the
//! reference mesh itself, each round
//! 1. splits edges with l > 4/3 at their midpoints (longest first, halves re-queued), the new
//!    vertex projected onto the reference (onto the boundary/feature curve for constrained edges);
//! 2. collapses edges with l < 4/5 (shortest first, repeated passes) unless an edge of the result
//!    would get l > 4/3; two free vertices merge at the projected midpoint, two vertices sliding
//!    on the same boundary or feature curve at the midpoint projected onto that curve (so that a
//!    uniformly too finely sampled curve can be coarsened: collapsing one of its edges of length
//!    0.7 g at an endpoint would leave a 1.4 g edge), otherwise the vertex that may move is merged
//!    into the other one;
//! 3. flips interior edges when that brings the valences of the four vertices closer to 6 (4 on
//!    the boundary);
//! 4. (with 5.) moves every vertex toward the centroid of its incident faces weighted by their
//!    area in the sizing metric (A_f / g_f², g_f the mean g at the face's vertices), restricted to
//!    the tangent plane (boundary and feature vertices: along the curve, to the g-weighted
//!    midpoint of their two curve neighbours), and
//! 5. projects the result onto the reference (closest point through the BVH; boundary/feature
//!    vertices onto the reference's boundary/feature polylines). Smoothing and projection are
//!    fused per vertex so that the projected position is what is checked; a rejected move is
//!    retried with half and a quarter of the step, then projection alone, else the vertex stays.
//!
//! **Validity.** Every operation is checked before it is applied: the link condition, valences and
//! boundary cases ([`HalfedgeMesh::collapse_is_topologically_ok`],
//! [`HalfedgeMesh::flip_is_topologically_ok`]), and for every face it creates or moves, the normal
//! must stay within `max_normal_change_deg` of the face's previous normal (so nothing flips) and its
//! smallest angle must be at least `min(min_angle_deg, smallest angle of the faces it replaces)`
//! (so no degenerate face is created). Splits are the only exception to the angle floor: when the
//! projected midpoint fails the checks the edge is split at its straight midpoint (a planar
//! subdivision, which cannot flip), and that vertex is projected in the next smoothing step.
//!
//! **Boundaries and features.** Boundary edges and feature edges (dihedral angle above
//! `feature_angle_deg` in the reference) are constrained: their vertices slide along them, and they
//! are only split or collapsed along themselves. Corners (constrained curves turning by more than
//! `corner_angle_deg`, curve endpoints and junctions, non-manifold vertices) never move and are
//! never removed. Boundary loops are never closed, so the Euler characteristic and the number of
//! boundary loops are those of the reference.

// Negated float comparisons are deliberate: they also reject NaN.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::influence_zones::SizingField;
use crate::geometry::closest::TriangleBvh;
use crate::geometry::mesh::halfedge::{face, prev, HalfedgeMesh, Stamp, VertexKind, EDGE_FROZEN, NONE};
use crate::geometry::mesh::TriMesh;
use crate::progress::{Cancelled, OnProgress, Progress};

/// Split threshold on the normalized edge length.
pub const SPLIT_ABOVE: f64 = 4.0 / 3.0;
/// Collapse threshold on the normalized edge length.
pub const COLLAPSE_BELOW: f64 = 4.0 / 5.0;

/// Parameters of [`pliant_remesh`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct RemeshParams {
    /// Rounds of split / collapse / flip / smooth + project. Default 10 (paper Sec. 3).
    pub rounds: usize,
    /// Interior edges whose faces meet at more than this dihedral angle (degrees) in the reference
    /// are kept as feature curves. Default 45. 180 or more disables features.
    pub feature_angle_deg: f64,
    /// Boundary and feature curves turning by more than this (degrees) at a vertex make it a fixed
    /// corner. Default 30.
    pub corner_angle_deg: f64,
    /// Smoothing step toward the weighted centroid (0..=1). Default 0.5.
    pub smoothing_step: f64,
    /// Smoothing + projection sweeps per round. Default 2.
    pub smoothing_iterations: usize,
    /// Faces created or moved must keep their smallest angle at least this (degrees), unless the
    /// faces they replace were already worse. Default 2.
    pub min_angle_deg: f64,
    /// A face's normal may turn by at most this much (degrees) in one operation. Default 60.
    pub max_normal_change_deg: f64,
    /// Collapse passes per round (each pass tries every short edge once). Default 30.
    pub max_collapse_passes: usize,
}

impl Default for RemeshParams {
    fn default() -> Self {
        Self {
            rounds: 10,
            feature_angle_deg: 45.0,
            corner_angle_deg: 30.0,
            smoothing_step: 0.5,
            smoothing_iterations: 2,
            min_angle_deg: 2.0,
            max_normal_change_deg: 60.0,
            max_collapse_passes: 30,
        }
    }
}

/// What one round did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct RoundStats {
    pub splits: usize,
    pub collapses: usize,
    pub flips: usize,
    /// Vertices moved by smoothing and projection.
    pub moved: usize,
    /// Vertex moves rejected by the checks (the vertex stayed).
    pub rejected_moves: usize,
    /// Faces after the round.
    pub faces: usize,
}

/// The remeshed mesh and per-round statistics.
#[derive(Clone, Debug)]
pub struct RemeshOutput {
    pub mesh: TriMesh,
    pub rounds: Vec<RoundStats>,
    /// Vertices not on the reference at the end (their projection would have flipped or
    /// degenerated a face); 0 in all tests.
    pub unprojected_vertices: usize,
    /// Largest distance of an output vertex from the reference.
    pub max_distance_to_reference: f64,
    /// The most faces the mesh may reach (see [`face_cap`]).
    pub face_cap: usize,
}

/// The most faces a remesh of `reference` to `sizing` may reach: four times the faces the field
/// asks for, plus twice the reference's. Splits stop there, so the work of a round is bounded by
/// the target and the input, never by the mesh's own growth.
pub fn face_cap(reference: &TriMesh, sizing: &SizingField) -> usize {
    let expected = sizing.expected_faces(reference);
    let cap = 4.0 * expected + 2.0 * reference.face_count() as f64 + 64.0;
    if cap.is_finite() && cap < 1e9 {
        cap as usize
    } else {
        1_000_000_000
    }
}

/// Why [`pliant_remesh`] gave no mesh.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RemeshError {
    Cancelled,
    /// Every face collapsed away (a sizing field far coarser than the surface).
    NoFaces,
    /// A uniform remesh to about `target` faces made `faces`, off by more than a factor
    /// [`TARGET_FACTOR`]: the reference is too small, thin or folded to be cut that finely.
    TargetMissed {
        target: usize,
        faces: usize,
    },
}

/// How far a uniform remesh may miss its face count before it is refused.
pub const TARGET_FACTOR: usize = 3;

impl std::fmt::Display for RemeshError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RemeshError::Cancelled => f.write_str("cancelled"),
            RemeshError::NoFaces => f.write_str("remeshing produced no faces"),
            RemeshError::TargetMissed { target, faces } => write!(
                f,
                "remeshing to about {target} faces made {faces}: the surface is too small, thin or folded to be remeshed to that \
                 size (repair it, or ask for a face count it can hold)"
            ),
        }
    }
}

impl std::error::Error for RemeshError {}

impl From<Cancelled> for RemeshError {
    fn from(_: Cancelled) -> Self {
        RemeshError::Cancelled
    }
}

/// Pliant remeshing of `reference` to the sizing field `sizing`. Reports step "remesh" before
/// every round and at the end.
pub fn pliant_remesh(reference: &TriMesh, sizing: &SizingField, params: &RemeshParams, progress: &mut OnProgress) -> Result<TriMesh, RemeshError> {
    let mesh = pliant_remesh_with_stats(reference, sizing, params, progress)?.mesh;
    if mesh.face_count() == 0 {
        return Err(RemeshError::NoFaces);
    }
    Ok(mesh)
}

/// [`pliant_remesh`] with statistics (an empty mesh is no error here).
pub fn pliant_remesh_with_stats(
    reference: &TriMesh,
    sizing: &SizingField,
    params: &RemeshParams,
    progress: &mut OnProgress,
) -> Result<RemeshOutput, Cancelled> {
    let mut r = Remesher::new(reference, sizing, params);
    let mut rounds = Vec::with_capacity(params.rounds);
    for round in 0..params.rounds {
        progress(Progress::new("remesh", round, params.rounds))?;
        rounds.push(r.round());
    }
    if r.split_boundary_chords() > 0 {
        r.smooth_and_project();
        r.m.compact();
    }
    progress(Progress::new("remesh", params.rounds, params.rounds))?;
    let (unprojected, max_d) = r.final_projection();
    Ok(RemeshOutput { mesh: r.m.to_mesh(), rounds, unprojected_vertices: unprojected, max_distance_to_reference: max_d, face_cap: r.face_cap })
}

/// Remeshing state: the halfedge mesh, the reference's BVHs and scratch buffers.
pub struct Remesher<'a> {
    pub m: HalfedgeMesh,
    sizing: &'a SizingField,
    own_surface: Option<TriangleBvh>,
    boundary: TriangleBvh,
    features: TriangleBvh,
    /// Unit normals of the reference faces, and of the reference face(s) at each boundary /
    /// feature segment (the bisector for features).
    face_normals: Vec<DVec3>,
    boundary_normals: Vec<DVec3>,
    feature_normals: Vec<DVec3>,
    params: RemeshParams,
    cos_normal: f64,
    sin_min_angle: f64,
    stamp: Stamp,
    ring_a: Vec<u32>,
    ring_b: Vec<u32>,
    faces_buf: Vec<u32>,
    /// Snap distance: projections closer than this are skipped.
    tiny: f64,
    /// Splits stop at this many faces ([`face_cap`]).
    pub face_cap: usize,
}

/// Smallest angle's sine, 2A / (l_mid · l_max) (0 for degenerate triangles), and the unnormalized
/// normal.
fn quality(a: DVec3, b: DVec3, c: DVec3) -> (f64, DVec3) {
    let n = (b - a).cross(c - a);
    let mut l = [(b - a).length_squared(), (c - b).length_squared(), (a - c).length_squared()];
    l.sort_by(f64::total_cmp);
    let den = (l[1] * l[2]).sqrt();
    let q = if den > 0.0 { n.length() / den } else { 0.0 };
    (if q.is_finite() { q } else { 0.0 }, n)
}

impl<'a> Remesher<'a> {
    pub fn new(reference: &TriMesh, sizing: &'a SizingField, params: &RemeshParams) -> Self {
        let m = HalfedgeMesh::from_mesh(reference, params.feature_angle_deg.to_radians(), params.corner_angle_deg.to_radians());
        let shared = sizing.is_defined_on(reference);
        let own_surface = if shared { None } else { Some(TriangleBvh::new(reference)) };
        let face_normals: Vec<DVec3> = (0..reference.face_count()).map(|f| reference.face_area_vector(f).normalize_or_zero()).collect();
        let he_normal = |h: u32| m.face_normal(face(h)).unwrap_or(DVec3::ZERO);
        let (mut bseg, mut bnrm, mut fseg, mut fnrm) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for h in 0..m.twin.len() as u32 {
            let t = m.twin[h as usize];
            if t != NONE && t < h {
                continue;
            }
            let (a, b) = (m.pos[m.from(h) as usize], m.pos[m.to(h) as usize]);
            if t == NONE {
                bseg.push([a, b, b]);
                bnrm.push(he_normal(h));
            } else if m.edge_flag[h as usize] != 0 {
                fseg.push([a, b, b]);
                fnrm.push((he_normal(h) + he_normal(t)).normalize_or_zero());
            }
        }
        let n = m.pos.len();
        let diag = reference.bbox_diagonal();
        Self {
            sizing,
            own_surface,
            boundary: TriangleBvh::from_triangles(bseg),
            features: TriangleBvh::from_triangles(fseg),
            face_normals,
            boundary_normals: bnrm,
            feature_normals: fnrm,
            cos_normal: params.max_normal_change_deg.to_radians().cos(),
            sin_min_angle: params.min_angle_deg.to_radians().sin(),
            params: params.clone(),
            stamp: Stamp::new(n),
            ring_a: Vec::new(),
            ring_b: Vec::new(),
            faces_buf: Vec::new(),
            tiny: 1e-15 * diag.max(1e-300),
            face_cap: face_cap(reference, sizing),
            m,
        }
    }

    fn surface(&self) -> &TriangleBvh {
        self.own_surface.as_ref().unwrap_or_else(|| self.sizing.bvh())
    }

    /// g at the point of the reference closest to `p`.
    fn g_at(&self, p: DVec3) -> f64 {
        self.sizing.at(p)
    }

    /// Normalized length of the segment p–q (endpoints on or near the reference, so the midpoint's
    /// closest point is within about |p − q| / 2).
    fn normalized_length(&self, p: DVec3, q: DVec3) -> f64 {
        let d = p.distance(q);
        d / self.sizing.at_near(0.5 * (p + q), 0.5 * d + self.tiny)
    }

    fn edge_length(&self, h: u32) -> f64 {
        self.normalized_length(self.m.pos[self.m.from(h) as usize], self.m.pos[self.m.to(h) as usize])
    }

    /// Closest point on the surface (or on the constraint curves for `kind` Slide / `boundary`)
    /// and the reference normal there; corners (and failed queries) keep `p` and `n`.
    fn project(&self, p: DVec3, kind: VertexKind, boundary: bool, n: DVec3) -> (DVec3, DVec3) {
        let (bvh, normals) = match kind {
            VertexKind::Corner => return (p, n),
            VertexKind::Slide if boundary => (&self.boundary, &self.boundary_normals),
            VertexKind::Slide => (&self.features, &self.feature_normals),
            VertexKind::Free => (self.surface(), &self.face_normals),
        };
        match bvh.closest_point(p) {
            Some(h) => (h.point, normals.get(h.triangle).copied().unwrap_or(n)),
            None => (p, n),
        }
    }

    /// One round; returns its statistics.
    pub fn round(&mut self) -> RoundStats {
        let mut st = RoundStats { splits: self.split_long_edges(), ..Default::default() };
        st.collapses = self.collapse_short_edges();
        st.flips = self.flip_edges();
        for _ in 0..self.params.smoothing_iterations.max(1) {
            let (moved, rejected) = self.smooth_and_project();
            st.moved += moved;
            st.rejected_moves += rejected;
        }
        self.m.compact();
        st.faces = self.m.face_count();
        st
    }

    /// A snapshot of the current mesh (compacted copy), e.g. for showing progress.
    pub fn mesh(&self) -> TriMesh {
        self.m.to_mesh()
    }

    /// Undirected live edges, one halfedge each.
    fn edges(&self) -> Vec<u32> {
        let m = &self.m;
        (0..m.twin.len() as u32)
            .filter(|&h| {
                let t = m.twin[h as usize];
                !m.face_dead[face(h)] && (t == NONE || t > h)
            })
            .collect()
    }

    // --- 1. Splits ---------------------------------------------------------------------------

    pub(crate) fn split_long_edges(&mut self) -> usize {
        let mut queue: Vec<(f64, u32)> = self
            .edges()
            .into_iter()
            .filter(|&h| self.m.edge_flag[h as usize] & EDGE_FROZEN == 0)
            .map(|h| (self.edge_length(h), h))
            .filter(|&(l, _)| l > SPLIT_ABOVE)
            .collect();
        queue.sort_by(|a, b| a.0.total_cmp(&b.0));
        // A split adds at most two faces.
        let budget = self.face_cap.saturating_sub(self.m.face_count()) / 2;
        let mut splits = 0;
        while let Some((_, h)) = queue.pop() {
            if splits >= budget {
                break;
            }
            if self.m.face_dead[face(h)] || self.edge_length(h) <= SPLIT_ABOVE {
                continue;
            }
            let (_, second) = self.split(h);
            splits += 1;
            for e in [h, second] {
                let l = self.edge_length(e);
                if l > SPLIT_ABOVE {
                    queue.push((l, e));
                }
            }
        }
        splits
    }

    /// Splits every interior edge whose two ends lie on the boundary (a chord across the
    /// boundary, often an "ear" face with three boundary corners). A face sphere there has its
    /// vertices pinned to the boundary and little freedom left, and the arc of such a chord runs
    /// over the boundary; the split gives the edge an interior vertex. Returns the number of splits.
    pub(crate) fn split_boundary_chords(&mut self) -> usize {
        let chords: Vec<u32> = self
            .edges()
            .into_iter()
            .filter(|&h| {
                let m = &self.m;
                !m.is_boundary_edge(h) && m.is_boundary_vertex(m.from(h)) && m.is_boundary_vertex(m.to(h))
            })
            .collect();
        // A split adds two faces; the face cap holds here too.
        let budget = self.face_cap.saturating_sub(self.m.face_count()) / 2;
        for &h in chords.iter().take(budget) {
            self.split(h);
        }
        chords.len().min(budget)
    }

    /// Splits edge h at its projected midpoint (straight midpoint if that fails the checks).
    fn split(&mut self, h: u32) -> (u32, u32) {
        let m = &self.m;
        let (a, b) = (m.from(h), m.to(h));
        let (pa, pb) = (m.pos[a as usize], m.pos[b as usize]);
        let mid = 0.5 * (pa + pb);
        let constrained = m.is_constrained(h);
        let kind = if constrained { VertexKind::Slide } else { VertexKind::Free };
        let n0 = (m.normal[a as usize] + m.normal[b as usize]).normalize_or_zero();
        let (p, n) = self.project(mid, kind, m.is_boundary_edge(h), n0);
        let (p, n) = if p != mid && !self.split_ok(h, p, n) { (mid, n0) } else { (p, n) };
        let (v, second) = self.m.split(h, p);
        self.m.normal[v as usize] = n;
        (v, second)
    }

    /// Checks the faces a split of h at p (reference normal n) would create.
    fn split_ok(&self, h: u32, p: DVec3, n: DVec3) -> bool {
        let m = &self.m;
        let check_face = |e: u32| -> bool {
            let (a, b, c) = (m.from(e), m.to(e), m.from(prev(e)));
            let [pa, pb, pc] = [a, b, c].map(|v| m.pos[v as usize]);
            let [na, nb, nc] = [a, b, c].map(|v| m.normal[v as usize]);
            let (q_old, n_old) = quality(pa, pb, pc);
            let floor = self.sin_min_angle.min(q_old);
            let n_old = n_old.try_normalize();
            self.face_ok([pa, p, pc], [na, n, nc], n_old, floor) && self.face_ok([p, pb, pc], [n, nb, nc], n_old, floor)
        };
        if !check_face(h) {
            return false;
        }
        let t = m.twin[h as usize];
        t == NONE || check_face(t)
    }

    /// A new or moved face with corners `p` and reference normals `nref` there is acceptable: not
    /// degenerate, smallest angle's sine ≥ `floor`, normal within the allowed change of the
    /// previous unit normal `n_old` (if the face had one), and not facing against the reference
    /// (positive on the sum of the corners' reference normals).
    #[inline]
    fn face_ok(&self, p: [DVec3; 3], nref: [DVec3; 3], n_old: Option<DVec3>, floor: f64) -> bool {
        let (q, n) = quality(p[0], p[1], p[2]);
        let len = n.length();
        len > 0.0 && q >= floor && n_old.is_none_or(|o| n.dot(o) >= self.cos_normal * len) && n.dot(nref[0] + nref[1] + nref[2]) > 0.0
    }

    // --- 2. Collapses ------------------------------------------------------------------------

    pub(crate) fn collapse_short_edges(&mut self) -> usize {
        let mut total = 0;
        // The first pass looks at every edge, later passes only at the edges around vertices
        // whose neighbourhood changed (the kept vertex of each collapse and its one-ring).
        let mut edges = self.edges();
        let mut touched: Vec<u32> = Vec::new();
        let mut ring = Vec::new();
        for _pass in 0..self.params.max_collapse_passes.max(1) {
            let mut cand: Vec<(f64, u32)> = edges.iter().map(|&h| (self.edge_length(h), h)).filter(|&(l, _)| l < COLLAPSE_BELOW).collect();
            if cand.is_empty() {
                break;
            }
            cand.sort_by(|a, b| a.0.total_cmp(&b.0));
            touched.clear();
            let mut done = 0;
            for (_, h) in cand {
                if self.m.face_dead[face(h)] || self.edge_length(h) >= COLLAPSE_BELOW {
                    continue;
                }
                if let Some(kept) = self.try_collapse(h) {
                    touched.push(kept);
                    done += 1;
                }
            }
            total += done;
            if done == 0 {
                break;
            }
            // Edges incident to the kept vertices and their neighbours.
            edges.clear();
            let g = self.stamp_next();
            for &k in &touched {
                if self.m.vertex_dead[k as usize] {
                    continue;
                }
                self.m.one_ring_into(k, &mut ring);
                ring.push(k);
                for &v in &ring {
                    if self.stamp.marks[v as usize] == g {
                        continue;
                    }
                    self.stamp.marks[v as usize] = g;
                    self.m.outgoing_into(v, &mut self.faces_buf);
                    for &e in &self.faces_buf {
                        let t = self.m.twin[e as usize];
                        edges.push(if t == NONE { e } else { e.min(t) });
                        // The incoming boundary edge is not an outgoing halfedge of v.
                        let p = prev(e);
                        if self.m.twin[p as usize] == NONE {
                            edges.push(p);
                        }
                    }
                }
            }
            edges.sort_unstable();
            edges.dedup();
        }
        total
    }

    fn stamp_next(&mut self) -> u32 {
        self.stamp.ensure(self.m.pos.len());
        self.stamp.fresh()
    }

    /// May `x` be removed into `y` along edge h (x, y its endpoints)?
    fn may_remove(&self, x: u32, h: u32) -> bool {
        let m = &self.m;
        if m.locked[x as usize] {
            return false;
        }
        match m.kind[x as usize] {
            VertexKind::Corner => false,
            VertexKind::Free => true,
            VertexKind::Slide => m.is_constrained(h),
        }
    }

    /// Collapses h if allowed; returns the kept vertex.
    fn try_collapse(&mut self, h: u32) -> Option<u32> {
        let (a, b) = (self.m.from(h), self.m.to(h));
        let (ka, kb) = (self.m.kind[a as usize], self.m.kind[b as usize]);
        // (removed vertex, kept vertex, new position and reference normal; None: the kept one's).
        type Option3 = [(u32, u32, Option<(DVec3, DVec3)>); 3];
        let mut options: Option3 = [(NONE, NONE, None); 3];
        let mut n = 0;
        if ka == VertexKind::Free && kb == VertexKind::Free {
            let mid = 0.5 * (self.m.pos[a as usize] + self.m.pos[b as usize]);
            let n0 = self.m.normal[a as usize];
            let p = self.project(mid, VertexKind::Free, false, n0);
            // The projected midpoint, else either endpoint.
            options = [(a, b, Some(p)), (a, b, None), (b, a, None)];
            n = 3;
        } else if ka == VertexKind::Slide && kb == VertexKind::Slide && self.m.is_constrained(h) {
            // Along a boundary or feature curve: the midpoint on the curve, else either endpoint.
            let mid = 0.5 * (self.m.pos[a as usize] + self.m.pos[b as usize]);
            let n0 = self.m.normal[a as usize];
            let p = self.project(mid, VertexKind::Slide, self.m.is_boundary_edge(h), n0);
            options = [(a, b, Some(p)), (a, b, None), (b, a, None)];
            n = 3;
        } else {
            for (x, y) in [(a, b), (b, a)] {
                if self.may_remove(x, h) && n < 2 {
                    options[n] = (x, y, None);
                    n += 1;
                }
            }
        }
        if n == 0 {
            return None;
        }
        self.stamp.ensure(self.m.pos.len());
        if !self.m.collapse_is_topologically_ok(h, &mut self.stamp, &mut self.ring_a) {
            return None;
        }
        for &(x, y, pn) in &options[..n] {
            let (p, pn) = pn.unwrap_or((self.m.pos[y as usize], self.m.normal[y as usize]));
            if self.collapse_geometry_ok(x, y, p, pn) {
                self.m.collapse(h, x, p);
                self.m.normal[y as usize] = pn;
                return Some(y);
            }
        }
        None
    }

    /// Geometric checks of removing x into y moved to p: the new edges at p have l ≤ 4/3, and
    /// every face around x and y (except the two that vanish) keeps its orientation and quality.
    fn collapse_geometry_ok(&mut self, x: u32, y: u32, p: DVec3, pn: DVec3) -> bool {
        let mut faces = std::mem::take(&mut self.faces_buf);
        let mut ring = std::mem::take(&mut self.ring_b);
        let ok = self.collapse_geometry_ok_inner(x, y, p, pn, &mut faces, &mut ring);
        self.faces_buf = faces;
        self.ring_b = ring;
        ok
    }

    fn collapse_geometry_ok_inner(&self, x: u32, y: u32, p: DVec3, pn: DVec3, faces: &mut Vec<u32>, ring: &mut Vec<u32>) -> bool {
        let m = &self.m;
        let py = m.pos[y as usize];
        // New edge lengths: neighbours of x (and of y if y moves).
        m.one_ring_into(x, ring);
        for &w in ring.iter() {
            if w != y && self.normalized_length(p, m.pos[w as usize]) > SPLIT_ABOVE {
                return false;
            }
        }
        if p != py {
            m.one_ring_into(y, ring);
            for &w in ring.iter() {
                if w != x && self.normalized_length(p, m.pos[w as usize]) > SPLIT_ABOVE {
                    return false;
                }
            }
        }
        // Faces around x and y.
        faces.clear();
        m.outgoing_into(x, faces);
        let nx = faces.len();
        let mut tmp = Vec::new();
        m.outgoing_into(y, &mut tmp);
        faces.extend(tmp);
        let mut worst_old = f64::INFINITY;
        for &e in faces.iter() {
            let t = m.tri[face(e)];
            let (q, _) = quality(m.pos[t[0] as usize], m.pos[t[1] as usize], m.pos[t[2] as usize]);
            worst_old = worst_old.min(q);
        }
        let floor = self.sin_min_angle.min(worst_old);
        for (i, &e) in faces.iter().enumerate() {
            let t = m.tri[face(e)];
            if t.contains(&x) && t.contains(&y) {
                continue; // vanishes
            }
            if i >= nx && p == py {
                continue; // a face of y that does not move
            }
            let old = t.map(|v| m.pos[v as usize]);
            let n_old = (old[1] - old[0]).cross(old[2] - old[0]).try_normalize();
            let new = t.map(|v| if v == x || v == y { p } else { m.pos[v as usize] });
            let nref = t.map(|v| if v == x || v == y { pn } else { m.normal[v as usize] });
            if !self.face_ok(new, nref, n_old, floor) {
                return false;
            }
        }
        true
    }

    // --- 3. Flips ----------------------------------------------------------------------------

    fn target_valence(&self, v: u32) -> i64 {
        if self.m.is_boundary_vertex(v) {
            4
        } else {
            6
        }
    }

    pub(crate) fn flip_edges(&mut self) -> usize {
        let mut total = 0;
        for _pass in 0..3 {
            let mut done = 0;
            for h in self.edges() {
                if self.try_flip(h) {
                    done += 1;
                }
            }
            total += done;
            if done == 0 {
                break;
            }
        }
        total
    }

    fn try_flip(&mut self, h: u32) -> bool {
        let m = &self.m;
        let t = m.twin[h as usize];
        if t == NONE || m.edge_flag[h as usize] != 0 {
            return false;
        }
        let (a, b) = (m.from(h), m.to(h));
        let (c, d) = (m.from(prev(h)), m.from(prev(t)));
        let val = |v: u32| m.valence(v) as i64;
        let (va, vb, vc, vd) = (val(a), val(b), val(c), val(d));
        let (ta, tb, tc, td) = (self.target_valence(a), self.target_valence(b), self.target_valence(c), self.target_valence(d));
        let before = (va - ta).pow(2) + (vb - tb).pow(2) + (vc - tc).pow(2) + (vd - td).pow(2);
        let after = (va - 1 - ta).pow(2) + (vb - 1 - tb).pow(2) + (vc + 1 - tc).pow(2) + (vd + 1 - td).pow(2);
        if after >= before {
            return false;
        }
        let mut ring = std::mem::take(&mut self.ring_a);
        let topo_ok = self.m.flip_is_topologically_ok(h, &mut ring);
        self.ring_a = ring;
        if !topo_ok || !self.flip_geometry_ok(h) {
            return false;
        }
        self.m.flip(h);
        true
    }

    /// The two new faces (a, d, c), (d, b, c) keep the orientation of the old pair, do not fold
    /// against each other more than the old pair did (or 45°), and respect the angle floor.
    fn flip_geometry_ok(&self, h: u32) -> bool {
        let m = &self.m;
        let t = m.twin[h as usize];
        let (a, b) = (m.from(h), m.to(h));
        let (c, d) = (m.from(prev(h)), m.from(prev(t)));
        let [pa, pb, pc, pd] = [a, b, c, d].map(|v| m.pos[v as usize]);
        let [na, nb, nc, nd] = [a, b, c, d].map(|v| m.normal[v as usize]);
        let (q0, n0) = quality(pa, pb, pc);
        let (q1, n1) = quality(pb, pa, pd);
        let floor = self.sin_min_angle.min(q0.min(q1));
        // Against the average normal of the old pair (None if both were degenerate).
        let avg = (n0.normalize_or_zero() + n1.normalize_or_zero()).try_normalize();
        if !self.face_ok([pa, pd, pc], [na, nd, nc], avg, floor) || !self.face_ok([pd, pb, pc], [nd, nb, nc], avg, floor) {
            return false;
        }
        let (qn0, m0) = quality(pa, pd, pc);
        let (qn1, m1) = quality(pd, pb, pc);
        // Do not make the pair much worse: the smaller minimum angle must not drop below half.
        if qn0.min(qn1) < 0.5 * q0.min(q1) {
            return false;
        }
        // Do not fold the pair more than before (or 45°).
        let (Some(w0), Some(w1)) = (m0.try_normalize(), m1.try_normalize()) else { return false };
        match (n0.try_normalize(), n1.try_normalize()) {
            (Some(u0), Some(u1)) => w0.dot(w1) >= u0.dot(u1).min(std::f64::consts::FRAC_1_SQRT_2),
            _ => true,
        }
    }

    // --- 4 + 5. Tangential smoothing and projection ---------------------------------------------

    /// Per-vertex g (at each vertex's closest reference point) for the smoothing weights.
    fn vertex_sizing(&self) -> Vec<f64> {
        if let Some(g) = self.sizing.uniform_value() {
            return vec![g; self.m.pos.len()];
        }
        self.m.pos.iter().enumerate().map(|(v, &p)| if self.m.vertex_dead[v] { 1.0 } else { self.g_at(p) }).collect()
    }

    pub(crate) fn smooth_and_project(&mut self) -> (usize, usize) {
        let gv = self.vertex_sizing();
        let (mut moved, mut rejected) = (0, 0);
        let mut out = Vec::with_capacity(16);
        for v in 0..self.m.pos.len() as u32 {
            let m = &self.m;
            if m.vertex_dead[v as usize] || m.locked[v as usize] || m.vhe[v as usize] == NONE {
                continue;
            }
            let kind = m.kind[v as usize];
            if kind == VertexKind::Corner {
                continue;
            }
            let p = m.pos[v as usize];
            m.outgoing_into(v, &mut out);
            let boundary = m.is_boundary_vertex(v);
            let delta = match kind {
                VertexKind::Free => {
                    // Centroid of incident face centroids, weighted by area / g_f²; normal by area.
                    let (mut acc, mut wsum, mut nrm) = (DVec3::ZERO, 0.0, DVec3::ZERO);
                    for &e in &out {
                        let t = m.tri[face(e)];
                        let [x, y, z] = t.map(|w| m.pos[w as usize]);
                        let an = (y - x).cross(z - x);
                        let area = 0.5 * an.length();
                        let gf = (gv[t[0] as usize] + gv[t[1] as usize] + gv[t[2] as usize]) / 3.0;
                        let w = area / (gf * gf);
                        acc += w * (x + y + z) / 3.0;
                        wsum += w;
                        nrm += an;
                    }
                    let Some(n) = nrm.try_normalize() else { continue };
                    if !(wsum > 0.0) {
                        continue;
                    }
                    let u = acc / wsum - p;
                    u - u.dot(n) * n
                }
                VertexKind::Slide => {
                    // The two neighbours along the constrained curve.
                    let mut ends = [NONE; 2];
                    let mut k = 0;
                    for &e in &out {
                        if m.is_constrained(e) && k < 2 {
                            ends[k] = m.to(e);
                            k += 1;
                        }
                        let pe = prev(e);
                        if m.twin[pe as usize] == NONE && k < 2 {
                            ends[k] = m.from(pe);
                            k += 1;
                        }
                    }
                    if k != 2 {
                        continue;
                    }
                    let (u, w) = (ends[0], ends[1]);
                    let (pu, pw) = (m.pos[u as usize], m.pos[w as usize]);
                    let (gu, gw) = (gv[u as usize], gv[w as usize]);
                    let target = (gw * pu + gu * pw) / (gu + gw);
                    let Some(dir) = (pw - pu).try_normalize() else { continue };
                    let d = target - p;
                    d.dot(dir) * dir
                }
                VertexKind::Corner => continue,
            };
            let step = self.params.smoothing_step;
            let mut tried = false;
            for s in [step, 0.5 * step, 0.25 * step, 0.0] {
                let (cand, cn) = self.project(p + s * delta, kind, boundary, self.m.normal[v as usize]);
                if cand.distance(p) <= self.tiny {
                    continue;
                }
                tried = true;
                if self.move_ok(v, cand, cn, &out) {
                    self.m.pos[v as usize] = cand;
                    self.m.normal[v as usize] = cn;
                    moved += 1;
                    tried = false;
                    break;
                }
            }
            if tried {
                rejected += 1;
            }
        }
        (moved, rejected)
    }

    /// Moving v (with outgoing halfedges `out`) to p, with reference normal `pn` there, keeps every
    /// incident face valid.
    fn move_ok(&self, v: u32, p: DVec3, pn: DVec3, out: &[u32]) -> bool {
        let m = &self.m;
        for &e in out {
            let (b, c) = (m.to(e), m.from(prev(e)));
            let (pv, pb, pc) = (m.pos[v as usize], m.pos[b as usize], m.pos[c as usize]);
            let (q_old, n_old) = quality(pv, pb, pc);
            let nref = [pn, m.normal[b as usize], m.normal[c as usize]];
            if !self.face_ok([p, pb, pc], nref, n_old.try_normalize(), self.sin_min_angle.min(q_old)) {
                return false;
            }
        }
        true
    }

    /// Projects every vertex that is not on the reference (with the usual checks). Returns the
    /// number of vertices that could not be projected and the largest distance to the reference.
    pub(crate) fn final_projection(&mut self) -> (usize, f64) {
        let mut out = Vec::new();
        let mut failed = 0;
        let mut max_d: f64 = 0.0;
        for v in 0..self.m.pos.len() as u32 {
            if self.m.vertex_dead[v as usize] || self.m.vhe[v as usize] == NONE {
                continue;
            }
            let p = self.m.pos[v as usize];
            let kind = self.m.kind[v as usize];
            let (q, qn) = self.project(p, kind, self.m.is_boundary_vertex(v), self.m.normal[v as usize]);
            if q != p {
                self.m.outgoing_into(v, &mut out);
                if self.m.locked[v as usize] || !self.move_ok(v, q, qn, &out) {
                    if q.distance(p) > self.tiny {
                        failed += 1;
                    }
                } else {
                    self.m.pos[v as usize] = q;
                    self.m.normal[v as usize] = qn;
                }
            }
            let d = self.surface().distance(self.m.pos[v as usize]);
            if d.is_finite() {
                max_d = max_d.max(d);
            }
        }
        (failed, max_d)
    }
}
