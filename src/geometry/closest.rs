//! Closest points on triangles and on triangle meshes.
//!
//! [`closest_point_on_triangle`] is the region test of Ericson, *Real-Time Collision Detection*,
//! Sec. 5.1.5. [`TriangleBvh`] is a small bounding-volume hierarchy (axis-aligned boxes, median
//! split on the longest axis, at most [`LEAF_SIZE`] triangles per leaf) answering closest-point
//! queries by depth-first traversal, nearer child first, pruned by the box distance. Everything is
//! f64. Build is O(n log n); a query is about O(log n) for points near the surface.

use glam::DVec3;

use super::mesh::TriMesh;

/// Largest number of triangles in a BVH leaf.
pub const LEAF_SIZE: usize = 4;

/// The point of triangle `abc` closest to `p`, and its barycentric coordinates (weights of a, b,
/// c). Degenerate triangles (segments, points) are handled: the result is then a closest point
/// of the degenerate set.
pub fn closest_point_on_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> (DVec3, [f64; 3]) {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, [1.0, 0.0, 0.0]);
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return (b, [0.0, 1.0, 0.0]);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (a + v * ab, [1.0 - v, v, 0.0]);
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return (c, [0.0, 0.0, 1.0]);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (a + w * ac, [1.0 - w, 0.0, w]);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (b + w * (c - b), [0.0, 1.0 - w, w]);
    }
    let sum = va + vb + vc;
    if !sum.is_finite() || sum == 0.0 {
        // Degenerate (zero-area) triangle whose regions above did not decide: take the best of
        // the three edges.
        let seg = |s: DVec3, t: DVec3| {
            let d = t - s;
            let l2 = d.length_squared();
            let u = if l2 > 0.0 { ((p - s).dot(d) / l2).clamp(0.0, 1.0) } else { 0.0 };
            (s + u * d, u)
        };
        let (q0, u0) = seg(a, b);
        let (q1, u1) = seg(b, c);
        let (q2, u2) = seg(c, a);
        let cands = [(q0, [1.0 - u0, u0, 0.0]), (q1, [0.0, 1.0 - u1, u1]), (q2, [u2, 0.0, 1.0 - u2])];
        return cands.into_iter().min_by(|x, y| x.0.distance_squared(p).total_cmp(&y.0.distance_squared(p))).unwrap_or((a, [1.0, 0.0, 0.0]));
    }
    let denom = 1.0 / sum;
    let v = vb * denom;
    let w = vc * denom;
    (a + ab * v + ac * w, [1.0 - v - w, v, w])
}

/// Result of a closest-point query.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClosestHit {
    /// The closest point on the mesh.
    pub point: DVec3,
    /// Index of the triangle it lies on (in the order given to the BVH).
    pub triangle: usize,
    /// Barycentric coordinates of `point` in that triangle.
    pub barycentric: [f64; 3],
    /// Euclidean distance from the query point.
    pub distance: f64,
}

#[derive(Clone, Copy, Debug)]
struct Node {
    lo: DVec3,
    hi: DVec3,
    /// Leaf: first index into `order` and count (> 0). Inner: `count == 0`, children at
    /// `first` and `first + 1`.
    first: u32,
    count: u32,
}

/// A bounding-volume hierarchy over triangles for closest-point queries. It owns a copy of the
/// triangle corners, so it does not borrow the mesh.
#[derive(Clone, Debug, Default)]
pub struct TriangleBvh {
    tris: Vec<[DVec3; 3]>,
    /// Triangle indices in leaf order.
    order: Vec<u32>,
    nodes: Vec<Node>,
}

impl TriangleBvh {
    /// The BVH of a mesh's faces (out-of-range indices are skipped; triangle indices in hits are
    /// the face indices).
    pub fn new(mesh: &TriMesh) -> Self {
        let n = mesh.positions.len();
        let tris = mesh
            .triangles
            .iter()
            .map(|t| if t.iter().all(|&v| (v as usize) < n) { mesh_face(mesh, t) } else { [DVec3::splat(f64::NAN); 3] })
            .collect();
        Self::from_triangles(tris)
    }

    /// The BVH of explicit triangles. Triangles with non-finite corners are never hit.
    pub fn from_triangles(tris: Vec<[DVec3; 3]>) -> Self {
        let mut order: Vec<u32> = (0..tris.len() as u32).filter(|&i| tris[i as usize].iter().all(|p| p.is_finite())).collect();
        let centroids: Vec<DVec3> = tris.iter().map(|t| (t[0] + t[1] + t[2]) / 3.0).collect();
        let mut nodes = Vec::with_capacity(2 * order.len() / LEAF_SIZE + 1);
        if !order.is_empty() {
            nodes.push(Node { lo: DVec3::ZERO, hi: DVec3::ZERO, first: 0, count: 0 });
            // Explicit stack: (node index, range start, range end).
            let mut stack = vec![(0usize, 0usize, order.len())];
            while let Some((ni, start, end)) = stack.pop() {
                let (lo, hi) = bounds(&tris, &order[start..end]);
                nodes[ni].lo = lo;
                nodes[ni].hi = hi;
                if end - start <= LEAF_SIZE {
                    nodes[ni].first = start as u32;
                    nodes[ni].count = (end - start) as u32;
                    continue;
                }
                // Split at the median centroid along the longest axis of the centroid box.
                let (clo, chi) = order[start..end]
                    .iter()
                    .map(|&i| centroids[i as usize])
                    .fold((DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)), |(l, h), c| (l.min(c), h.max(c)));
                let ext = chi - clo;
                let axis = if ext.x >= ext.y && ext.x >= ext.z {
                    0
                } else if ext.y >= ext.z {
                    1
                } else {
                    2
                };
                let mid = (start + end) / 2;
                order[start..end].select_nth_unstable_by(mid - start, |&a, &b| centroids[a as usize][axis].total_cmp(&centroids[b as usize][axis]));
                let left = nodes.len();
                nodes.push(Node { lo: DVec3::ZERO, hi: DVec3::ZERO, first: 0, count: 0 });
                nodes.push(Node { lo: DVec3::ZERO, hi: DVec3::ZERO, first: 0, count: 0 });
                nodes[ni].first = left as u32;
                nodes[ni].count = 0;
                stack.push((left, start, mid));
                stack.push((left + 1, mid, end));
            }
        }
        Self { tris, order, nodes }
    }

    /// Number of triangles the BVH was built from (including skipped non-finite ones).
    pub fn len(&self) -> usize {
        self.tris.len()
    }

    pub fn is_empty(&self) -> bool {
        self.order.is_empty()
    }

    /// Corners of triangle `i`.
    pub fn triangle(&self, i: usize) -> [DVec3; 3] {
        self.tris[i]
    }

    /// The closest point on any triangle; None for an empty BVH or a non-finite query point.
    pub fn closest_point(&self, p: DVec3) -> Option<ClosestHit> {
        self.closest_point_within(p, f64::INFINITY)
    }

    /// The closest point at distance at most `max_distance`; None if there is none.
    pub(crate) fn closest_point_within(&self, p: DVec3, max_distance: f64) -> Option<ClosestHit> {
        let d2 = if max_distance.is_finite() { max_distance * max_distance } else { f64::INFINITY };
        self.search(p, d2, None)
    }

    /// [`Self::closest_point`], started from triangle `hint` (e.g. the last hit of a moving
    /// point): its closest point bounds the search, so a coherent query visits only the part of
    /// the hierarchy that could hold a nearer one. The same point as an unstarted search.
    pub(crate) fn closest_point_from(&self, p: DVec3, hint: usize) -> Option<ClosestHit> {
        let Some(&[a, b, c]) = self.tris.get(hint) else { return self.closest_point(p) };
        if !(a.is_finite() && b.is_finite() && c.is_finite()) {
            return self.closest_point(p);
        }
        let (q, barycentric) = closest_point_on_triangle(p, a, b, c);
        let d2 = q.distance_squared(p);
        let start = ClosestHit { point: q, triangle: hint, barycentric, distance: d2.sqrt() };
        self.search(p, d2, Some(start))
    }

    /// Depth-first search, nearer child first, for a point nearer than `best` (or within
    /// `best_d2`).
    fn search(&self, p: DVec3, mut best_d2: f64, mut best: Option<ClosestHit>) -> Option<ClosestHit> {
        if self.nodes.is_empty() || !p.is_finite() {
            return None;
        }
        // A median split keeps the depth below log2(n) + 1, and the stack below depth + 1.
        let mut stack = [(0u32, 0.0f64); 64];
        stack[0] = (0, box_distance2(p, self.nodes[0].lo, self.nodes[0].hi));
        let mut top = 1usize;
        while top > 0 {
            top -= 1;
            let (ni, d2) = stack[top];
            if d2 > best_d2 {
                continue;
            }
            let node = self.nodes[ni as usize];
            if node.count > 0 {
                for &ti in &self.order[node.first as usize..(node.first + node.count) as usize] {
                    let [a, b, c] = self.tris[ti as usize];
                    let (q, bary) = closest_point_on_triangle(p, a, b, c);
                    let dq = q.distance_squared(p);
                    if dq < best_d2 || (dq == best_d2 && best.is_none()) {
                        best_d2 = dq;
                        best = Some(ClosestHit { point: q, triangle: ti as usize, barycentric: bary, distance: dq.sqrt() });
                    }
                }
            } else {
                let (l, r) = (node.first, node.first + 1);
                let dl = box_distance2(p, self.nodes[l as usize].lo, self.nodes[l as usize].hi);
                let dr = box_distance2(p, self.nodes[r as usize].lo, self.nodes[r as usize].hi);
                // Push the farther child first so the nearer one is visited first.
                let (near, far) = if dl <= dr { ((l, dl), (r, dr)) } else { ((r, dr), (l, dl)) };
                stack[top] = far;
                stack[top + 1] = near;
                top += 2;
            }
        }
        best
    }

    /// Distance from `p` to the mesh (infinite for an empty BVH).
    pub fn distance(&self, p: DVec3) -> f64 {
        self.closest_point(p).map_or(f64::INFINITY, |h| h.distance)
    }
}

fn mesh_face(mesh: &TriMesh, t: &[u32; 3]) -> [DVec3; 3] {
    [mesh.positions[t[0] as usize], mesh.positions[t[1] as usize], mesh.positions[t[2] as usize]]
}

fn bounds(tris: &[[DVec3; 3]], ids: &[u32]) -> (DVec3, DVec3) {
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for &i in ids {
        for p in tris[i as usize] {
            lo = lo.min(p);
            hi = hi.max(p);
        }
    }
    (lo, hi)
}

/// Squared distance from `p` to the box [lo, hi] (0 inside).
fn box_distance2(p: DVec3, lo: DVec3, hi: DVec3) -> f64 {
    let d = (lo - p).max(DVec3::ZERO).max(p - hi);
    d.length_squared()
}

/// Brute-force closest point over all triangles of a mesh: the reference for tests.
pub fn closest_point_brute_force(mesh: &TriMesh, p: DVec3) -> Option<ClosestHit> {
    let mut best: Option<ClosestHit> = None;
    for (i, t) in mesh.triangles.iter().enumerate() {
        if t.iter().any(|&v| v as usize >= mesh.positions.len()) {
            continue;
        }
        let [a, b, c] = mesh_face(mesh, t);
        let (q, bary) = closest_point_on_triangle(p, a, b, c);
        let d = q.distance(p);
        if best.is_none_or(|h| d < h.distance) {
            best = Some(ClosestHit { point: q, triangle: i, barycentric: bary, distance: d });
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    #[test]
    fn triangle_regions() {
        let (a, b, c) = (DVec3::ZERO, DVec3::X, DVec3::Y);
        let cases = [
            (DVec3::new(-1.0, -1.0, 2.0), a),
            (DVec3::new(2.0, -0.5, 0.0), b),
            (DVec3::new(-0.1, 3.0, -1.0), c),
            (DVec3::new(0.5, -2.0, 0.3), DVec3::new(0.5, 0.0, 0.0)),
            (DVec3::new(-2.0, 0.25, 0.0), DVec3::new(0.0, 0.25, 0.0)),
            (DVec3::new(1.0, 1.0, 5.0), DVec3::new(0.5, 0.5, 0.0)),
            (DVec3::new(0.2, 0.3, -4.0), DVec3::new(0.2, 0.3, 0.0)),
        ];
        for (p, want) in cases {
            let (q, w) = closest_point_on_triangle(p, a, b, c);
            assert!((q - want).length() < 1e-14, "{p} -> {q}, want {want}");
            assert!((w[0] * a + w[1] * b + w[2] * c - q).length() < 1e-14);
        }
        // Degenerate triangle: a segment.
        let (q, _) = closest_point_on_triangle(DVec3::new(0.5, 1.0, 0.0), a, b, 2.0 * b);
        assert!((q - DVec3::new(0.5, 0.0, 0.0)).length() < 1e-14);
    }

    #[test]
    fn closest_point_on_triangle_is_a_minimum() {
        let mut rng = Rng(0x1234_5678_9abc_def1);
        for _ in 0..500 {
            let (a, b, c, p) = (rng.vec(1.0), rng.vec(1.0), rng.vec(1.0), rng.vec(1.0) * 2.0);
            let (q, _) = closest_point_on_triangle(p, a, b, c);
            let d = q.distance(p);
            for _ in 0..40 {
                let (mut u, mut v) = (rng.uniform(), rng.uniform());
                if u + v > 1.0 {
                    (u, v) = (1.0 - u, 1.0 - v);
                }
                let x = a + u * (b - a) + v * (c - a);
                assert!(x.distance(p) >= d - 1e-12);
            }
        }
    }

    #[test]
    fn bvh_matches_brute_force() {
        let mut rng = Rng(42);
        // A bumpy grid plus random triangles.
        let n = 24;
        let mut positions = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                let (x, y) = (i as f64 / n as f64, j as f64 / n as f64);
                positions.push(DVec3::new(x, y, 0.2 * (7.0 * x).sin() * (5.0 * y).cos()));
            }
        }
        let mut triangles = Vec::new();
        let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        for j in 0..n {
            for i in 0..n {
                triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        for _ in 0..50 {
            let k = positions.len() as u32;
            positions.extend([rng.vec(1.0) * 0.3, rng.vec(1.0) * 0.3, rng.vec(1.0) * 0.3]);
            triangles.push([k, k + 1, k + 2]);
        }
        let mesh = TriMesh::new(positions, triangles);
        let bvh = TriangleBvh::new(&mesh);
        assert_eq!(bvh.len(), mesh.face_count());
        for _ in 0..400 {
            let p = rng.vec(1.0) * 1.5 + DVec3::new(0.5, 0.5, 0.0);
            let h = bvh.closest_point(p).unwrap();
            let g = closest_point_brute_force(&mesh, p).unwrap();
            assert!((h.distance - g.distance).abs() < 1e-14, "{} vs {}", h.distance, g.distance);
            let [a, b, c] = mesh.face_points(h.triangle);
            let (q, _) = closest_point_on_triangle(p, a, b, c);
            assert!(q.distance(h.point) < 1e-14);
            // Started from any triangle: the same distance.
            let hint = ((rng.uniform() * mesh.face_count() as f64) as usize).min(mesh.face_count() - 1);
            let s = bvh.closest_point_from(p, hint).unwrap();
            assert!((s.distance - g.distance).abs() < 1e-14, "from {hint}: {} vs {}", s.distance, g.distance);
            // Bounded queries.
            assert!(bvh.closest_point_within(p, g.distance * 0.5).is_none() || g.distance == 0.0);
            assert!(bvh.closest_point_within(p, g.distance * 1.01 + 1e-12).is_some());
        }
        assert!(TriangleBvh::new(&TriMesh::default()).closest_point(DVec3::ZERO).is_none());
        assert!(bvh.closest_point(DVec3::NAN).is_none());
    }
}
