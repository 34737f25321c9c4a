//! Meshes with adapted face size (paper Sec. 3): influence zones and the sizing field
//! ([`sizing`]), and pliant remeshing ([`pliant`]) on a halfedge mesh ([`halfedge`]).
//!
//! Typical use:
//! ```no_run
//! # use spherical_faces::{mesh::{Topology, TriMesh}, curvature::{jet_fit, JetParams}};
//! # use spherical_faces::remesh::{SizingField, RemeshParams, pliant_remesh, DEFAULT_EPSILON};
//! # let reference = TriMesh::default();
//! let topo = Topology::new(&reference);
//! let field = jet_fit(&reference, &topo, &JetParams::default(), &mut |_, _| true).unwrap();
//! let sizing = SizingField::from_curvature(&reference, &topo, &field, DEFAULT_EPSILON);
//! let remeshed = pliant_remesh(&reference, &sizing, &RemeshParams::default(), &mut |_, _| true).unwrap();
//! ```

pub mod halfedge;
pub mod pliant;
pub mod sizing;

pub use halfedge::{HalfedgeMesh, VertexKind};
pub use pliant::{
    pliant_remesh, pliant_remesh_with_stats, RemeshOutput, RemeshParams, RoundStats, COLLAPSE_BELOW, SPLIT_ABOVE,
};
pub use sizing::{
    influence_zone, local_spheres_orthogonal, mean_edge_length, zone_diameter, SizingBounds, SizingField,
    DEFAULT_EPSILON,
};
