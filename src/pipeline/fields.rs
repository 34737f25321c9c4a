//! What stages send: binary [`Field`]s of per-element data (moved as transferable
//! `ArrayBuffer`s on the web) and their progress.

use serde::{Deserialize, Serialize};

/// A named energy or statistic of an iteration.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Energy {
    pub name: String,
    pub value: f64,
}

/// Which part of a stage's stream a snapshot belongs to: the stage's own geometry, or what a
/// method made of the reference before it optimizes (Sec. 3: the sizing field, the remeshed
/// triangulation), or what it shows when it refuses a surface (Sec. 6.3: H at the vertices).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Part {
    Main,
    Sizing,
    Remeshed,
    Refused,
}

impl Part {
    pub const ALL: [Part; 4] = [Part::Main, Part::Sizing, Part::Remeshed, Part::Refused];

    /// The suffix of the stage's key ("" for the stage itself: "st", "st.sizing").
    pub fn suffix(self) -> &'static str {
        match self {
            Part::Main => "",
            Part::Sizing => "sizing",
            Part::Remeshed => "remeshed",
            Part::Refused => "refused",
        }
    }
}

/// A step's progress as a stage reports it; the session says which stage it is.
#[derive(Clone, Debug, PartialEq)]
pub struct StepProgress {
    /// The step within the stage, e.g. "absolute_sphere".
    pub detail: String,
    pub iteration: u32,
    /// Total iterations when known (0 when open-ended).
    pub total: u32,
    pub energies: Vec<Energy>,
    pub elapsed_ms: f64,
}

/// Well-known field names.
pub mod field {
    /// Vertex positions, f32 × 3.
    pub const POSITIONS: &str = "positions";
    /// Triangle indices, u32 × 3.
    pub const TRIANGLES: &str = "triangles";
    /// Unique undirected edges, u32 × 2.
    pub(crate) const EDGES: &str = "edges";
    pub const MEAN_CURVATURE: &str = "H";
    pub const K1: &str = "k1";
    pub(crate) const K2: &str = "k2";
    pub(crate) const K1_MINUS_K2: &str = "k1-k2";
    /// Vertex normals used for the curvature sign, f32 × 3.
    pub(crate) const NORMALS: &str = "normals";
    /// Normalized generalized central spheres (a, b.x, b.y, b.z, c), f32 × 5.
    pub const CENTRAL_SPHERES: &str = "central_spheres";
    /// 1 where the vertex is on the boundary, u32 × 1.
    pub(crate) const BOUNDARY: &str = "boundary";
    /// The sizing field g at the reference vertices (absolute length), f32 × 1.
    pub const SIZING: &str = "sizing";
    /// Panel tessellations: positions with the sphere normals there, triangles, and the
    /// boundary arcs of every panel as line segments over the positions.
    pub const PANEL_POSITIONS: &str = "panels.positions";
    pub(crate) const PANEL_NORMALS: &str = "panels.normals";
    pub const PANEL_TRIANGLES: &str = "panels.triangles";
    pub(crate) const PANEL_EDGES: &str = "panels.edges";
    /// The mould of each panel vertex (its panel's, [`crate::panels::moulds`]), u32 × 1.
    pub const PANEL_MOULDS: &str = "panels.moulds";
    pub(crate) const SUPPORT_POSITIONS: &str = "support.positions";
    pub const SUPPORT_TRIANGLES: &str = "support.triangles";
    pub(crate) const AXES_POSITIONS: &str = "axes.positions";
    pub const AXES_LINES: &str = "axes.lines";
    /// The second envelope: the mesh inverted in Ω.
    pub(crate) const ENVELOPE_POSITIONS: &str = "envelope2.positions";
    pub(crate) const ENVELOPE_TRIANGLES: &str = "envelope2.triangles";
    /// SQ (Sec. 5.1): line segments as point pairs, f32 × 3: the optimized lines over the
    /// surface, the lines of the central congruence, the torsal cross field (two arms per quad)
    /// and the outlines of the quads without real torsal directions.
    pub(crate) const SQ_LINES: &str = "sq.lines";
    pub const SQ_INITIAL_LINES: &str = "sq.initial_lines";
    pub const SQ_CROSS_FIELD: &str = "sq.cross_field";
    /// The torsal-plane angle (degrees) of each cross-field arm, f32 × 1.
    pub const SQ_CROSS_FIELD_ANGLE: &str = "sq.cross_field.angle";
    pub const SQ_NO_REAL_QUADS: &str = "sq.no_real_quads";
    /// SQ (Sec. 5.2): the edges of the quad mesh (as remeshed, Q′, then the SQ mesh) as point
    /// pairs, f32 × 3.
    pub const SQ_QUAD_MESH: &str = "sq.quad_mesh";
}

/// Binary payload of a field.
#[derive(Clone, Debug, PartialEq)]
pub enum FieldData {
    F32(Vec<f32>),
    U32(Vec<u32>),
    /// Raw bytes, e.g. an exported file.
    Bytes(Vec<u8>),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum FieldKind {
    F32,
    U32,
    U8,
}

/// A named per-element array with `dim` components per element.
#[derive(Clone, Debug, PartialEq)]
pub struct Field {
    pub name: String,
    pub dim: u32,
    pub data: FieldData,
}

/// What the JSON header says of a field; its bytes travel separately, in order.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FieldHeader {
    pub name: String,
    pub kind: FieldKind,
    pub dim: u32,
    pub len: u32,
}

impl Field {
    pub fn f32(name: &str, dim: u32, values: Vec<f32>) -> Self {
        Self { name: name.into(), dim, data: FieldData::F32(values) }
    }

    pub fn u32(name: &str, dim: u32, values: Vec<u32>) -> Self {
        Self { name: name.into(), dim, data: FieldData::U32(values) }
    }

    pub fn bytes(name: &str, bytes: Vec<u8>) -> Self {
        Self { name: name.into(), dim: 1, data: FieldData::Bytes(bytes) }
    }

    pub fn header(&self) -> FieldHeader {
        let (kind, len) = match &self.data {
            FieldData::F32(v) => (FieldKind::F32, v.len()),
            FieldData::U32(v) => (FieldKind::U32, v.len()),
            FieldData::Bytes(v) => (FieldKind::U8, v.len()),
        };
        FieldHeader { name: self.name.clone(), kind, dim: self.dim, len: len as u32 }
    }

    pub fn as_f32(&self) -> Option<&[f32]> {
        match &self.data {
            FieldData::F32(v) => Some(v),
            _ => None,
        }
    }

    pub fn as_u32(&self) -> Option<&[u32]> {
        match &self.data {
            FieldData::U32(v) => Some(v),
            _ => None,
        }
    }

    pub fn as_bytes(&self) -> Option<&[u8]> {
        match &self.data {
            FieldData::Bytes(v) => Some(v),
            _ => None,
        }
    }

    /// Little-endian bytes (the wasm and x86 byte order).
    pub fn to_bytes(&self) -> Vec<u8> {
        match &self.data {
            FieldData::F32(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
            FieldData::U32(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
            FieldData::Bytes(v) => v.clone(),
        }
    }

    /// Rebuilds a field from its header and bytes; rejects a length mismatch.
    pub fn from_bytes(header: &FieldHeader, bytes: &[u8]) -> Result<Self, FieldLengthError> {
        let width: u64 = if header.kind == FieldKind::U8 { 1 } else { 4 };
        // In u64: on wasm32 a crafted `len` would wrap a 32-bit usize product.
        let expected = (header.len as u64).checked_mul(width);
        if expected != Some(bytes.len() as u64) {
            let expected = expected.map_or(usize::MAX, |e| usize::try_from(e).unwrap_or(usize::MAX));
            return Err(FieldLengthError { name: header.name.clone(), expected, got: bytes.len() });
        }
        let words = bytes.chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]]);
        let data = match header.kind {
            FieldKind::F32 => FieldData::F32(words.map(f32::from_le_bytes).collect()),
            FieldKind::U32 => FieldData::U32(words.map(u32::from_le_bytes).collect()),
            FieldKind::U8 => FieldData::Bytes(bytes.to_vec()),
        };
        Ok(Self { name: header.name.clone(), dim: header.dim, data })
    }
}

/// A field's bytes do not match its header.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FieldLengthError {
    pub name: String,
    pub expected: usize,
    pub got: usize,
}

impl std::fmt::Display for FieldLengthError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "field '{}': expected {} bytes, got {}", self.name, self.expected, self.got)
    }
}

impl std::error::Error for FieldLengthError {}

/// Find a field by name.
pub fn find<'a>(fields: &'a [Field], name: &str) -> Option<&'a Field> {
    fields.iter().find(|f| f.name == name)
}
