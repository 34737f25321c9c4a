//! The plain triangle mesh: geometry (positions) apart from connectivity ([`topology`]).

pub mod topology;
pub mod weld;

use glam::DVec3;

pub use topology::{MeshStats, Topology};

/// A triangle mesh with f64 positions. Connectivity is derived on demand by [`Topology`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriMesh {
    pub positions: Vec<DVec3>,
    pub triangles: Vec<[u32; 3]>,
}

impl TriMesh {
    pub fn new(positions: Vec<DVec3>, triangles: Vec<[u32; 3]>) -> Self {
        Self { positions, triangles }
    }

    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    pub fn face_count(&self) -> usize {
        self.triangles.len()
    }

    /// Axis-aligned bounding box (min, max). Empty meshes give (0, 0).
    pub fn bbox(&self) -> (DVec3, DVec3) {
        if self.positions.is_empty() {
            return (DVec3::ZERO, DVec3::ZERO);
        }
        self.positions
            .iter()
            .fold((DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)), |(lo, hi), p| {
                (lo.min(*p), hi.max(*p))
            })
    }

    /// Bounding-box diagonal: the unit of every relative tolerance.
    pub fn bbox_diagonal(&self) -> f64 {
        let (lo, hi) = self.bbox();
        (hi - lo).length()
    }

    /// Bounding-box diagonal of the vertices faces refer to (stray and out-of-range indices
    /// do not count); 0 without faces.
    pub fn referenced_diagonal(&self) -> f64 {
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for &v in self.triangles.iter().flatten() {
            if let Some(p) = self.positions.get(v as usize) {
                lo = lo.min(*p);
                hi = hi.max(*p);
            }
        }
        if lo.x > hi.x { 0.0 } else { (hi - lo).length() }
    }

    /// Corner positions of face `f`.
    pub fn face_points(&self, f: usize) -> [DVec3; 3] {
        let t = self.triangles[f];
        [self.positions[t[0] as usize], self.positions[t[1] as usize], self.positions[t[2] as usize]]
    }

    /// Area vector (normal times area) of face `f`, following its orientation.
    pub fn face_area_vector(&self, f: usize) -> DVec3 {
        let [a, b, c] = self.face_points(f);
        0.5 * (b - a).cross(c - a)
    }

    /// Area-weighted unit vertex normals, following the face orientation. Isolated vertices get +z.
    pub fn vertex_normals(&self) -> Vec<DVec3> {
        let mut n = vec![DVec3::ZERO; self.positions.len()];
        for (f, t) in self.triangles.iter().enumerate() {
            let a = self.face_area_vector(f);
            for &v in t {
                n[v as usize] += a;
            }
        }
        n.into_iter().map(|v| v.try_normalize().unwrap_or(DVec3::Z)).collect()
    }
}
