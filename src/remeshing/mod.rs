//! Meshes with adapted face size (Sec. 3): influence zones and the sizing field g
//! ([`influence_zones`], Fig. 13), and pliant remeshing to it ([`pliant`]) on a halfedge mesh.
//!
//! Typical use:
//! ```no_run
//! # use spherical_faces::geometry::mesh::{Topology, TriMesh};
//! # use spherical_faces::congruence::central_spheres::{jet_fit, JetParams};
//! # use spherical_faces::remeshing::{SizingField, RemeshParams, pliant_remesh, DEFAULT_EPSILON};
//! # use spherical_faces::progress::ignore;
//! # let reference = TriMesh::default();
//! let topo = Topology::new(&reference);
//! let field = jet_fit(&reference, &topo, &JetParams::default(), &mut ignore).unwrap();
//! let sizing = SizingField::from_curvature(&reference, &topo, &field, DEFAULT_EPSILON);
//! let remeshed = pliant_remesh(&reference, &sizing, &RemeshParams::default(), &mut ignore).unwrap();
//! ```

pub mod influence_zones;
pub mod pliant;
pub mod quad_remeshing;

use serde::{Deserialize, Serialize};

use crate::geometry::mesh::TriMesh;

use crate::geometry::mesh::topology::Topology;
use crate::geometry::sphere::Sphere;
use crate::progress::{Cancelled, OnProgress};

pub use influence_zones::{
    influence_zone, local_spheres_orthogonal, mean_edge_length, zone_diameter, SizingBounds, SizingField,
    DEFAULT_EPSILON,
};
pub use pliant::{
    pliant_remesh, pliant_remesh_with_stats, RemeshError, RemeshOutput, RemeshParams, RoundStats, COLLAPSE_BELOW,
    SPLIT_ABOVE,
};

/// How the reference is remeshed before a method runs (Sec. 3).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Sizing {
    /// Influence zones of per-vertex spheres, ε relative to the bbox diagonal.
    Adaptive { epsilon: f64 },
    /// Uniform field for about this many faces.
    UniformFaces(usize),
    /// Use the reference triangulation as is (no remeshing).
    None,
}

impl Sizing {
    /// The sizing field this asks for on `mesh`: the influence zones of `sphere_of(i)` (ε × the
    /// bbox diagonal, clamped to `bounds`), the uniform field for about N faces, or None (keep
    /// the mesh).
    pub fn field(
        &self,
        mesh: &TriMesh,
        topo: &Topology,
        sphere_of: &dyn Fn(usize) -> Sphere,
        bounds: SizingBounds,
        progress: &mut OnProgress,
    ) -> Result<Option<SizingField>, Cancelled> {
        Ok(match *self {
            Sizing::Adaptive { epsilon } => {
                let eps = epsilon * mesh.bbox_diagonal();
                Some(SizingField::from_sphere_fn(mesh, topo, sphere_of, eps, bounds, progress)?)
            }
            Sizing::UniformFaces(n) => Some(SizingField::uniform_for_face_count(mesh, n)),
            Sizing::None => None,
        })
    }
}
