//! Meshes: geometry (positions) apart from connectivity ([`topology`]).
//!
//! [`TriMesh`] is the triangle mesh the reference-surface algorithms work on (jet fit,
//! remeshing, closest points). [`PolyMesh`] has faces of 3 or 4 corners ([`Face`]): the meshes
//! with spherical faces (ST triangles, SQ quads) and imported quads. [`Faces`] is what both
//! share, so connectivity is built once for either.

pub mod halfedge;
pub mod topology;
pub mod weld;

use glam::DVec3;

/// A triangle mesh with f64 positions. Connectivity is derived by [`topology::Topology`].
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
        bbox(&self.positions)
    }

    /// Bounding-box diagonal: the unit of every relative tolerance.
    pub fn bbox_diagonal(&self) -> f64 {
        bbox_diagonal(&self.positions)
    }

    /// Bounding-box diagonal of the vertices faces refer to (stray and out-of-range indices
    /// do not count); 0 without faces.
    pub(crate) fn referenced_diagonal(&self) -> f64 {
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for &v in self.triangles.iter().flatten() {
            if let Some(p) = self.positions.get(v as usize) {
                lo = lo.min(*p);
                hi = hi.max(*p);
            }
        }
        if lo.x > hi.x {
            0.0
        } else {
            (hi - lo).length()
        }
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

/// Axis-aligned bounding box (min, max) of points; (0, 0) for none.
pub fn bbox(points: &[DVec3]) -> (DVec3, DVec3) {
    if points.is_empty() {
        return (DVec3::ZERO, DVec3::ZERO);
    }
    points.iter().fold((DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)), |(lo, hi), p| (lo.min(*p), hi.max(*p)))
}

/// The diagonal of [`bbox`]: the unit of every relative tolerance.
pub fn bbox_diagonal(points: &[DVec3]) -> f64 {
    let (lo, hi) = bbox(points);
    (hi - lo).length()
}

/// The faces of a mesh as corner lists: what connectivity ([`topology::Topology`]) is built from.
pub trait Faces {
    fn vertex_count(&self) -> usize;
    fn face_count(&self) -> usize;
    /// The corners of face `f`, in order.
    fn corners(&self, f: usize) -> &[u32];
}

impl Faces for TriMesh {
    fn vertex_count(&self) -> usize {
        self.positions.len()
    }
    fn face_count(&self) -> usize {
        self.triangles.len()
    }
    fn corners(&self, f: usize) -> &[u32] {
        &self.triangles[f]
    }
}

/// A face of 3 or 4 corners, counter-clockwise about its outward normal.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Face {
    corners: [u32; 4],
    len: u8,
}

impl Face {
    pub fn triangle(t: [u32; 3]) -> Self {
        Self { corners: [t[0], t[1], t[2], u32::MAX], len: 3 }
    }

    pub fn quad(q: [u32; 4]) -> Self {
        Self { corners: q, len: 4 }
    }

    pub fn corners(&self) -> &[u32] {
        &self.corners[..self.len as usize]
    }

    /// 3 or 4.
    pub fn len(&self) -> usize {
        self.len as usize
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Side k: from corner k to corner k + 1 (mod len).
    pub fn side(&self, k: usize) -> [u32; 2] {
        [self.corners[k], self.corners[(k + 1) % self.len()]]
    }

    /// The triangles of the face: itself, or a quad split along the diagonal from corner 0
    /// (corners 0 1 2 and 0 2 3).
    pub fn triangles(&self) -> impl Iterator<Item = [u32; 3]> + '_ {
        let c = &self.corners;
        (1..self.len() - 1).map(move |k| [c[0], c[k], c[k + 1]])
    }
}

impl From<[u32; 3]> for Face {
    fn from(t: [u32; 3]) -> Self {
        Face::triangle(t)
    }
}

impl From<[u32; 4]> for Face {
    fn from(q: [u32; 4]) -> Self {
        Face::quad(q)
    }
}

/// A mesh with faces of 3 or 4 corners and f64 positions.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PolyMesh {
    pub positions: Vec<DVec3>,
    pub faces: Vec<Face>,
}

impl PolyMesh {
    pub fn new(positions: Vec<DVec3>, faces: Vec<Face>) -> Self {
        Self { positions, faces }
    }

    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    pub fn face_count(&self) -> usize {
        self.faces.len()
    }

    pub fn bbox_diagonal(&self) -> f64 {
        bbox_diagonal(&self.positions)
    }

    /// Corner positions of face `f`, in order.
    pub fn face_points(&self, f: usize) -> Vec<DVec3> {
        self.faces[f].corners().iter().map(|&v| self.positions[v as usize]).collect()
    }

    /// Area vector of face `f` (normal times area; for a quad the sum over its two triangles,
    /// which does not depend on the diagonal).
    pub fn face_area_vector(&self, f: usize) -> DVec3 {
        let c = self.faces[f].corners();
        let p = |k: usize| self.positions[c[k] as usize];
        let mut area = 0.5 * (p(1) - p(0)).cross(p(2) - p(0));
        if c.len() == 4 {
            area += 0.5 * (p(2) - p(0)).cross(p(3) - p(0));
        }
        area
    }

    /// The triangles of every face ([`Face::triangles`]), face by face.
    pub fn triangulated(&self) -> TriMesh {
        TriMesh::new(self.positions.clone(), self.faces.iter().flat_map(|f| f.triangles()).collect())
    }
}

impl From<TriMesh> for PolyMesh {
    fn from(m: TriMesh) -> Self {
        Self { positions: m.positions, faces: m.triangles.into_iter().map(Face::triangle).collect() }
    }
}

impl From<&TriMesh> for PolyMesh {
    fn from(m: &TriMesh) -> Self {
        Self { positions: m.positions.clone(), faces: m.triangles.iter().map(|&t| Face::triangle(t)).collect() }
    }
}

impl Faces for PolyMesh {
    fn vertex_count(&self) -> usize {
        self.positions.len()
    }
    fn face_count(&self) -> usize {
        self.faces.len()
    }
    fn corners(&self, f: usize) -> &[u32] {
        self.faces[f].corners()
    }
}
