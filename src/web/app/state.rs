//! What the app holds of the worker's results that every method shares: the loaded reference as
//! a display mesh with its curvature, the downloads and the running stage. What a method's stage
//! streamed is its view's ([`super::views`]).

use std::sync::Arc;

use glam::Vec3;

use crate::congruence::central_spheres::CurvatureSummary;
use crate::design_link::ColorBy;
use crate::pipeline::fields::{field, find, Field};
use crate::pipeline::protocol::ReferenceInfo;
use crate::pipeline::protocol::{StageId, StageProgress};
use crate::web::viewer::{Geometry, Layer, MeshData, ScalarData};

/// The loaded reference and its curvature.
pub struct Scene {
    pub info: ReferenceInfo,
    pub mesh: Arc<MeshData>,
    pub center: Vec3,
    pub radius: f32,
    pub curvature: Option<CurvatureView>,
}

impl Scene {
    pub fn new(info: ReferenceInfo) -> Self {
        Self { info, mesh: Arc::new(empty_mesh()), center: Vec3::ZERO, radius: 1.0, curvature: None }
    }
}

/// The curvature fields and their summary.
pub struct CurvatureView {
    pub fields: Vec<Field>,
    pub summary: Option<CurvatureSummary>,
}

/// The field names of a display mesh: positions, normals, triangles, edges.
pub const PANEL_FIELDS: [&str; 4] = [field::PANEL_POSITIONS, field::PANEL_NORMALS, field::PANEL_TRIANGLES, field::PANEL_EDGES];
pub const MESH_FIELDS: [&str; 4] = [field::POSITIONS, field::NORMALS, field::TRIANGLES, field::EDGES];
pub const SUPPORT_FIELDS: [&str; 4] = [field::SUPPORT_POSITIONS, "", field::SUPPORT_TRIANGLES, ""];
pub const AXES_FIELDS: [&str; 4] = [field::AXES_POSITIONS, "", "", field::AXES_LINES];

/// A display mesh from snapshot fields (missing fields are empty), with a fresh generation.
pub fn mesh_from_fields(fields: &[Field], generation: &mut u64, names: [&str; 4]) -> Arc<MeshData> {
    let f = |n| find(fields, n).and_then(Field::as_f32).map(<[f32]>::to_vec).unwrap_or_default();
    let u = |n| find(fields, n).and_then(Field::as_u32).map(<[u32]>::to_vec).unwrap_or_default();
    *generation += 1;
    Arc::new(MeshData { generation: *generation, positions: f(names[0]), normals: f(names[1]), triangles: u(names[2]), edges: u(names[3]) })
}

/// A file the worker produced, offered for download.
pub struct Download {
    pub name: String,
    pub mime: String,
    pub bytes: Vec<u8>,
}

/// A stage running in the worker.
pub struct Busy {
    pub stage: StageId,
    pub progress: Option<StageProgress>,
    /// `performance.now()` when the run was asked for (Run pressed, a link opened, a file dropped).
    pub since_ms: f64,
}

impl Busy {
    pub fn new(stage: StageId) -> Self {
        Self { stage, progress: None, since_ms: super::dom::now_ms() }
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
    MeshData { generation: 0, positions: Vec::new(), normals: Vec::new(), triangles: Vec::new(), edges: Vec::new() }
}

/// What a message belongs to, which says when it goes: a message lives as long as what caused
/// it (a new link replaces the link's notices, a new reference or file replaces everything of
/// the old one, a new run replaces the last run's).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Origin {
    /// The design link as opened or edited.
    Link,
    /// The loaded reference or a file the user gave.
    Reference,
    /// A run of the method.
    Run,
    /// The worker itself (a crash): kept through the run that restores the design.
    Worker,
    /// A button's confirmation: goes after [`UI_NOTICE_MS`].
    Ui,
}

/// How long a button's confirmation shows (ms).
pub const UI_NOTICE_MS: f64 = 6000.0;

/// A notice, and what it belongs to.
pub struct Notice {
    pub text: String,
    pub origin: Origin,
    pub since_ms: f64,
}

impl Notice {
    pub fn new(text: impl Into<String>, origin: Origin) -> Self {
        Self { text: text.into(), origin, since_ms: super::dom::now_ms() }
    }
}

/// The error shown, what it belongs to, and what it offers.
pub struct ShownError {
    pub text: String,
    pub origin: Origin,
    /// A method refused its input's size: a remesh to about this many faces is offered.
    pub remesh_to: Option<usize>,
    /// The method that refused its input: the menu's other methods are offered.
    pub refused_by: Option<crate::pipeline::protocol::MethodId>,
}

impl ShownError {
    pub fn new(text: impl Into<String>, origin: Origin) -> Self {
        Self { text: text.into(), origin, remesh_to: None, refused_by: None }
    }
}

/// The reach of what is drawn, for the clip planes: the radius about the reference's centre of
/// everything drawn, at least the reference's, at most [`CLIP_REACH`] × it. Computed again when
/// the layers' meshes change (one pass over their points).
pub struct Extent {
    pub key: Vec<u64>,
    pub clip_radius: f32,
}

/// How far beyond the reference's radius the clip planes reach at most.
const CLIP_REACH: f32 = 50.0;

/// The finite points of the mesh layers, in world coordinates.
fn layer_points(layers: &[Layer]) -> impl Iterator<Item = Vec3> + '_ {
    layers
        .iter()
        .filter_map(|l| match &l.geometry {
            Geometry::Mesh(m) => Some((m, l.model)),
            _ => None,
        })
        .flat_map(|(m, model)| m.positions.chunks_exact(3).map(move |p| model.transform_point3(Vec3::from_slice(p))))
        .filter(|p| p.is_finite())
}

impl Extent {
    pub fn of(key: Vec<u64>, layers: &[Layer], center: Vec3, radius: f32) -> Self {
        let reach = layer_points(layers).fold(radius, |r, p| r.max(p.distance(center)));
        Self { key, clip_radius: reach.min(CLIP_REACH * radius) }
    }
}

/// What a double click frames: the reference and the bulk of the layers (the 2nd to 98th
/// percentile along each axis), so that a failed result's wild parts do not shrink the rest to
/// a dot. Centre and radius.
pub fn framing(layers: &[Layer], center: Vec3, radius: f32) -> (Vec3, f32) {
    let points: Vec<Vec3> = layer_points(layers).collect();
    let (mut lo, mut hi) = (center - Vec3::splat(radius), center + Vec3::splat(radius));
    if !points.is_empty() {
        for axis in 0..3 {
            let mut v: Vec<f32> = points.iter().map(|p| p[axis]).collect();
            v.sort_by(f32::total_cmp);
            let at = |q: f32| v[((v.len() - 1) as f32 * q).round() as usize];
            lo[axis] = lo[axis].min(at(0.02));
            hi[axis] = hi[axis].max(at(0.98));
        }
    }
    ((lo + hi) * 0.5, ((hi - lo).length() * 0.5).max(1e-6))
}

/// What the view says while a design waits for its file.
pub fn drop_prompt(name: &str) -> String {
    let name = if name.is_empty() { "your file" } else { name };
    format!("This design uses {name}.\nDrop {name} here (or Open…) to continue it.")
}
