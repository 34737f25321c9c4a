//! A panel: one face of a sphere mesh cut from its sphere by its arcs, and its tessellation.

use glam::DVec3;

use super::arc::Arc;
use super::tessellate::triangle_chord_error;
use crate::geometry::sphere::Sphere;

/// A spherical (or planar) panel with 3 or 4 circular sides.
#[derive(Clone, Debug, PartialEq)]
pub struct Panel {
    /// Face index in the [`super::sphere_mesh::SphereMesh`] (= panel id).
    pub face: usize,
    /// The face sphere (normalized), oriented like the face.
    pub sphere: Sphere,
    /// Mesh vertex ids of the corners, in face order (3 or 4).
    pub corners: Vec<u32>,
    /// `arcs[k]` runs from corner k to corner k + 1 (mod the corner count).
    pub arcs: Vec<Arc>,
    /// Tessellation vertices; the first ones are the corners.
    pub positions: Vec<DVec3>,
    /// Tessellation triangles (indices into `positions`), oriented like the face.
    pub triangles: Vec<[u32; 3]>,
    /// Sum of the tessellation triangle areas.
    pub area: f64,
    /// `arc_vertices[k]`: indices into `positions` of the points of arc k, from corner k to corner
    /// k + 1 inclusive. In variant (a) the neighbour across that edge has the same points in
    /// reverse; in variant (b) only the two end points (the mesh vertices) are shared.
    pub arc_vertices: Vec<Vec<u32>>,
}

impl Panel {
    /// Exact chord error of the tessellation: max over its triangles of the largest distance
    /// between the triangle and the panel's sphere (see [`triangle_chord_error`]).
    pub fn chord_error(&self) -> f64 {
        let s = self.sphere;
        self.triangles
            .iter()
            .map(|t| triangle_chord_error(&s, self.positions[t[0] as usize], self.positions[t[1] as usize], self.positions[t[2] as usize]))
            .fold(0.0, f64::max)
    }

    /// Tessellation triangles facing against the panel's outward normal −∇ψ. Non-zero only when
    /// the panel itself is invalid: two of its arcs cross near a corner (the curved corner angle
    /// is negative), which happens for extreme kinks between neighbouring spheres.
    pub fn folded_triangles(&self) -> usize {
        self.triangles
            .iter()
            .filter(|t| {
                let [a, b, c] = t.map(|i| self.positions[i as usize]);
                (b - a).cross(c - a).dot(self.normal_at((a + b + c) / 3.0)) < 0.0
            })
            .count()
    }

    /// True when the panel's sphere is a plane (a = 0).
    pub fn is_planar(&self) -> bool {
        self.sphere.a == 0.0
    }

    /// Outward unit normal of the panel surface at `x` (on or near the sphere): −∇ψ/|∇ψ|, the
    /// reference-normal side.
    pub fn normal_at(&self, x: DVec3) -> DVec3 {
        self.sphere.unit_normal_at(x)
    }

    /// The points of arc k, from corner k to corner k + 1.
    pub fn arc_points(&self, k: usize) -> Vec<DVec3> {
        self.arc_vertices[k].iter().map(|&i| self.positions[i as usize]).collect()
    }
}
