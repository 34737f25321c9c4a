//! Connectivity derived from a mesh's faces (3 or 4 corners, [`Faces`]): one-rings, vertex faces,
//! edges, and the one edge → faces table.

use super::Faces;
use serde::{Deserialize, Serialize};

/// Counts reported by the info panel and `spherical-faces info`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct MeshStats {
    pub vertices: usize,
    pub faces: usize,
    pub boundary_loops: usize,
    pub non_manifold_edges: usize,
    pub boundary_vertices: usize,
}

/// Compressed adjacency (CSR) of a mesh. Built once, read many times.
#[derive(Clone, Debug)]
pub struct Topology {
    neighbor_offsets: Vec<u32>,
    neighbors: Vec<u32>,
    face_offsets: Vec<u32>,
    faces: Vec<u32>,
    /// Undirected edges (lo, hi), sorted.
    edges: Vec<[u32; 2]>,
    /// Number of faces incident to each edge.
    edge_face_count: Vec<u32>,
    /// Faces of edge e: `edge_faces[edge_face_offsets[e]..edge_face_offsets[e + 1]]`, ascending,
    /// with the side of the face the edge is (side k runs from corner k to corner k + 1).
    edge_face_offsets: Vec<u32>,
    edge_faces: Vec<(u32, u8)>,
    boundary_vertex: Vec<bool>,
}

impl Topology {
    pub fn new<M: Faces + ?Sized>(mesh: &M) -> Self {
        let n = mesh.vertex_count();
        let nf = mesh.face_count();
        // Half-edges bucketed by their smaller vertex (a counting sort), then by the larger one
        // inside each small bucket: the edges come out sorted, each with its faces in face order,
        // without a global sort, a search or a hash map.
        let half_edges = |f: usize| {
            let c = mesh.corners(f);
            (0..c.len()).map(move |k| {
                let (a, b) = (c[k], c[(k + 1) % c.len()]);
                (a.min(b), a.max(b), k as u8)
            })
        };
        let mut lo_count = vec![0u32; n];
        for f in 0..nf {
            for (a, _, _) in half_edges(f) {
                lo_count[a as usize] += 1;
            }
        }
        let lo_offsets = prefix_sum(&lo_count);
        let mut fill = lo_offsets.clone();
        // (larger vertex, face, side)
        let mut bucketed = vec![(0u32, 0u32, 0u8); *lo_offsets.last().unwrap() as usize];
        for f in 0..nf {
            for (a, b, k) in half_edges(f) {
                bucketed[fill[a as usize] as usize] = (b, f as u32, k);
                fill[a as usize] += 1;
            }
        }
        let mut edges: Vec<[u32; 2]> = Vec::with_capacity(bucketed.len() / 2 + 1);
        let mut edge_face_count: Vec<u32> = Vec::with_capacity(bucketed.len() / 2 + 1);
        let mut edge_faces = Vec::with_capacity(bucketed.len());
        for a in 0..n {
            let bucket = &mut bucketed[lo_offsets[a] as usize..lo_offsets[a + 1] as usize];
            bucket.sort_by_key(|h| h.0); // stable: faces stay ascending
            for &(b, f, k) in bucket.iter() {
                let e = [a as u32, b];
                if edges.last() == Some(&e) {
                    *edge_face_count.last_mut().unwrap() += 1;
                } else {
                    edges.push(e);
                    edge_face_count.push(1);
                }
                edge_faces.push((f, k));
            }
        }
        let mut boundary_vertex = vec![false; n];
        let mut deg = vec![0u32; n];
        for (e, c) in edges.iter().zip(&edge_face_count) {
            deg[e[0] as usize] += 1;
            deg[e[1] as usize] += 1;
            if *c == 1 {
                boundary_vertex[e[0] as usize] = true;
                boundary_vertex[e[1] as usize] = true;
            }
        }
        let neighbor_offsets = prefix_sum(&deg);
        let mut fill = neighbor_offsets.clone();
        let mut neighbors = vec![0u32; *neighbor_offsets.last().unwrap() as usize];
        for e in &edges {
            for (a, b) in [(e[0], e[1]), (e[1], e[0])] {
                neighbors[fill[a as usize] as usize] = b;
                fill[a as usize] += 1;
            }
        }
        let mut fdeg = vec![0u32; n];
        for f in 0..mesh.face_count() {
            for &v in mesh.corners(f) {
                fdeg[v as usize] += 1;
            }
        }
        let face_offsets = prefix_sum(&fdeg);
        let mut fill = face_offsets.clone();
        let mut faces = vec![0u32; *face_offsets.last().unwrap() as usize];
        for f in 0..mesh.face_count() {
            for &v in mesh.corners(f) {
                faces[fill[v as usize] as usize] = f as u32;
                fill[v as usize] += 1;
            }
        }
        let edge_face_offsets = prefix_sum(&edge_face_count);
        Self { neighbor_offsets, neighbors, face_offsets, faces, edges, edge_face_count, edge_face_offsets, edge_faces, boundary_vertex }
    }

    pub fn vertex_count(&self) -> usize {
        self.boundary_vertex.len()
    }

    /// Vertices sharing an edge with `v` (its one-ring), in no particular order.
    pub fn vertex_neighbors(&self, v: usize) -> &[u32] {
        &self.neighbors[self.neighbor_offsets[v] as usize..self.neighbor_offsets[v + 1] as usize]
    }

    /// Faces incident to `v`.
    pub fn vertex_faces(&self, v: usize) -> &[u32] {
        &self.faces[self.face_offsets[v] as usize..self.face_offsets[v + 1] as usize]
    }

    pub fn is_boundary_vertex(&self, v: usize) -> bool {
        self.boundary_vertex[v]
    }

    /// Undirected edges (lo, hi).
    pub fn edges(&self) -> &[[u32; 2]] {
        &self.edges
    }

    /// Number of faces on each edge of [`Self::edges`]: 1 boundary, 2 interior, >2 non-manifold.
    pub fn edge_face_counts(&self) -> &[u32] {
        &self.edge_face_count
    }

    /// The faces of edge `e` (index into [`Self::edges`]), ascending, each with the side of the
    /// face the edge is: side k runs from corner k to corner k + 1.
    pub fn edge_faces(&self, e: usize) -> &[(u32, u8)] {
        &self.edge_faces[self.edge_face_offsets[e] as usize..self.edge_face_offsets[e + 1] as usize]
    }

    /// The index of the edge between vertices `a` and `b`, if there is one.
    pub fn edge_index(&self, a: u32, b: u32) -> Option<usize> {
        self.edges.binary_search(&[a.min(b), a.max(b)]).ok()
    }

    /// Interior edges (exactly two faces): (edge index, lower face, higher face), in edge order.
    pub fn interior_edges(&self) -> impl Iterator<Item = (usize, u32, u32)> + '_ {
        (0..self.edges.len()).filter_map(|e| match self.edge_faces(e) {
            [(f, _), (g, _)] => Some((e, *f, *g)),
            _ => None,
        })
    }

    /// Vertex, face, boundary-loop and non-manifold-edge counts.
    pub fn stats<M: Faces + ?Sized>(&self, mesh: &M) -> MeshStats {
        // Boundary loops: connected components of the graph of boundary edges.
        let mut parent: Vec<u32> = (0..self.vertex_count() as u32).collect();
        fn find(p: &mut [u32], mut x: u32) -> u32 {
            while p[x as usize] != x {
                p[x as usize] = p[p[x as usize] as usize];
                x = p[x as usize];
            }
            x
        }
        let mut non_manifold_edges = 0;
        for (e, &c) in self.edges.iter().zip(&self.edge_face_count) {
            if c > 2 {
                non_manifold_edges += 1;
            }
            if c == 1 {
                let (a, b) = (find(&mut parent, e[0]), find(&mut parent, e[1]));
                if a != b {
                    parent[a as usize] = b;
                }
            }
        }
        let mut boundary_loops = 0;
        let mut boundary_vertices = 0;
        for v in 0..self.vertex_count() {
            if self.boundary_vertex[v] {
                boundary_vertices += 1;
                if find(&mut parent, v as u32) == v as u32 {
                    boundary_loops += 1;
                }
            }
        }
        MeshStats { vertices: mesh.vertex_count(), faces: mesh.face_count(), boundary_loops, non_manifold_edges, boundary_vertices }
    }
}

fn prefix_sum(counts: &[u32]) -> Vec<u32> {
    let mut out = Vec::with_capacity(counts.len() + 1);
    let mut s = 0;
    out.push(0);
    for &c in counts {
        s += c;
        out.push(s);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;
    use std::collections::BTreeMap;

    /// Faces of 3 or 4 random corners over few vertices: shared, non-manifold and repeated
    /// edges, isolated vertices.
    struct Soup {
        n: usize,
        faces: Vec<Vec<u32>>,
    }

    impl Faces for Soup {
        fn vertex_count(&self) -> usize {
            self.n
        }
        fn face_count(&self) -> usize {
            self.faces.len()
        }
        fn corners(&self, f: usize) -> &[u32] {
            &self.faces[f]
        }
    }

    #[test]
    fn edges_and_their_faces_match_a_map() {
        let mut rng = Rng(7);
        for round in 0..50 {
            let n = 4 + round % 9;
            let pick = |rng: &mut Rng| ((rng.uniform() * n as f64) as u32).min(n as u32 - 1);
            let faces: Vec<Vec<u32>> =
                (0..3 + round).map(|_| (0..if rng.uniform() < 0.5 { 3 } else { 4 }).map(|_| pick(&mut rng)).collect()).collect();
            let soup = Soup { n, faces };
            let topo = Topology::new(&soup);
            let mut map: BTreeMap<[u32; 2], Vec<(u32, u8)>> = BTreeMap::new();
            for (f, c) in soup.faces.iter().enumerate() {
                for k in 0..c.len() {
                    let (a, b) = (c[k], c[(k + 1) % c.len()]);
                    map.entry([a.min(b), a.max(b)]).or_default().push((f as u32, k as u8));
                }
            }
            let edges: Vec<[u32; 2]> = map.keys().copied().collect();
            assert_eq!(topo.edges(), edges.as_slice());
            for (e, faces) in map.values().enumerate() {
                assert_eq!(topo.edge_faces(e), faces.as_slice());
                assert_eq!(topo.edge_face_counts()[e] as usize, faces.len());
            }
        }
    }
}
