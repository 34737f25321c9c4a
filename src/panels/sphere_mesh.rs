//! A mesh with spherical faces: every face (3 or 4 corners) carries a normalized generalized
//! face sphere through its corners. Panels, support structures and exports are derived from it.

use std::cell::OnceCell;
use std::collections::{BTreeSet, HashMap};

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::geometry::mesh::PolyMesh;

use crate::geometry::mesh::topology::Topology;
use crate::geometry::sphere::Sphere;

/// How the arc of a boundary edge (one face only) is cut from its face sphere: by the plane
/// through the edge's two vertices that also contains `through` (a point, e.g. m) or is parallel
/// to `parallel` (a direction, e.g. the axis a). Interior edges use the intersection circle of
/// the two adjacent face spheres.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum BoundaryArcRule {
    Through(DVec3),
    Parallel(DVec3),
}

/// A mesh with spherical faces of 3 or 4 corners.
#[derive(Clone, Debug)]
pub struct SphereMesh {
    pub mesh: PolyMesh,
    /// One normalized sphere per face, oriented like the face (its outward side follows the
    /// reference normal).
    pub face_spheres: Vec<Sphere>,
    pub boundary_arcs: BoundaryArcRule,
    /// Per boundary edge (lo, hi): the normal of the plane that cuts its arc, instead of
    /// `boundary_arcs` (the SQ method cuts along its support planes, Sec. 5.2; the ST method
    /// along the reference boundary).
    pub boundary_planes: HashMap<[u32; 2], DVec3>,
    /// Interior edges (lo, hi) that variant (a) cuts by their bisecting plane, as variant (b)
    /// does, because their intersection circle would make a panel's arcs cross or sweep too wide
    /// ([`super::bisect_unbuildable_arcs`]).
    pub bisected_edges: BTreeSet<[u32; 2]>,
    /// Connectivity of `mesh`, computed on first use ([`Self::topology`]).
    topology: OnceCell<Topology>,
}

impl SphereMesh {
    pub fn new(mesh: impl Into<PolyMesh>, face_spheres: Vec<Sphere>, boundary_arcs: BoundaryArcRule) -> Self {
        Self {
            mesh: mesh.into(),
            face_spheres,
            boundary_arcs,
            boundary_planes: HashMap::new(),
            bisected_edges: BTreeSet::new(),
            topology: OnceCell::new(),
        }
    }

    /// The same mesh with its boundary edges cut by the planes with these normals.
    pub(crate) fn with_boundary_planes(self, boundary_planes: HashMap<[u32; 2], DVec3>) -> Self {
        Self { boundary_planes, ..self }
    }

    /// The connectivity of the mesh (edges and their faces), computed once. The mesh's faces
    /// must not change afterwards.
    pub fn topology(&self) -> &Topology {
        self.topology.get_or_init(|| Topology::new(&self.mesh))
    }

    /// Kink angles (degrees) along the interior edges, in edge order: the angle between the two
    /// panels' normals on their common circle ([`Sphere::kink_angle`]).
    pub fn kink_angles_deg(&self) -> Vec<f64> {
        self.topology()
            .interior_edges()
            .map(|(_, f, g)| self.face_spheres[f as usize].kink_angle(&self.face_spheres[g as usize]).to_degrees())
            .collect()
    }

    /// max over faces and corners of the distance from the corner to its face sphere.
    pub fn max_vertex_sphere_residual(&self) -> f64 {
        let mut res = 0.0f64;
        for (f, face) in self.mesh.faces.iter().enumerate() {
            for &v in face.corners() {
                res = res.max(self.face_spheres[f].distance(self.mesh.positions[v as usize]));
            }
        }
        res
    }
}

impl PartialEq for SphereMesh {
    fn eq(&self, other: &Self) -> bool {
        self.mesh == other.mesh
            && self.face_spheres == other.face_spheres
            && self.boundary_arcs == other.boundary_arcs
            && self.boundary_planes == other.boundary_planes
            && self.bisected_edges == other.bisected_edges
    }
}
