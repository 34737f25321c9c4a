//! What the app holds of the worker's results: the loaded reference as display meshes, and per
//! method what its stage streamed.

use std::sync::Arc;

use glam::Vec3;

use crate::congruence::central_spheres::CurvatureSummary;
use crate::design_link::ColorBy;
use crate::pipeline::fields::Energy;
use crate::pipeline::fields::{field, find, Field, StageProgress};
use crate::pipeline::protocol::ReferenceInfo;
use crate::pipeline::stages::sq::SqSummary;
use crate::pipeline::stages::st_adapted::StAdaptedSummary;
use crate::pipeline::stages::st_support::StSupportSummary;
use crate::web::viewer::{MeshData, ScalarData};

/// The loaded reference and what the stages made of it.
pub struct Scene {
    pub info: ReferenceInfo,
    pub mesh: Arc<MeshData>,
    pub center: Vec3,
    pub radius: f32,
    pub curvature: Option<CurvatureView>,
    pub st_support: Option<StSupportView>,
    pub st_adapted: Option<StAdaptedView>,
    pub sq: Option<SqView>,
}

impl Scene {
    pub fn new(info: ReferenceInfo) -> Self {
        Self {
            info,
            mesh: Arc::new(empty_mesh()),
            center: Vec3::ZERO,
            radius: 1.0,
            curvature: None,
            st_support: None,
            st_adapted: None,
            sq: None,
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

/// The SQ run (Sec. 5) as it streams in: the lines of the central congruence, the lines as
/// they optimize, the energy of every term per iteration; when done, the torsal cross field by
/// angle bins, the quads without real torsal directions and the summary. On a refusal for the
/// sign of H, H at the reference vertices.
#[derive(Default)]
pub struct SqView {
    pub initial_lines: Option<Arc<MeshData>>,
    pub lines: Option<Arc<MeshData>>,
    pub line_iteration: u32,
    pub line_snapshots: u32,
    /// The cross field's arms, one mesh per angle bin ([`CROSS_FIELD_BINS`] over [lo, 90°]).
    pub cross_field: Vec<Arc<MeshData>>,
    pub cross_field_range: (f32, f32),
    pub cross_field_arms: usize,
    pub no_real_quads: Option<Arc<MeshData>>,
    /// Sec. 5.2: the quad mesh's edges (as remeshed, Q′, then the SQ mesh), the panels (live
    /// while the spheres optimize, then final), the support structure and the node axes.
    pub quad_mesh: Option<Arc<MeshData>>,
    pub panels: Option<Arc<MeshData>>,
    pub support: Option<Arc<MeshData>>,
    pub axes: Option<Arc<MeshData>>,
    /// (iteration, step, energy of every term and the total).
    pub energy: Vec<(u32, String, Vec<Energy>)>,
    pub refused_h: Option<Arc<ScalarData>>,
    pub summary: Option<SqSummary>,
}

/// Colour bins of the cross field by torsal-plane angle.
pub const CROSS_FIELD_BINS: usize = 6;

/// Line segments (point pairs) of field `name` as a display mesh of edges.
pub fn segments_mesh(fields: &[Field], name: &str, generation: &mut u64) -> Option<Arc<MeshData>> {
    Some(segment_mesh(
        find(fields, name).and_then(Field::as_f32)?.to_vec(),
        generation,
    ))
}

/// Point pairs as a display mesh of edges, with a fresh generation.
fn segment_mesh(positions: Vec<f32>, generation: &mut u64) -> Arc<MeshData> {
    *generation += 1;
    let edges = (0..(positions.len() / 3) as u32).collect();
    Arc::new(MeshData {
        generation: *generation,
        positions,
        normals: Vec::new(),
        triangles: Vec::new(),
        edges,
    })
}

impl SqView {
    /// Takes what a snapshot of the stage carries (live snapshots carry the lines only).
    pub fn install(&mut self, fields: &[Field], iteration: u32, generation: &mut u64) {
        if let Some(m) = segments_mesh(fields, field::SQ_INITIAL_LINES, generation) {
            self.initial_lines = Some(m);
        }
        if let Some(m) = segments_mesh(fields, field::SQ_LINES, generation) {
            self.lines = Some(m);
            self.line_iteration = iteration;
            self.line_snapshots += 1;
        }
        if let Some(m) = segments_mesh(fields, field::SQ_NO_REAL_QUADS, generation) {
            self.no_real_quads = Some(m);
        }
        if let Some(m) = segments_mesh(fields, field::SQ_QUAD_MESH, generation) {
            self.quad_mesh = Some(m);
        }
        if find(fields, field::PANEL_POSITIONS).is_some() {
            self.panels = Some(mesh_from_fields(fields, generation, PANEL_FIELDS));
        }
        if find(fields, field::SUPPORT_POSITIONS).is_some() {
            self.support = Some(mesh_from_fields(fields, generation, SUPPORT_FIELDS));
            self.axes = Some(mesh_from_fields(fields, generation, AXES_FIELDS));
        }
        let (Some(arms), Some(angles)) = (
            find(fields, field::SQ_CROSS_FIELD).and_then(Field::as_f32),
            find(fields, field::SQ_CROSS_FIELD_ANGLE).and_then(Field::as_f32),
        ) else {
            return;
        };
        let lo = angles
            .iter()
            .copied()
            .fold(90.0f32, f32::min)
            .floor()
            .min(89.0);
        let mut bins = vec![Vec::new(); CROSS_FIELD_BINS];
        for (k, &a) in angles.iter().enumerate() {
            let b = (((a - lo) / (90.0 - lo) * CROSS_FIELD_BINS as f32) as usize)
                .min(CROSS_FIELD_BINS - 1);
            bins[b].extend_from_slice(&arms[6 * k..6 * k + 6]);
        }
        self.cross_field = bins
            .into_iter()
            .map(|positions| segment_mesh(positions, generation))
            .collect();
        self.cross_field_range = (lo, 90.0);
        self.cross_field_arms = angles.len();
    }
}

/// The field names of a display mesh: positions, normals, triangles, edges.
pub const PANEL_FIELDS: [&str; 4] = [
    field::PANEL_POSITIONS,
    field::PANEL_NORMALS,
    field::PANEL_TRIANGLES,
    field::PANEL_EDGES,
];
pub const MESH_FIELDS: [&str; 4] = [
    field::POSITIONS,
    field::NORMALS,
    field::TRIANGLES,
    field::EDGES,
];
pub const SUPPORT_FIELDS: [&str; 4] = [field::SUPPORT_POSITIONS, "", field::SUPPORT_TRIANGLES, ""];
pub const AXES_FIELDS: [&str; 4] = [field::AXES_POSITIONS, "", "", field::AXES_LINES];

/// A display mesh from snapshot fields (missing fields are empty), with a fresh generation.
pub fn mesh_from_fields(fields: &[Field], generation: &mut u64, names: [&str; 4]) -> Arc<MeshData> {
    let f = |n| {
        find(fields, n)
            .and_then(Field::as_f32)
            .map(<[f32]>::to_vec)
            .unwrap_or_default()
    };
    let u = |n| {
        find(fields, n)
            .and_then(Field::as_u32)
            .map(<[u32]>::to_vec)
            .unwrap_or_default()
    };
    *generation += 1;
    Arc::new(MeshData {
        generation: *generation,
        positions: f(names[0]),
        normals: f(names[1]),
        triangles: u(names[2]),
        edges: u(names[3]),
    })
}

impl StSupportView {
    pub fn from_fields(fields: &[Field], generation: &mut u64) -> Self {
        let envelope = find(fields, field::ENVELOPE_POSITIONS).is_some().then(|| {
            mesh_from_fields(
                fields,
                generation,
                [field::ENVELOPE_POSITIONS, "", field::ENVELOPE_TRIANGLES, ""],
            )
        });
        Self {
            panels: mesh_from_fields(fields, generation, PANEL_FIELDS),
            support: mesh_from_fields(fields, generation, SUPPORT_FIELDS),
            axes: mesh_from_fields(fields, generation, AXES_FIELDS),
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
    /// `performance.now()` when the run was asked for (Run pressed, a link opened, a file dropped).
    pub since_ms: f64,
}

impl Busy {
    pub fn new(stage: impl Into<String>) -> Self {
        Self {
            stage: stage.into(),
            progress: None,
            since_ms: super::dom::now_ms(),
        }
    }
}

/// The colour map currently uploaded.
pub struct ScalarView {
    pub color: ColorBy,
    pub data: Arc<ScalarData>,
    pub range: (f32, f32),
    pub diverging: bool,
}

pub fn empty_mesh() -> MeshData {
    MeshData {
        generation: 0,
        positions: Vec::new(),
        normals: Vec::new(),
        triangles: Vec::new(),
        edges: Vec::new(),
    }
}
