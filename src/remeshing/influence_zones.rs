//! Influence zones and the sizing field g (paper Sec. 3, Fig. 13).
//!
//! For each vertex v_i of the dense reference mesh a region U_i is grown breadth-first over mesh
//! edges, starting at v_i and admitting a neighbour only while its distance to the vertex's sphere
//! C_i (by default the central sphere, Def. 2.9) is below ε. g(v_i) is the diameter of U_i (measured
//! as described under **Diameter**), clamped to [g_min, g_max], and g is interpolated linearly (barycentrically) across the reference
//! triangles; a point off the reference takes the value at its closest point.
//!
//! **Diameter.** The paper takes the diameter of U_i, assuming U_i is "roughly disk-shaped". It is
//! not in general: the central sphere has the surface's normal curvature H only in the two
//! directions bisecting the principal ones, so where κ1 ≠ κ2 the ε-band around v_i is a disc of
//! radius ≈ √(4ε / |κ1 − κ2|) with four thin arms along those directions (an X; on a cylinder of
//! radius r the arms run along 45° helices and reach far beyond the disc). Their length depends on
//! higher-order terms and on how the triangulation happens to follow them, so a max-pairwise
//! diameter would be mesh-dependent and much too large. We therefore measure the **diameter of the
//! largest disc around v_i inside the zone**: the zone is grown over mesh edges in order of
//! Euclidean distance from v_i (best-first rather than hop-count breadth-first), and g(v_i) = 2r
//! with r the distance at which the growth first reaches a vertex farther than ε from C_i (the
//! crossing interpolated linearly on the edge from the zone), or the distance of the farthest zone
//! vertex when the connected component contains no such vertex. For a disc-shaped zone centred at
//! v_i this is its diameter; a zone cut by the mesh boundary (a half disc) keeps its full
//! diameter 2r, because the boundary is not a rejection. [`influence_zone`] still returns the full
//! U_i of the paper (for display).
//!
//! **Clamping and cost.** g never vanishes or explodes: g ∈ [g_min, g_max]. Growth stops as soon as
//! r reaches g_max / 2 (the value would be clamped anyway), which bounds the work per vertex by the
//! number of reference vertices within g_max / 2 of it (O(k log k) with a binary heap). It stops
//! at the first vertex off the band, so the arms are never explored. The defaults
//! ([`SizingBounds::for_mesh`]) are g_min = ½ · the mean edge length of the reference (so a remesh
//! is never much finer than the reference) and g_max = ¼ · the bounding-box diagonal.
//!
//! **Special cases.** Where H ≈ 0 the central sphere is the tangent plane and [`Sphere::distance`]
//! is the distance to that plane. The mesh boundary does not stop the growth (see above). A vertex
//! that is itself farther than ε from its sphere (possible with spheres not through v_i), or whose
//! first neighbour is already off the band, gets g_min.
//!
//! **Boundary.** A panel's boundary arc between two boundary vertices runs nearly along a
//! geodesic of its sphere, while the reference's boundary curve turns in the surface with
//! geodesic curvature κ_g: over an edge of length L they part by about L² κ_g / 8. So at a
//! boundary vertex g is also at most √(8ε / κ_g) ([`cap_at_boundary`]), with κ_g the tangential
//! part of the boundary polyline's discrete curvature there. Without it a surface that one sphere
//! fits (a spherical patch) gets faces as large as g_max whose boundary arcs leave the reference's
//! footprint by far more than ε.
//!
//! **Gradation.** g may grow by at most [`GRADATION`] per unit length along the mesh
//! ([`limit_gradation`], after the clamping and the boundary cap). Without it a surface that one
//! sphere fits gets g_max faces right beside the boundary's short ones (chebyshev_sphere at
//! ε = 4e-4: edges from 0.013 to 0.38 of the diagonal on a sphere of radius 0.38); the remesher
//! cannot project the vertices of such a transition without flipping faces, leaves them up to
//! 0.04 of the diagonal off the reference, and the panels follow (92ε).
//!
//! **Variant (Fig. 16, bottom).** Any per-vertex sphere can replace the central sphere
//! ([`SizingField::from_sphere_fn`]); [`local_spheres_orthogonal`] gives the local least-squares
//! spheres orthogonal to an absolute sphere Ω.

// Negated float comparisons are deliberate: they also reject NaN.

use glam::DVec3;

use crate::congruence::central_spheres::CurvatureField;
use crate::geometry::absolute_sphere::AbsoluteSphere;
use crate::geometry::closest::{ClosestHit, TriangleBvh};
use crate::geometry::linalg::Svd;
use crate::geometry::mesh::topology::Topology;
use crate::geometry::mesh::TriMesh;
use crate::geometry::sphere::Sphere;
use crate::progress::{ignore, Cancelled, OnProgress, Progress};

/// Default ε, relative to the bounding-box diagonal. On the default sample (`Sample::Dome`, 3456
/// triangles) it gives g ∈ [1.0, 3.9] m and 367 faces after 10 rounds; 4× larger gives 107
/// faces, 4× smaller 1715 (measured in `tests/remesh.rs`).
pub const DEFAULT_EPSILON: f64 = 4e-4;

/// Default g_min as a fraction of the mean edge length of the reference.
pub(crate) const DEFAULT_G_MIN_EDGE_FACTOR: f64 = 0.5;
/// Default g_max as a fraction of the bounding-box diagonal.
pub(crate) const DEFAULT_G_MAX_DIAGONAL_FACTOR: f64 = 0.25;
/// How fast g may grow along the surface, per unit length ([`limit_gradation`]).
pub const GRADATION: f64 = 0.5;

/// How often the progress callback is called, in vertices.
const PROGRESS_EVERY: usize = 1024;

/// The range g is clamped to (absolute lengths).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SizingBounds {
    pub g_min: f64,
    pub g_max: f64,
}

impl SizingBounds {
    /// [½ · mean edge length, ¼ · bbox diagonal] of `mesh` (see the module documentation).
    pub fn for_mesh(mesh: &TriMesh, topo: &Topology) -> Self {
        let diag = mesh.bbox_diagonal();
        let mean = mean_edge_length(mesh, topo);
        let g_max = DEFAULT_G_MAX_DIAGONAL_FACTOR * diag;
        let g_min = (DEFAULT_G_MIN_EDGE_FACTOR * mean).min(g_max);
        Self { g_min, g_max }
    }
}

/// Mean length of the edges of `mesh` (0 without edges).
pub fn mean_edge_length(mesh: &TriMesh, topo: &Topology) -> f64 {
    let edges = topo.edges();
    if edges.is_empty() {
        return 0.0;
    }
    let sum: f64 = edges.iter().map(|e| mesh.positions[e[0] as usize].distance(mesh.positions[e[1] as usize])).sum();
    sum / edges.len() as f64
}

/// A target edge length g on a reference surface: one value per reference vertex, interpolated
/// linearly across its triangles.
#[derive(Clone, Debug)]
pub struct SizingField {
    values: Vec<f64>,
    triangles: Vec<[u32; 3]>,
    bvh: TriangleBvh,
    uniform: Option<f64>,
    bounds: SizingBounds,
}

impl SizingField {
    /// The constant field g on `mesh` (no closest-point queries are made).
    pub fn uniform(mesh: &TriMesh, g: f64) -> Self {
        Self {
            values: vec![g; mesh.vertex_count()],
            triangles: mesh.triangles.clone(),
            bvh: TriangleBvh::default(),
            uniform: Some(g),
            bounds: SizingBounds { g_min: g, g_max: g },
        }
    }

    /// The constant field whose uniform triangulation of `mesh` has about `faces` faces: for
    /// equilateral triangles of edge g, area A = N · √3/4 · g². A boundary of length P needs
    /// P / g vertices, so g is at least P / N: a sliver of tiny area but long boundary is not
    /// cut into far more than N faces.
    pub fn uniform_for_face_count(mesh: &TriMesh, faces: usize) -> Self {
        let n = faces.max(1) as f64;
        let area: f64 = (0..mesh.face_count()).map(|f| mesh.face_area_vector(f).length()).sum();
        let g = (4.0 * area / (3f64.sqrt() * n)).sqrt().max(boundary_length(mesh) / n);
        Self::uniform(mesh, g)
    }

    /// About how many faces a remesh to this field makes on `mesh` (the mesh it was built on):
    /// Σ over triangles of A_t / (√3/4 · g_t²), g_t the mean of its corners' values, plus the
    /// boundary's length in units of g (Sec. 3).
    pub(crate) fn expected_faces(&self, mesh: &TriMesh) -> f64 {
        let g_of = |v: u32| self.values.get(v as usize).copied().unwrap_or(self.bounds.g_min).max(f64::MIN_POSITIVE);
        let per_area = 4.0 / 3f64.sqrt();
        let interior: f64 = mesh
            .triangles
            .iter()
            .enumerate()
            .map(|(f, t)| {
                let g = (g_of(t[0]) + g_of(t[1]) + g_of(t[2])) / 3.0;
                per_area * mesh.face_area_vector(f).length() / (g * g)
            })
            .sum();
        let boundary: f64 =
            boundary_edges(mesh).map(|(a, b)| mesh.positions[a as usize].distance(mesh.positions[b as usize]) / g_of(a).min(g_of(b))).sum();
        interior + boundary
    }

    /// Influence zones of the given per-vertex spheres (normalized), ε absolute, default bounds.
    pub fn from_spheres(mesh: &TriMesh, topo: &Topology, spheres: &[Sphere], eps_abs: f64) -> Self {
        let bounds = SizingBounds::for_mesh(mesh, topo);
        let plane = |i: usize| Sphere::plane(mesh.positions[i], DVec3::Z);
        let sphere_of = |i: usize| spheres.get(i).copied().unwrap_or_else(|| plane(i));
        Self::from_sphere_fn(mesh, topo, &sphere_of, eps_abs, bounds, &mut ignore).expect("progress never cancels")
    }

    /// Influence zones of the central spheres of `field`, ε relative to the bbox diagonal,
    /// default bounds.
    pub fn from_curvature(mesh: &TriMesh, topo: &Topology, field: &CurvatureField, eps_rel: f64) -> Self {
        Self::from_spheres(mesh, topo, &field.central_spheres, eps_rel * mesh.bbox_diagonal())
    }

    /// Influence zones of arbitrary per-vertex spheres `sphere_of(i)` (normalized generalized
    /// spheres through or near v_i, e.g. central spheres or [`local_spheres_orthogonal`]), ε
    /// absolute. Reports step "sizing" every 1024 vertices.
    pub fn from_sphere_fn(
        mesh: &TriMesh,
        topo: &Topology,
        sphere_of: &dyn Fn(usize) -> Sphere,
        eps_abs: f64,
        bounds: SizingBounds,
        progress: &mut OnProgress,
    ) -> Result<Self, Cancelled> {
        let n = mesh.vertex_count().min(topo.vertex_count());
        let mut zones = ZoneGrower::new(n);
        let mut values = Vec::with_capacity(mesh.vertex_count());
        for i in 0..n {
            if i % PROGRESS_EVERY == 0 && i > 0 {
                progress(Progress::new("sizing", i, n))?;
            }
            let d = zones.diameter(mesh, topo, i, &sphere_of(i), eps_abs, bounds.g_max);
            values.push(d.clamp(bounds.g_min, bounds.g_max));
        }
        values.resize(mesh.vertex_count(), bounds.g_min);
        cap_at_boundary(mesh, topo, &mut values, eps_abs);
        limit_gradation(mesh, topo, &mut values, GRADATION);
        progress(Progress::new("sizing", n, n))?;
        Ok(Self::from_values(mesh, values, bounds))
    }

    /// A field from given per-vertex values (clamped to `bounds`).
    pub(crate) fn from_values(mesh: &TriMesh, values: Vec<f64>, bounds: SizingBounds) -> Self {
        let values = values.into_iter().map(|v| if v.is_finite() { v.clamp(bounds.g_min, bounds.g_max) } else { bounds.g_max }).collect();
        Self { values, triangles: mesh.triangles.clone(), bvh: TriangleBvh::new(mesh), uniform: None, bounds }
    }

    /// g at the reference vertices.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// The clamping range.
    pub fn bounds(&self) -> SizingBounds {
        self.bounds
    }

    /// Some(g) for a constant field.
    pub(crate) fn uniform_value(&self) -> Option<f64> {
        self.uniform
    }

    /// The BVH of the reference (empty for uniform fields).
    pub fn bvh(&self) -> &TriangleBvh {
        &self.bvh
    }

    /// Whether the field was built on exactly this mesh's triangles (so a hit of a BVH of `mesh`
    /// can be passed to [`Self::at_hit`]).
    pub(crate) fn is_defined_on(&self, mesh: &TriMesh) -> bool {
        self.uniform.is_none()
            && self.triangles == mesh.triangles
            && self.bvh.len() == mesh.face_count()
            && (0..mesh.face_count()).all(|f| self.bvh.triangle(f) == mesh.face_points(f))
    }

    /// g at the point of the reference closest to `p` (barycentric interpolation).
    pub fn at(&self, p: DVec3) -> f64 {
        if let Some(g) = self.uniform {
            return g;
        }
        match self.bvh.closest_point(p) {
            Some(hit) => self.at_hit(&hit),
            None => self.bounds.g_max,
        }
    }

    /// [`Self::at`] for a point known to be within about `max_distance` of the reference (the
    /// search is pruned by it; farther points fall back to the unbounded search).
    pub(crate) fn at_near(&self, p: DVec3, max_distance: f64) -> f64 {
        if let Some(g) = self.uniform {
            return g;
        }
        match self.bvh.closest_point_within(p, max_distance) {
            Some(hit) => self.at_hit(&hit),
            None => self.at(p),
        }
    }

    /// g at a closest-point hit on the reference this field was built on.
    pub fn at_hit(&self, hit: &ClosestHit) -> f64 {
        if let Some(g) = self.uniform {
            return g;
        }
        let t = self.triangles[hit.triangle];
        let w = hit.barycentric;
        w[0] * self.values[t[0] as usize] + w[1] * self.values[t[1] as usize] + w[2] * self.values[t[2] as usize]
    }

    /// Min, mean and max of the per-vertex values.
    pub fn summary(&self) -> (f64, f64, f64) {
        if self.values.is_empty() {
            return (0.0, 0.0, 0.0);
        }
        let (mut lo, mut hi, mut sum) = (f64::INFINITY, f64::NEG_INFINITY, 0.0);
        for &v in &self.values {
            lo = lo.min(v);
            hi = hi.max(v);
            sum += v;
        }
        (lo, sum / self.values.len() as f64, hi)
    }
}

/// Limits the growth of g along the mesh edges to `gradation` per unit length: g(v) ≤ g(u) +
/// gradation · |u − v| over every path (Dijkstra from all vertices at once), so large faces do not
/// meet small ones abruptly.
pub fn limit_gradation(mesh: &TriMesh, topo: &Topology, values: &mut [f64], gradation: f64) {
    use std::cmp::Reverse;
    use std::collections::BinaryHeap;
    let n = values.len().min(topo.vertex_count());
    let key = |g: f64| Reverse(g.to_bits());
    let mut heap: BinaryHeap<(Reverse<u64>, u32)> = (0..n).filter(|&v| values[v] >= 0.0).map(|v| (key(values[v]), v as u32)).collect();
    while let Some((Reverse(bits), u)) = heap.pop() {
        let g = f64::from_bits(bits);
        if g > values[u as usize] {
            continue;
        }
        for &w in topo.vertex_neighbors(u as usize) {
            let w = w as usize;
            if w >= n {
                continue;
            }
            let candidate = g + gradation * mesh.positions[u as usize].distance(mesh.positions[w]);
            if candidate < values[w] {
                values[w] = candidate;
                heap.push((key(candidate), w as u32));
            }
        }
    }
}

/// The largest turn of the boundary polyline at a vertex that [`cap_at_boundary`] reads as the
/// curvature of a smooth boundary curve; sharper turns are corners.
pub const MAX_BOUNDARY_TURN_DEG: f64 = 30.0;

/// Caps g at every boundary vertex of `mesh` by √(8ε / κ_g) (see the module docs): κ_g is the
/// part tangent to the surface of the boundary polyline's curvature vector
/// (t₂ − t₁) / (½ (|e₁| + |e₂|)), t₁, t₂ the unit directions of the two boundary edges at the
/// vertex, and the surface normal the sum of the incident faces' area vectors. Corners (turns over
/// [`MAX_BOUNDARY_TURN_DEG`]) and vertices on more or fewer than two boundary edges are left alone.
pub fn cap_at_boundary(mesh: &TriMesh, topo: &Topology, values: &mut [f64], eps_abs: f64) {
    let mut ends: Vec<Vec<u32>> = vec![Vec::new(); topo.vertex_count()];
    for (e, &[a, b]) in topo.edges().iter().enumerate() {
        if topo.edge_face_counts()[e] == 1 {
            ends[a as usize].push(b);
            ends[b as usize].push(a);
        }
    }
    for (v, ends) in ends.iter().enumerate() {
        let &[u, w] = ends.as_slice() else { continue };
        let p = mesh.positions[v];
        let (e1, e2) = (p - mesh.positions[u as usize], mesh.positions[w as usize] - p);
        let (l1, l2) = (e1.length(), e2.length());
        if !(l1 > 0.0 && l2 > 0.0) {
            continue;
        }
        // A corner of the boundary is kept as a vertex by the remesher and needs no short edges.
        if (e1 / l1).dot(e2 / l2) < MAX_BOUNDARY_TURN_DEG.to_radians().cos() {
            continue;
        }
        let k = (e2 / l2 - e1 / l1) / (0.5 * (l1 + l2));
        let n = topo.vertex_faces(v).iter().map(|&f| mesh.face_area_vector(f as usize)).sum::<DVec3>().normalize_or_zero();
        let kg = (k - k.dot(n) * n).length();
        if kg > 0.0 && v < values.len() {
            values[v] = values[v].min((8.0 * eps_abs / kg).sqrt());
        }
    }
}

/// The influence zone U_i of vertex `i` for `sphere` and ε = `eps_abs`, as in the paper: the
/// vertices reached breadth-first over mesh edges from v_i through vertices within ε of the sphere
/// (complete, no cut-off). Vertex indices, `i` first; empty if v_i itself is not within ε.
pub fn influence_zone(mesh: &TriMesh, topo: &Topology, i: usize, sphere: &Sphere, eps_abs: f64) -> Vec<u32> {
    let n = mesh.vertex_count().min(topo.vertex_count());
    if i >= n {
        return Vec::new();
    }
    ZoneGrower::new(n).full_zone(topo, &mesh.positions, i, sphere, eps_abs)
}

/// g(v_i) before clamping: the diameter of the largest disc around v_i inside its influence zone
/// (see the module documentation); `cap` stops the growth early (g_max).
pub fn zone_diameter(mesh: &TriMesh, topo: &Topology, i: usize, sphere: &Sphere, eps_abs: f64, cap: f64) -> f64 {
    let n = mesh.vertex_count().min(topo.vertex_count());
    if i >= n {
        return 0.0;
    }
    ZoneGrower::new(n).diameter(mesh, topo, i, sphere, eps_abs, cap)
}

/// Growth of influence zones with a generation-stamped visited array.
struct ZoneGrower {
    stamp: Vec<u32>,
    generation: u32,
    region: Vec<u32>,
    heap: std::collections::BinaryHeap<Entry>,
}

/// Heap entry: a candidate vertex at squared distance `d2` from v_i, reached from the zone vertex
/// `from` (min-heap by `d2`).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Entry {
    d2: f64,
    vertex: u32,
    from: u32,
}

impl Eq for Entry {}

impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Entry {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        other.d2.total_cmp(&self.d2).then_with(|| other.vertex.cmp(&self.vertex))
    }
}

impl ZoneGrower {
    fn new(n: usize) -> Self {
        Self { stamp: vec![0; n], generation: 0, region: Vec::with_capacity(256), heap: Default::default() }
    }

    fn next_generation(&mut self) -> u32 {
        if self.generation == u32::MAX {
            self.stamp.iter_mut().for_each(|s| *s = 0);
            self.generation = 0;
        }
        self.generation += 1;
        self.generation
    }

    /// Diameter 2r of the largest disc around v_i inside its zone (see the module documentation):
    /// the zone is grown over mesh edges in order of Euclidean distance from v_i, and r is where
    /// it first meets a vertex off the ε-band (the crossing interpolated linearly on the edge from
    /// the zone), or the distance of the last zone vertex when the connected component is
    /// exhausted. Stops at r ≥ cap/2 (returns `cap`).
    fn diameter(&mut self, mesh: &TriMesh, topo: &Topology, i: usize, sphere: &Sphere, eps: f64, cap: f64) -> f64 {
        let g = self.next_generation();
        let pos = &mesh.positions;
        let p0 = pos[i];
        if !sphere.is_finite() || !(sphere.distance(p0) < eps) {
            return 0.0;
        }
        let dist = |q: DVec3| sphere.distance(q);
        self.heap.clear();
        self.stamp[i] = g;
        let mut r_max = 0.0f64;
        let half_cap = 0.5 * cap;
        let push_neighbors = |stamp: &mut Vec<u32>, heap: &mut std::collections::BinaryHeap<Entry>, v: usize| {
            for &w in topo.vertex_neighbors(v) {
                let wu = w as usize;
                if wu < stamp.len() && stamp[wu] != g {
                    stamp[wu] = g;
                    heap.push(Entry { d2: pos[wu].distance_squared(p0), vertex: w, from: v as u32 });
                }
            }
        };
        push_neighbors(&mut self.stamp, &mut self.heap, i);
        while let Some(e) = self.heap.pop() {
            let w = e.vertex as usize;
            let r = e.d2.sqrt();
            let dw = dist(pos[w]);
            if dw < eps {
                r_max = r_max.max(r);
                if r >= half_cap {
                    return cap;
                }
                push_neighbors(&mut self.stamp, &mut self.heap, w);
            } else {
                // Leaves the band between `from` (inside) and w: interpolate the crossing.
                let pf = pos[e.from as usize];
                let df = dist(pf);
                let t = if dw > df { ((eps - df) / (dw - df)).clamp(0.0, 1.0) } else { 0.0 };
                let x = pf + t * (pos[w] - pf);
                let r_exit = x.distance(p0).min(r);
                return (2.0 * r_exit).min(cap);
            }
        }
        (2.0 * r_max).min(cap)
    }

    /// The zone U_i of the paper: breadth-first over mesh edges through vertices within ε of the
    /// sphere (the whole connected part of the ε-band containing v_i).
    fn full_zone(&mut self, topo: &Topology, pos: &[DVec3], i: usize, sphere: &Sphere, eps: f64) -> Vec<u32> {
        let g = self.next_generation();
        self.region.clear();
        if !sphere.is_finite() || !(sphere.distance(pos[i]) < eps) {
            return Vec::new();
        }
        self.region.push(i as u32);
        self.stamp[i] = g;
        let mut head = 0;
        while head < self.region.len() {
            let v = self.region[head] as usize;
            head += 1;
            for &w in topo.vertex_neighbors(v) {
                let wu = w as usize;
                if wu < self.stamp.len() && self.stamp[wu] != g {
                    self.stamp[wu] = g;
                    if sphere.distance(pos[wu]) < eps {
                        self.region.push(w);
                    }
                }
            }
        }
        self.region.clone()
    }
}

/// Local least-squares spheres orthogonal to the absolute sphere Ω (paper Sec. 3 and Fig. 16,
/// bottom), one per vertex, for [`SizingField::from_sphere_fn`].
///
/// For vertex v the neighbourhood is its k-rings (grown until at least `min_points` points or 4
/// rings). The sphere s = (a, b, c) is constrained to pass through v and to be orthogonal to Ω
/// (two linear conditions: [`Sphere::point_row`] and Ω's inversive row) and minimizes
/// Σ ψ_s(p_j)² / (bᵀb − 4ac) over the neighbours p_j (the Pratt-normalized algebraic distance,
/// ≈ Σ dist² near the sphere), solved in the frame centred at v and scaled to the neighbourhood
/// as a 3 × 3 generalized eigenproblem. Oriented like the mesh normal at v and normalized. Where it
/// is undetermined (fewer than 3 neighbours, degenerate data) the tangent plane through v is used.
pub fn local_spheres_orthogonal(mesh: &TriMesh, topo: &Topology, omega: &AbsoluteSphere, min_points: usize) -> Vec<Sphere> {
    let n = mesh.vertex_count().min(topo.vertex_count());
    let normals = mesh.vertex_normals();
    let mut stamp = vec![0u32; n];
    let mut ring: Vec<u32> = Vec::with_capacity(64);
    let omega_coeff = omega.coefficients();
    let mut out = Vec::with_capacity(n);
    for v in 0..n {
        let p0 = mesh.positions[v];
        let fallback = Sphere::plane(p0, normals[v]);
        // k-rings.
        let g = v as u32 + 1;
        ring.clear();
        ring.push(v as u32);
        stamp[v] = g;
        let (mut start, mut rings) = (0usize, 0usize);
        while rings < 4 && (rings == 0 || ring.len() < min_points.max(6)) {
            let end = ring.len();
            for k in start..end {
                for &w in topo.vertex_neighbors(ring[k] as usize) {
                    if (w as usize) < n && stamp[w as usize] != g {
                        stamp[w as usize] = g;
                        ring.push(w);
                    }
                }
            }
            if ring.len() == end {
                break;
            }
            start = end;
            rings += 1;
        }
        if ring.len() < 4 {
            out.push(fallback);
            continue;
        }
        let sigma = ring.iter().map(|&w| mesh.positions[w as usize].distance(p0)).sum::<f64>() / (ring.len() - 1) as f64;
        if !(sigma > 0.0) || !sigma.is_finite() {
            out.push(fallback);
            continue;
        }
        // Frame y = (x − v)/σ; spheres through the origin have c = 0: unknowns (a, b) ∈ R⁴.
        let o = omega_coeff.in_frame(p0, sigma);
        let row = o.inversive_row(); // ⟨Ω, s⟩ = row · (a, b, c)
        let r4 = [row[0], row[1], row[2], row[3]];
        let rn = r4.iter().map(|x| x * x).sum::<f64>().sqrt();
        // Basis Z (4 × 3) of the subspace orthogonal to r4 (all of R⁴ restricted if Ω's row vanishes).
        let z: Vec<[f64; 4]> = if rn > 1e-300 && rn.is_finite() {
            let svd = Svd::<4>::new(&[r4]);
            vec![svd.v[1], svd.v[2], svd.v[3]]
        } else {
            out.push(fallback);
            continue;
        };
        // M = Σ r_j r_jᵀ with r_j = (|y|², −y); Q = diag(0, 1, 1, 1).
        let mut mm = [[0.0f64; 3]; 3];
        let mut qq = [[0.0f64; 3]; 3];
        for &w in &ring[1..] {
            let y = (mesh.positions[w as usize] - p0) / sigma;
            let r = [y.length_squared(), -y.x, -y.y, -y.z];
            let rz: [f64; 3] = std::array::from_fn(|k| (0..4).map(|l| r[l] * z[k][l]).sum());
            for i in 0..3 {
                for j in 0..3 {
                    mm[i][j] += rz[i] * rz[j];
                }
            }
        }
        for i in 0..3 {
            for j in 0..3 {
                qq[i][j] = (1..4).map(|l| z[i][l] * z[j][l]).sum();
            }
        }
        // Largest μ of Q y = μ M y: M = U Λ Uᵀ, S = Λ^{-1/2} Uᵀ Q U Λ^{-1/2}, y = U Λ^{-1/2} w.
        let tr = mm[0][0] + mm[1][1] + mm[2][2];
        for (i, r) in mm.iter_mut().enumerate() {
            r[i] += 1e-13 * tr.max(1e-300);
        }
        let eig = Svd::<3>::new(&mm);
        let u = eig.v; // columns as rows: eigenvectors u[k]
        let lam = eig.sigma;
        if !(lam[2] > 0.0) {
            out.push(fallback);
            continue;
        }
        let mut s = [[0.0f64; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                let mut acc = 0.0;
                for k in 0..3 {
                    for l in 0..3 {
                        acc += u[i][k] * qq[k][l] * u[j][l];
                    }
                }
                s[i][j] = acc / (lam[i] * lam[j]).sqrt();
            }
        }
        let se = Svd::<3>::new(&s);
        let wv = se.v[0];
        let yv: [f64; 3] = std::array::from_fn(|k| (0..3).map(|i| u[i][k] * wv[i] / lam[i].sqrt()).sum());
        let coef: [f64; 4] = std::array::from_fn(|l| (0..3).map(|k| yv[k] * z[k][l]).sum());
        let sf = Sphere { a: coef[0], b: DVec3::new(coef[1], coef[2], coef[3]), c: 0.0 };
        let sw = sf.from_frame(p0, sigma).normalized();
        if sw.is_finite() && (sw.discriminant() - 1.0).abs() < 1e-6 {
            out.push(sw.orient_toward(p0, normals[v]));
        } else {
            out.push(fallback);
        }
    }
    out
}

/// The edges of `mesh` on fewer or more than two faces (boundary and non-manifold edges), once
/// each as (low, high) vertex, sorted (sums over them are deterministic).
fn boundary_edges(mesh: &TriMesh) -> impl Iterator<Item = (u32, u32)> {
    let mut count: std::collections::HashMap<(u32, u32), u32> = std::collections::HashMap::new();
    for t in &mesh.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *count.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    let mut edges: Vec<(u32, u32)> = count.into_iter().filter(|&(_, c)| c != 2).map(|(e, _)| e).collect();
    edges.sort_unstable();
    edges.into_iter()
}

/// Total length of the boundary (and non-manifold) edges of `mesh`.
fn boundary_length(mesh: &TriMesh) -> f64 {
    boundary_edges(mesh).map(|(a, b)| mesh.positions[a as usize].distance(mesh.positions[b as usize])).sum()
}
