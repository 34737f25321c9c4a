//! What the app holds of the worker's results: the loaded reference as display meshes, and per
//! method what its stage streamed.

use std::sync::Arc;

use glam::Vec3;

use crate::congruence::central_spheres::CurvatureSummary;
use crate::design_link::ColorBy;
use crate::pipeline::fields::{field, find, Field, StageProgress};
use crate::pipeline::protocol::ReferenceInfo;
use crate::pipeline::stages::st_adapted::StAdaptedSummary;
use crate::pipeline::stages::st_support::StSupportSummary;
use crate::web::viewer::{MeshData, ScalarData};

/// The loaded reference and what the stages made of it.
pub struct Loaded {
    pub info: ReferenceInfo,
    pub mesh: Arc<MeshData>,
    pub center: Vec3,
    pub radius: f32,
    pub curvature: Option<CurvatureView>,
    pub st_support: Option<StSupportView>,
    pub st_adapted: Option<StAdaptedView>,
}

impl Loaded {
    pub fn new(info: ReferenceInfo) -> Self {
        Self {
            info,
            mesh: Arc::new(empty_mesh()),
            center: Vec3::ZERO,
            radius: 1.0,
            curvature: None,
            st_support: None,
            st_adapted: None,
        }
    }
}

/// The curvature fields and their summary.
pub struct CurvatureView {
    pub fields: Vec<Field>,
    pub summary: Option<CurvatureSummary>,
}

/// The "ST, adapted face size" run as it streams in: sizing field, remeshed triangulation, the
/// latest panels and the energy of every iteration.
#[derive(Default)]
pub struct StAdaptedView {
    /// g at the reference vertices.
    pub sizing: Option<Vec<f32>>,
    pub remeshed: Option<Arc<MeshData>>,
    pub panels: Option<Arc<MeshData>>,
    /// Iteration of the panels shown, and how many panel snapshots arrived.
    pub panel_iteration: u32,
    pub panel_snapshots: u32,
    /// (iteration, optimizer stage, total energy).
    pub energy: Vec<(u32, String, f64)>,
    pub summary: Option<StAdaptedSummary>,
}

/// The ST-with-support-structure result as display meshes.
pub struct StSupportView {
    pub panels: Arc<MeshData>,
    pub support: Arc<MeshData>,
    pub axes: Arc<MeshData>,
    pub envelope: Option<Arc<MeshData>>,
    pub summary: Option<StSupportSummary>,
}

/// The field names of a display mesh: positions, normals, triangles, edges.
pub const PANEL_FIELDS: [&str; 4] = [field::PANEL_POSITIONS, field::PANEL_NORMALS, field::PANEL_TRIANGLES, field::PANEL_EDGES];
pub const MESH_FIELDS: [&str; 4] = [field::POSITIONS, field::NORMALS, field::TRIANGLES, field::EDGES];

/// A display mesh from snapshot fields (missing fields are empty), with a fresh generation.
pub fn mesh_from_fields(fields: &[Field], generation: &mut u64, names: [&str; 4]) -> Arc<MeshData> {
    let f = |n| find(fields, n).and_then(Field::as_f32).map(<[f32]>::to_vec).unwrap_or_default();
    let u = |n| find(fields, n).and_then(Field::as_u32).map(<[u32]>::to_vec).unwrap_or_default();
    *generation += 1;
    Arc::new(MeshData { generation: *generation, positions: f(names[0]), normals: f(names[1]), triangles: u(names[2]), edges: u(names[3]) })
}

impl StSupportView {
    pub fn from_fields(fields: &[Field], generation: &mut u64) -> Self {
        let envelope = find(fields, field::ENVELOPE_POSITIONS).is_some().then(|| {
            mesh_from_fields(fields, generation, [field::ENVELOPE_POSITIONS, "", field::ENVELOPE_TRIANGLES, ""])
        });
        Self {
            panels: mesh_from_fields(fields, generation, PANEL_FIELDS),
            support: mesh_from_fields(fields, generation, [field::SUPPORT_POSITIONS, "", field::SUPPORT_TRIANGLES, ""]),
            axes: mesh_from_fields(fields, generation, [field::AXES_POSITIONS, "", "", field::AXES_LINES]),
            envelope,
            summary: None,
        }
    }
}

/// A file the worker produced, offered for download.
pub struct Download {
    pub name: String,
    pub mime: String,
    pub bytes: Vec<u8>,
}

/// A stage running in the worker.
pub struct Busy {
    pub stage: String,
    pub progress: Option<StageProgress>,
}

/// The colour map currently uploaded.
pub struct ScalarView {
    pub color: ColorBy,
    pub data: Arc<ScalarData>,
    pub range: (f32, f32),
    pub diverging: bool,
}

pub fn empty_mesh() -> MeshData {
    MeshData { generation: 0, positions: Vec::new(), normals: Vec::new(), triangles: Vec::new(), edges: Vec::new() }
}
