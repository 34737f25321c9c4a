//! A compact halfedge mesh (corner table) with the local operators of pliant remeshing: edge
//! split, edge collapse and edge flip.
//!
//! Halfedge `h = 3f + k` runs from corner `k` to corner `k + 1` of face `f`; `next`/`prev` are
//! implicit, `twin[h]` is stored ([`NONE`] on the boundary). Each vertex stores one outgoing
//! halfedge; for a boundary vertex it is the one without twin, so that the counter-clockwise
//! rotation `h → twin(prev(h))` visits the whole fan. Faces and vertices removed by collapses are
//! flagged dead and dropped by [`HalfedgeMesh::compact`].
//!
//! The operators here only keep the connectivity consistent. They do **not** check whether an
//! operation is allowed; [`HalfedgeMesh::collapse_is_topologically_ok`] and
//! [`HalfedgeMesh::flip_is_topologically_ok`] do (link condition, valences, boundary cases), and the
//! geometric checks (no flipped or degenerate faces) live in the remesher.
//!
//! Input that is not an oriented 2-manifold is tolerated: edges shared by more than two faces or by
//! two faces of inconsistent orientation are left without twins and **frozen** (never split,
//! collapsed or flipped), and vertices whose faces do not form a single fan are **locked** (never
//! moved or removed). The remesher leaves such regions as they are.

use super::TriMesh;
use glam::DVec3;

/// "No halfedge" (boundary twin) and "no vertex".
pub const NONE: u32 = u32::MAX;

/// What a vertex may do.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VertexKind {
    /// Interior vertex off every feature curve: moves freely on the surface.
    Free,
    /// On a boundary or feature curve (exactly two constrained edges, no sharp turn): slides along it.
    Slide,
    /// Boundary or feature corner, endpoint or junction, or a locked (non-manifold) vertex: fixed.
    Corner,
}

/// Edge flags (stored on both halfedges of an edge).
pub const EDGE_FEATURE: u8 = 1;
/// Non-manifold or inconsistently oriented edge: never touched.
pub const EDGE_FROZEN: u8 = 2;

#[inline]
pub fn next(h: u32) -> u32 {
    if h % 3 == 2 {
        h - 2
    } else {
        h + 1
    }
}

#[inline]
pub fn prev(h: u32) -> u32 {
    if h.is_multiple_of(3) {
        h + 2
    } else {
        h - 1
    }
}

#[inline]
pub fn face(h: u32) -> usize {
    (h / 3) as usize
}

/// The halfedge mesh. Fields are public for the remesher; keep them consistent through the
/// operators.
#[derive(Clone, Debug, Default)]
pub struct HalfedgeMesh {
    pub pos: Vec<DVec3>,
    pub tri: Vec<[u32; 3]>,
    pub twin: Vec<u32>,
    /// Per halfedge: [`EDGE_FEATURE`], [`EDGE_FROZEN`] bits (equal on both halves of an edge).
    pub edge_flag: Vec<u8>,
    /// Per vertex: an outgoing halfedge (the twinless one on the boundary); [`NONE`] if isolated.
    pub vhe: Vec<u32>,
    pub kind: Vec<VertexKind>,
    pub vertex_dead: Vec<bool>,
    pub face_dead: Vec<bool>,
    /// Non-manifold vertices: never moved, removed or given new edges by a flip.
    pub locked: Vec<bool>,
    /// Per vertex: the unit normal of the reference where the vertex lies (maintained by the
    /// remesher; initially the area-weighted vertex normals of the input).
    pub normal: Vec<DVec3>,
}

impl HalfedgeMesh {
    /// Builds the halfedge mesh of `mesh`. Faces with out-of-range or repeated indices are dropped;
    /// unreferenced vertices are dead. Edges whose dihedral angle exceeds `feature_angle` (radians)
    /// are features; with `feature_angle ≥ π` there are none. Constrained curves (boundary and
    /// features) turning by more than `corner_angle` at a vertex make it a corner.
    pub fn from_mesh(mesh: &TriMesh, feature_angle: f64, corner_angle: f64) -> Self {
        let nv = mesh.positions.len();
        let tri: Vec<[u32; 3]> =
            mesh.triangles.iter().copied().filter(|t| t.iter().all(|&v| (v as usize) < nv) && t[0] != t[1] && t[1] != t[2] && t[0] != t[2]).collect();
        let nh = tri.len() * 3;
        let mut m = HalfedgeMesh {
            pos: mesh.positions.clone(),
            twin: vec![NONE; nh],
            edge_flag: vec![0; nh],
            vhe: vec![NONE; nv],
            kind: vec![VertexKind::Free; nv],
            vertex_dead: vec![true; nv],
            face_dead: vec![false; tri.len()],
            locked: vec![false; nv],
            normal: mesh.vertex_normals(),
            tri,
        };
        // Pair halfedges by sorting undirected keys (no hash maps).
        let mut keys: Vec<(u32, u32, u32)> = (0..nh as u32)
            .map(|h| {
                let (a, b) = (m.from(h), m.to(h));
                (a.min(b), a.max(b), h)
            })
            .collect();
        keys.sort_unstable();
        let mut i = 0;
        while i < keys.len() {
            let mut j = i + 1;
            while j < keys.len() && keys[j].0 == keys[i].0 && keys[j].1 == keys[i].1 {
                j += 1;
            }
            let group = &keys[i..j];
            if group.len() == 2 && m.from(group[0].2) == m.to(group[1].2) {
                m.twin[group[0].2 as usize] = group[1].2;
                m.twin[group[1].2 as usize] = group[0].2;
            } else if group.len() >= 2 {
                for &(a, b, h) in group {
                    m.edge_flag[h as usize] |= EDGE_FROZEN;
                    m.locked[a as usize] = true;
                    m.locked[b as usize] = true;
                }
            }
            i = j;
        }
        for h in 0..nh as u32 {
            let v = m.from(h) as usize;
            m.vertex_dead[v] = false;
            if m.vhe[v] == NONE {
                m.vhe[v] = h;
            }
        }
        // Outgoing boundary halfedge first; check that each vertex has a single fan.
        let mut incident = vec![0u32; nv];
        for t in &m.tri {
            for &v in t {
                incident[v as usize] += 1;
            }
        }
        for v in 0..nv {
            if m.vhe[v] == NONE {
                continue;
            }
            m.fix_vhe(v as u32, m.vhe[v]);
            let fan = m.outgoing(v as u32).len() as u32;
            if fan != incident[v] {
                m.locked[v] = true;
            }
        }
        // Feature edges by dihedral angle.
        if feature_angle < std::f64::consts::PI {
            let cos_f = feature_angle.cos();
            for h in 0..nh as u32 {
                let t = m.twin[h as usize];
                if t == NONE || t < h {
                    continue;
                }
                let (n0, n1) = (m.face_normal(face(h)), m.face_normal(face(t)));
                if let (Some(n0), Some(n1)) = (n0, n1) {
                    if n0.dot(n1) < cos_f {
                        m.edge_flag[h as usize] |= EDGE_FEATURE;
                        m.edge_flag[t as usize] |= EDGE_FEATURE;
                    }
                }
            }
        }
        m.classify_vertices(corner_angle);
        m
    }

    /// Vertex kinds from the constrained edges (boundary and features) around each vertex.
    fn classify_vertices(&mut self, corner_angle: f64) {
        let nv = self.pos.len();
        let mut degree = vec![0u32; nv];
        let mut ends = vec![[NONE; 2]; nv];
        let mut mixed = vec![false; nv];
        let mut boundary = vec![false; nv];
        for h in 0..self.twin.len() as u32 {
            let t = self.twin[h as usize];
            if t != NONE && t < h {
                continue;
            }
            if !self.is_constrained(h) {
                continue;
            }
            let (a, b) = (self.from(h), self.to(h));
            for (x, y) in [(a, b), (b, a)] {
                let x = x as usize;
                if degree[x] < 2 {
                    ends[x][degree[x] as usize] = y;
                }
                degree[x] += 1;
                if t == NONE {
                    boundary[x] = true;
                } else {
                    mixed[x] = mixed[x] || boundary[x];
                }
            }
        }
        // A boundary vertex with a feature edge counted before its boundary edges.
        for h in 0..self.twin.len() as u32 {
            if self.twin[h as usize] != NONE && self.edge_flag[h as usize] & EDGE_FEATURE != 0 {
                let (a, b) = (self.from(h) as usize, self.to(h) as usize);
                mixed[a] |= boundary[a];
                mixed[b] |= boundary[b];
            }
        }
        let cos_c = corner_angle.cos();
        for v in 0..nv {
            self.kind[v] = if self.locked[v] || mixed[v] {
                VertexKind::Corner
            } else {
                match degree[v] {
                    0 => VertexKind::Free,
                    2 => {
                        let p = self.pos[v];
                        let (u, w) = (self.pos[ends[v][0] as usize], self.pos[ends[v][1] as usize]);
                        let (d0, d1) = ((p - u).normalize_or_zero(), (w - p).normalize_or_zero());
                        if d0.dot(d1) >= cos_c {
                            VertexKind::Slide
                        } else {
                            VertexKind::Corner
                        }
                    }
                    _ => VertexKind::Corner,
                }
            };
        }
    }

    #[inline]
    pub fn from(&self, h: u32) -> u32 {
        self.tri[face(h)][(h % 3) as usize]
    }

    #[inline]
    pub fn to(&self, h: u32) -> u32 {
        self.from(next(h))
    }

    #[inline]
    pub fn twin(&self, h: u32) -> u32 {
        self.twin[h as usize]
    }

    #[inline]
    fn set_corner(&mut self, h: u32, v: u32) {
        self.tri[face(h)][(h % 3) as usize] = v;
    }

    #[inline]
    fn link(&mut self, x: u32, y: u32) {
        if x != NONE {
            self.twin[x as usize] = y;
        }
        if y != NONE {
            self.twin[y as usize] = x;
        }
    }

    /// Boundary or feature (or frozen) edge.
    #[inline]
    pub(crate) fn is_constrained(&self, h: u32) -> bool {
        self.twin[h as usize] == NONE || self.edge_flag[h as usize] != 0
    }

    #[inline]
    pub fn is_boundary_edge(&self, h: u32) -> bool {
        self.twin[h as usize] == NONE
    }

    /// A vertex with a boundary edge.
    #[inline]
    pub fn is_boundary_vertex(&self, v: u32) -> bool {
        let h = self.vhe[v as usize];
        h != NONE && self.twin[h as usize] == NONE
    }

    pub fn face_count(&self) -> usize {
        self.face_dead.iter().filter(|&&d| !d).count()
    }

    /// Unit normal of face `f` (None when degenerate).
    pub fn face_normal(&self, f: usize) -> Option<DVec3> {
        let [a, b, c] = self.tri[f].map(|v| self.pos[v as usize]);
        (b - a).cross(c - a).try_normalize()
    }

    /// Makes `vhe[v]` the outgoing boundary halfedge if there is one, starting from the outgoing
    /// halfedge `h`.
    pub(crate) fn fix_vhe(&mut self, v: u32, h: u32) {
        debug_assert_eq!(self.from(h), v);
        let mut cur = h;
        loop {
            let t = self.twin[cur as usize];
            if t == NONE {
                break;
            }
            let n = next(t);
            if n == h {
                break;
            }
            cur = n;
        }
        self.vhe[v as usize] = cur;
    }

    /// Outgoing halfedges of `v`, counter-clockwise (starting at the boundary one).
    pub fn outgoing(&self, v: u32) -> Vec<u32> {
        let mut out = Vec::with_capacity(8);
        self.outgoing_into(v, &mut out);
        out
    }

    /// [`Self::outgoing`] into a reused buffer.
    pub(crate) fn outgoing_into(&self, v: u32, out: &mut Vec<u32>) {
        out.clear();
        let start = self.vhe[v as usize];
        if start == NONE {
            return;
        }
        let mut h = start;
        loop {
            out.push(h);
            let t = self.twin[prev(h) as usize];
            if t == NONE || t == start || out.len() > 1_000_000 {
                break;
            }
            h = t;
        }
    }

    /// Neighbours of `v` (targets of its outgoing halfedges, plus the last boundary neighbour).
    pub(crate) fn one_ring_into(&self, v: u32, out: &mut Vec<u32>) {
        self.outgoing_into(v, out);
        let Some(&last) = out.last() else { return };
        let p = prev(last);
        let boundary = self.twin[p as usize] == NONE;
        for h in out.iter_mut() {
            *h = self.to(*h);
        }
        if boundary {
            out.push(self.from(p));
        }
    }

    /// Number of neighbours of `v`.
    pub fn valence(&self, v: u32) -> usize {
        let start = self.vhe[v as usize];
        if start == NONE {
            return 0;
        }
        let mut n = 0;
        let mut h = start;
        loop {
            n += 1;
            let t = self.twin[prev(h) as usize];
            if t == NONE {
                return n + 1;
            }
            if t == start || n > 1_000_000 {
                return n;
            }
            h = t;
        }
    }

    /// Appends a vertex (reference normal zero until set).
    pub(crate) fn add_vertex(&mut self, p: DVec3, kind: VertexKind) -> u32 {
        self.pos.push(p);
        self.normal.push(DVec3::ZERO);
        self.vhe.push(NONE);
        self.kind.push(kind);
        self.vertex_dead.push(false);
        self.locked.push(false);
        (self.pos.len() - 1) as u32
    }

    fn add_face(&mut self, t: [u32; 3]) -> u32 {
        self.tri.push(t);
        self.twin.extend([NONE; 3]);
        self.edge_flag.extend([0; 3]);
        self.face_dead.push(false);
        (self.tri.len() - 1) as u32
    }

    /// Splits the edge of halfedge `h` (a → b) at a new vertex at `p`: the faces (a, b, c) and
    /// (b, a, d) become (a, m, c), (m, b, c), (b, m, d), (m, a, d). The halves keep the edge's flags;
    /// the new vertex slides on a constrained edge and is free otherwise. Returns m and the
    /// halfedge m → b (`h` itself becomes a → m).
    pub fn split(&mut self, h: u32, p: DVec3) -> (u32, u32) {
        let t = self.twin[h as usize];
        let (a, b, c) = (self.from(h), self.to(h), self.from(prev(h)));
        let flag = self.edge_flag[h as usize];
        let kind = if self.is_constrained(h) { VertexKind::Slide } else { VertexKind::Free };
        let m = self.add_vertex(p, kind);
        self.normal[m as usize] = (self.normal[a as usize] + self.normal[b as usize]).normalize_or_zero();
        // (a, b, c) → (a, m, c) + (m, b, c).
        let g0 = self.split_face(h, m);
        self.edge_flag[g0 as usize] = flag;
        if t != NONE {
            // (b, a, d) → (b, m, d) + (m, a, d).
            let d = self.to(next(t));
            let q0 = self.split_face(t, m);
            self.link(h, q0);
            self.link(t, g0);
            self.edge_flag[q0 as usize] = flag;
            self.fix_vhe(d, q0 + 2);
        } else {
            self.twin[h as usize] = NONE;
            self.twin[g0 as usize] = NONE;
        }
        self.fix_vhe(m, g0);
        self.fix_vhe(a, h);
        self.fix_vhe(b, g0 + 1);
        self.fix_vhe(c, g0 + 2);
        (m, g0)
    }

    /// One side of [`Self::split`]: the face (u, v, w) of halfedge `x` (u → v) becomes
    /// (u, m, w) + a new face (m, v, w), whose halfedge v → w takes over the outer twin and flag
    /// of v → w, and whose w → m is twinned with the old face's new m → w. Returns the new
    /// face's m → v (twin and flag still to set).
    fn split_face(&mut self, x: u32, m: u32) -> u32 {
        let xn = next(x);
        let (v, w) = (self.to(x), self.to(xn));
        self.set_corner(xn, m);
        let outer = self.twin[xn as usize];
        let f = self.add_face([m, v, w]);
        let (q0, q1, q2) = (3 * f, 3 * f + 1, 3 * f + 2);
        self.link(q1, outer);
        self.edge_flag[q1 as usize] = self.edge_flag[xn as usize];
        self.edge_flag[xn as usize] = 0;
        self.link(q2, xn);
        q0
    }

    /// Collapses the edge of halfedge `h` (a → b), removing `remove` (a or b) into the other vertex,
    /// which moves to `p`. The faces (a, b, c) and (b, a, d) disappear and their outer edges are
    /// glued (flags or-ed). Check [`Self::collapse_is_topologically_ok`] first.
    pub fn collapse(&mut self, h: u32, remove: u32, p: DVec3) {
        let (a, b) = (self.from(h), self.to(h));
        debug_assert!(remove == a || remove == b);
        let keep = if remove == a { b } else { a };
        let t = self.twin[h as usize];
        let (hn, hp) = (next(h), prev(h));
        let c = self.from(hp);
        let removed_out = self.outgoing(remove);
        let kept_out = self.outgoing(keep);
        // Glue the outer edges of (a, b, c): a→c (twin of c→a) with c→b (twin of b→c).
        let (x, y) = (self.twin[hp as usize], self.twin[hn as usize]);
        let flag_c = self.edge_flag[hp as usize] | self.edge_flag[hn as usize];
        self.link(x, y);
        for z in [x, y] {
            if z != NONE {
                self.edge_flag[z as usize] = flag_c;
            }
        }
        let (mut x2, mut y2, mut d) = (NONE, NONE, NONE);
        if t != NONE {
            let (tn, tp) = (next(t), prev(t));
            d = self.from(tp);
            // d→a (twin of a→d) with b→d (twin of d→b).
            x2 = self.twin[tn as usize];
            y2 = self.twin[tp as usize];
            let flag_d = self.edge_flag[tn as usize] | self.edge_flag[tp as usize];
            self.link(x2, y2);
            for z in [x2, y2] {
                if z != NONE {
                    self.edge_flag[z as usize] = flag_d;
                }
            }
            self.face_dead[face(t)] = true;
        }
        self.face_dead[face(h)] = true;
        for &o in &removed_out {
            if !self.face_dead[face(o)] {
                self.set_corner(o, keep);
            }
        }
        self.vertex_dead[remove as usize] = true;
        self.vhe[remove as usize] = NONE;
        self.pos[keep as usize] = p;
        // New outgoing halfedges for keep, c, d.
        let alive = |m: &Self, e: u32| e != NONE && !m.face_dead[face(e)];
        let pick = |m: &Self, v: u32, cands: &[u32]| cands.iter().copied().find(|&e| alive(m, e) && m.from(e) == v);
        let mut cands: Vec<u32> = vec![x, y2];
        cands.extend(removed_out.iter().copied());
        cands.extend(kept_out.iter().copied());
        match pick(self, keep, &cands) {
            Some(e) => self.fix_vhe(keep, e),
            None => self.vhe[keep as usize] = NONE,
        }
        let cc = [y, if x != NONE { next(x) } else { NONE }];
        match pick(self, c, &cc) {
            Some(e) => self.fix_vhe(c, e),
            None => self.vhe[c as usize] = NONE,
        }
        if d != NONE {
            let dc = [x2, if y2 != NONE { next(y2) } else { NONE }];
            match pick(self, d, &dc) {
                Some(e) => self.fix_vhe(d, e),
                None => self.vhe[d as usize] = NONE,
            }
        }
    }

    /// Flips the interior edge of `h` (a → b): (a, b, c), (b, a, d) become (a, d, c), (d, b, c).
    /// Check [`Self::flip_is_topologically_ok`] first.
    pub fn flip(&mut self, h: u32) {
        let t = self.twin[h as usize];
        debug_assert!(t != NONE);
        let (hn, hp, tn, tp) = (next(h), prev(h), next(t), prev(t));
        let (a, b, c, d) = (self.from(h), self.to(h), self.from(hp), self.from(tp));
        // Outer twins and flags: b→c (hn), c→a (hp), a→d (tn), d→b (tp).
        let (o_bc, o_ca, o_ad, o_db) = (self.twin[hn as usize], self.twin[hp as usize], self.twin[tn as usize], self.twin[tp as usize]);
        let (f_bc, f_ca, f_ad, f_db) =
            (self.edge_flag[hn as usize], self.edge_flag[hp as usize], self.edge_flag[tn as usize], self.edge_flag[tp as usize]);
        let (f0, f1) = (face(h) as u32, face(t) as u32);
        self.tri[f0 as usize] = [a, d, c];
        self.tri[f1 as usize] = [d, b, c];
        let (e0, e1, e2) = (3 * f0, 3 * f0 + 1, 3 * f0 + 2); // a→d, d→c, c→a
        let (k0, k1, k2) = (3 * f1, 3 * f1 + 1, 3 * f1 + 2); // d→b, b→c, c→d
        self.link(e0, o_ad);
        self.link(e2, o_ca);
        self.link(k0, o_db);
        self.link(k1, o_bc);
        self.link(e1, k2);
        self.edge_flag[e0 as usize] = f_ad;
        self.edge_flag[e2 as usize] = f_ca;
        self.edge_flag[k0 as usize] = f_db;
        self.edge_flag[k1 as usize] = f_bc;
        self.edge_flag[e1 as usize] = 0;
        self.edge_flag[k2 as usize] = 0;
        self.fix_vhe(a, e0);
        self.fix_vhe(b, k1);
        self.fix_vhe(c, e2);
        self.fix_vhe(d, e1);
    }

    /// Whether collapsing the edge of `h` (a → b) keeps the mesh a manifold with the same topology:
    /// link condition (the common neighbours of a and b are exactly the opposite vertices), no
    /// interior edge between two boundary vertices, no isolated triangle or three-edge boundary
    /// loop, and the opposite vertices keep valence ≥ 3 (≥ 2 on the boundary). `stamp` is scratch
    /// space (one u32 per vertex) with a generation counter.
    pub fn collapse_is_topologically_ok(&self, h: u32, stamp: &mut Stamp, ring: &mut Vec<u32>) -> bool {
        let (a, b) = (self.from(h), self.to(h));
        if self.locked[a as usize] || self.locked[b as usize] || self.edge_flag[h as usize] & EDGE_FROZEN != 0 {
            return false;
        }
        let t = self.twin[h as usize];
        let hp = prev(h);
        let c = self.from(hp);
        let d = if t != NONE { self.from(prev(t)) } else { NONE };
        if t == NONE {
            // Boundary edge: collapsing it shortens its boundary loop, which must keep ≥ 3 edges
            // (this also rejects isolated triangles).
            if self.boundary_loop_len(a, 4) <= 3 {
                return false;
            }
        } else if self.is_boundary_vertex(a) && self.is_boundary_vertex(b) {
            return false;
        }
        // Link condition.
        let g = stamp.fresh();
        self.one_ring_into(a, ring);
        for &w in ring.iter() {
            stamp.marks[w as usize] = g;
        }
        self.one_ring_into(b, ring);
        let mut common = 0;
        for &w in ring.iter() {
            if stamp.marks[w as usize] == g {
                if w != c && w != d {
                    return false;
                }
                common += 1;
            }
        }
        if common != if t == NONE { 1 } else { 2 } {
            return false;
        }
        for v in [c, d] {
            if v == NONE {
                continue;
            }
            let min = if self.is_boundary_vertex(v) { 3 } else { 4 };
            if self.valence(v) < min {
                return false;
            }
        }
        // The merged vertex needs valence ≥ 3.
        let merged = self.valence(a) + self.valence(b) - if t == NONE { 3 } else { 4 };
        merged >= 3
    }

    /// Number of edges of the boundary loop through boundary vertex `v`, counted up to `cap`.
    pub(crate) fn boundary_loop_len(&self, v: u32, cap: usize) -> usize {
        let mut cur = v;
        for n in 1..=cap {
            let h = self.vhe[cur as usize];
            if h == NONE || self.twin[h as usize] != NONE {
                return usize::MAX;
            }
            cur = self.to(h);
            if cur == v {
                return n;
            }
        }
        cap + 1
    }

    /// Whether flipping the edge of `h` is allowed topologically: interior, not constrained, the
    /// new edge c–d does not exist yet, a and b keep valence ≥ 3, no locked vertex.
    pub fn flip_is_topologically_ok(&self, h: u32, ring: &mut Vec<u32>) -> bool {
        let t = self.twin[h as usize];
        if t == NONE || self.edge_flag[h as usize] != 0 {
            return false;
        }
        let (a, b) = (self.from(h), self.to(h));
        let (c, d) = (self.from(prev(h)), self.from(prev(t)));
        if c == d || [a, b, c, d].iter().any(|&v| self.locked[v as usize]) {
            return false;
        }
        for v in [a, b] {
            let min = if self.is_boundary_vertex(v) { 3 } else { 4 };
            if self.valence(v) < min {
                return false;
            }
        }
        self.one_ring_into(c, ring);
        !ring.contains(&d)
    }

    /// Drops dead faces and vertices, renumbering everything. Returns the old → new vertex map
    /// ([`NONE`] for removed vertices).
    pub fn compact(&mut self) -> Vec<u32> {
        let nv = self.pos.len();
        let mut vmap = vec![NONE; nv];
        let mut k = 0u32;
        for v in 0..nv {
            if !self.vertex_dead[v] && self.vhe[v] != NONE {
                vmap[v] = k;
                k += 1;
            }
        }
        let nf = self.tri.len();
        let mut fmap = vec![NONE; nf];
        let mut kf = 0u32;
        for f in 0..nf {
            if !self.face_dead[f] {
                fmap[f] = kf;
                kf += 1;
            }
        }
        let hmap = |h: u32| if h == NONE { NONE } else { 3 * fmap[face(h)] + h % 3 };
        let mut tri = Vec::with_capacity(kf as usize);
        let mut twin = Vec::with_capacity(3 * kf as usize);
        let mut edge_flag = Vec::with_capacity(3 * kf as usize);
        for f in 0..nf {
            if self.face_dead[f] {
                continue;
            }
            tri.push(self.tri[f].map(|v| vmap[v as usize]));
            for j in 0..3 {
                let h = 3 * f + j;
                twin.push(hmap(self.twin[h]));
                edge_flag.push(self.edge_flag[h]);
            }
        }
        let mut pos = Vec::with_capacity(k as usize);
        let mut vhe = Vec::with_capacity(k as usize);
        let mut kind = Vec::with_capacity(k as usize);
        let mut locked = Vec::with_capacity(k as usize);
        let mut normal = Vec::with_capacity(k as usize);
        for v in 0..nv {
            if vmap[v] != NONE {
                normal.push(self.normal[v]);
                pos.push(self.pos[v]);
                vhe.push(hmap(self.vhe[v]));
                kind.push(self.kind[v]);
                locked.push(self.locked[v]);
            }
        }
        self.pos = pos;
        self.vhe = vhe;
        self.kind = kind;
        self.locked = locked;
        self.normal = normal;
        self.vertex_dead = vec![false; k as usize];
        self.face_dead = vec![false; kf as usize];
        self.tri = tri;
        self.twin = twin;
        self.edge_flag = edge_flag;
        vmap
    }

    /// The live faces as a [`TriMesh`] (compacted copy).
    pub fn to_mesh(&self) -> TriMesh {
        let mut c = self.clone();
        c.compact();
        TriMesh::new(c.pos, c.tri)
    }

    /// Consistency check of the connectivity (for tests and debug assertions): twins are mutual
    /// and opposite, every live vertex's outgoing halfedge starts at it (twinless on the boundary),
    /// and rotating around it visits all its faces. Returns a description of the first problem.
    pub fn check(&self) -> Result<(), String> {
        for f in 0..self.tri.len() {
            if self.face_dead[f] {
                continue;
            }
            let t = self.tri[f];
            if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
                return Err(format!("face {f} repeats a vertex: {t:?}"));
            }
            for j in 0..3 {
                let h = (3 * f + j) as u32;
                if self.vertex_dead[self.from(h) as usize] {
                    return Err(format!("face {f} uses a dead vertex"));
                }
                let o = self.twin[h as usize];
                if o == NONE {
                    continue;
                }
                if self.face_dead[face(o)] {
                    return Err(format!("halfedge {h} twinned with dead face"));
                }
                if self.twin[o as usize] != h {
                    return Err(format!("twin of {h} is not mutual"));
                }
                if self.from(o) != self.to(h) || self.to(o) != self.from(h) {
                    return Err(format!("twin of {h} is not opposite"));
                }
                if self.edge_flag[o as usize] != self.edge_flag[h as usize] {
                    return Err(format!("edge flags of {h} differ on its twin"));
                }
            }
        }
        let mut incident = vec![0usize; self.pos.len()];
        for f in 0..self.tri.len() {
            if !self.face_dead[f] {
                for &v in &self.tri[f] {
                    incident[v as usize] += 1;
                }
            }
        }
        for v in 0..self.pos.len() {
            if self.vertex_dead[v] || self.locked[v] {
                continue;
            }
            let h = self.vhe[v];
            if h == NONE {
                if incident[v] > 0 {
                    return Err(format!("vertex {v} has faces but no halfedge"));
                }
                continue;
            }
            if self.face_dead[face(h)] || self.from(h) != v as u32 {
                return Err(format!("vertex {v} has a bad outgoing halfedge"));
            }
            if self.outgoing(v as u32).len() != incident[v] {
                return Err(format!("vertex {v}: fan of {} faces, {} incident", self.outgoing(v as u32).len(), incident[v]));
            }
        }
        Ok(())
    }
}

/// Generation-stamped marks (no clearing between uses).
#[derive(Clone, Debug, Default)]
pub struct Stamp {
    pub marks: Vec<u32>,
    generation: u32,
}

impl Stamp {
    pub fn new(n: usize) -> Self {
        Self { marks: vec![0; n], generation: 0 }
    }

    /// A fresh generation: no vertex is marked with it yet.
    pub fn fresh(&mut self) -> u32 {
        if self.generation == u32::MAX {
            self.marks.iter_mut().for_each(|m| *m = 0);
            self.generation = 0;
        }
        self.generation += 1;
        self.generation
    }

    /// Grows to at least `n` marks.
    pub fn ensure(&mut self, n: usize) {
        if self.marks.len() < n {
            self.marks.resize(n, 0);
        }
    }
}
