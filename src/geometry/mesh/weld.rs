//! Vertex welding and face clean-up: merge coincident vertices, drop degenerate and duplicate
//! faces, remove unreferenced vertices.
//!
//! Merging is greedy and order-stable: vertices are visited in input order; each one either
//! joins an earlier *representative* within `tolerance` (Euclidean distance; one in the same
//! grid cell if any, else the earliest) or becomes a representative itself, keeping its own
//! position. Only representatives attract, so merges never chain beyond the tolerance. Representatives are found with a uniform
//! grid hash, so the whole pass is O(n) expected plus an O(f log f) sort for duplicate faces.

use super::TriMesh;
use glam::DVec3;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// What [`weld`] changed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct WeldReport {
    /// Input vertices merged into an earlier vertex within the tolerance.
    pub merged_vertices: usize,
    /// Faces dropped: out-of-range or repeated indices (after merging), zero area, duplicates.
    pub dropped_faces: usize,
    /// Vertices (after merging) no remaining face refers to.
    pub removed_unreferenced: usize,
}

/// Relative threshold for "zero area": a face is dropped when twice its area is below
/// `AREA_REL * longest_edge^2` (numerically collinear) or its area is below
/// `(AREA_REL * bbox_diagonal)^2`.
const AREA_REL: f64 = 1e-12;

/// Multiply-rotate hasher (FxHash style) for grid cells; SipHash is needlessly slow here.
#[derive(Default)]
struct CellHasher(u64);

impl Hasher for CellHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }
    fn write_u64(&mut self, v: u64) {
        self.0 = (self.0.rotate_left(5) ^ v).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
    fn write_i64(&mut self, v: i64) {
        self.write_u64(v as u64);
    }
}

type Cell = (i64, i64, i64);
type CellMap = HashMap<Cell, u32, BuildHasherDefault<CellHasher>>;

const NONE: u32 = u32::MAX;

/// Merges vertices closer than `tolerance` (absolute), then drops faces with repeated indices,
/// zero-area faces and duplicate faces (same vertex set, either orientation; the first is kept),
/// then removes unreferenced vertices. Surviving vertices and faces keep their relative order.
///
/// `tolerance <= 0` (or non-finite) merges only bit-identical positions (`-0.0 == 0.0`).
/// Faces referring to vertices out of range are dropped, never a panic.
pub fn weld(mesh: &TriMesh, tolerance: f64) -> (TriMesh, WeldReport) {
    let (welded, report, _) = weld_with_face_map(mesh, tolerance);
    (welded, report)
}

/// [`weld`], and for every input face the index of its output face (`u32::MAX` when dropped).
pub(crate) fn weld_with_face_map(mesh: &TriMesh, tolerance: f64) -> (TriMesh, WeldReport, Vec<u32>) {
    let n = mesh.positions.len();
    let mut report = WeldReport::default();

    // 1. Representatives: rep[i] = index (into `reps`) of the representative of vertex i.
    let remap = merge_vertices(&mesh.positions, tolerance);
    let mut reps: Vec<DVec3> = Vec::new();
    let mut rep_of = vec![NONE; n];
    for (i, &r) in remap.iter().enumerate() {
        let r = r as usize;
        if r == i {
            rep_of[i] = reps.len() as u32;
            reps.push(mesh.positions[i]);
        } else {
            rep_of[i] = rep_of[r];
            report.merged_vertices += 1;
        }
    }

    // 2. Faces: remap, drop out-of-range, repeated and zero-area faces.
    let diag = mesh.referenced_diagonal();
    let abs_area = (AREA_REL * diag) * (AREA_REL * diag);
    let mut faces: Vec<[u32; 3]> = Vec::with_capacity(mesh.triangles.len());
    // The input face of each kept face.
    let mut origin: Vec<u32> = Vec::with_capacity(mesh.triangles.len());
    for (input, t) in mesh.triangles.iter().enumerate() {
        if t.iter().any(|&v| v as usize >= n) {
            report.dropped_faces += 1;
            continue;
        }
        let f = [rep_of[t[0] as usize], rep_of[t[1] as usize], rep_of[t[2] as usize]];
        if f[0] == f[1] || f[1] == f[2] || f[0] == f[2] {
            report.dropped_faces += 1;
            continue;
        }
        let [a, b, c] = [reps[f[0] as usize], reps[f[1] as usize], reps[f[2] as usize]];
        let twice_area = (b - a).cross(c - a).length();
        let longest2 = (b - a).length_squared().max((c - b).length_squared()).max((a - c).length_squared());
        // Written so that NaN counts as degenerate.
        let has_area = twice_area > AREA_REL * longest2 && 0.5 * twice_area >= abs_area;
        if !has_area {
            report.dropped_faces += 1;
            continue;
        }
        faces.push(f);
        origin.push(input as u32);
    }

    // 3. Duplicate faces: sort by vertex set, keep the earliest of each group.
    let mut keys: Vec<([u32; 3], u32)> = faces
        .iter()
        .enumerate()
        .map(|(i, f)| {
            let mut k = *f;
            k.sort_unstable();
            (k, i as u32)
        })
        .collect();
    keys.sort_unstable();
    let mut keep = vec![true; faces.len()];
    for w in keys.windows(2) {
        if w[0].0 == w[1].0 {
            keep[w[1].1 as usize] = false;
        }
    }
    drop(keys);
    let before = faces.len();
    let mut k = keep.iter();
    faces.retain(|_| *k.next().unwrap_or(&true));
    let mut k = keep.iter();
    origin.retain(|_| *k.next().unwrap_or(&true));
    report.dropped_faces += before - faces.len();
    let mut face_map = vec![NONE; mesh.triangles.len()];
    for (out, &input) in origin.iter().enumerate() {
        face_map[input as usize] = out as u32;
    }

    // 4. Compact: keep referenced representatives in their original order.
    let mut new_index = vec![NONE; reps.len()];
    for f in &faces {
        for &v in f {
            new_index[v as usize] = 0;
        }
    }
    let mut positions = Vec::with_capacity(reps.len());
    for (r, slot) in new_index.iter_mut().enumerate() {
        if *slot != NONE {
            *slot = positions.len() as u32;
            positions.push(reps[r]);
        }
    }
    report.removed_unreferenced = reps.len() - positions.len();
    for f in &mut faces {
        for v in f.iter_mut() {
            *v = new_index[*v as usize];
        }
    }
    (TriMesh::new(positions, faces), report, face_map)
}

/// For every vertex, the index of its representative (itself if it is one).
fn merge_vertices(positions: &[DVec3], tolerance: f64) -> Vec<u32> {
    let n = positions.len();
    let mut remap: Vec<u32> = Vec::with_capacity(n);
    // Chained representatives per cell: head in the map, links in `next`.
    let mut next: Vec<u32> = vec![NONE; n];
    let mut cells: CellMap = CellMap::default();
    cells.reserve(n.min(1 << 16));

    let usable = tolerance > 0.0 && tolerance.is_finite();
    if !usable {
        // Exact merging: key on the bit patterns (normalising -0.0).
        for (i, p) in positions.iter().enumerate() {
            let key = ((p.x + 0.0).to_bits() as i64, (p.y + 0.0).to_bits() as i64, (p.z + 0.0).to_bits() as i64);
            let r = *cells.entry(key).or_insert(i as u32);
            remap.push(r);
        }
        return remap;
    }

    // Cells 16 times the tolerance: along each axis the query ball spills into a neighbour cell
    // with probability 1/8, so most queries touch only their own cell (never more than eight).
    let cell = 16.0 * tolerance;
    let inv = 1.0 / cell;
    let tol2 = tolerance * tolerance;
    let coord = |x: f64| -> i64 { (x * inv).floor() as i64 };
    // Smallest-index representative within the tolerance in one cell, or NONE.
    let scan = |cells: &CellMap, next: &[u32], key: Cell, p: DVec3| -> u32 {
        let mut found = NONE;
        let mut r = cells.get(&key).copied().unwrap_or(NONE);
        while r != NONE {
            if r < found && positions[r as usize].distance_squared(p) <= tol2 {
                found = r;
            }
            r = next[r as usize];
        }
        found
    };
    for (i, p) in positions.iter().enumerate() {
        let own = (coord(p.x), coord(p.y), coord(p.z));
        // A representative in the vertex's own cell wins; otherwise the smallest-index one in
        // the neighbouring cells the query ball reaches.
        let mut found = scan(&cells, &next, own, *p);
        if found == NONE {
            let lo = (coord(p.x - tolerance), coord(p.y - tolerance), coord(p.z - tolerance));
            let hi = (coord(p.x + tolerance), coord(p.y + tolerance), coord(p.z + tolerance));
            // Saturated coordinates: never more than two cells per axis.
            for cx in lo.0..=hi.0.min(lo.0.saturating_add(1)) {
                for cy in lo.1..=hi.1.min(lo.1.saturating_add(1)) {
                    for cz in lo.2..=hi.2.min(lo.2.saturating_add(1)) {
                        if (cx, cy, cz) != own {
                            found = found.min(scan(&cells, &next, (cx, cy, cz), *p));
                        }
                    }
                }
            }
        }
        if found != NONE {
            remap.push(found);
        } else {
            let head = cells.entry(own).or_insert(NONE);
            next[i] = *head;
            *head = i as u32;
            remap.push(i as u32);
        }
    }
    remap
}
