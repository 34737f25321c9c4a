//! The typed worker protocol. Headers travel as JSON (serde); bulk data travels beside them as
//! binary [`Field`]s, which the web layer moves as transferable `ArrayBuffer`s.

use serde::{Deserialize, Serialize};

use super::st_angle::{StRequest, StSummary};
use super::st_support::{StSupportRequest, StSupportSummary};
use crate::curvature::{CurvatureSummary, JetParams};
use crate::import::Format;
use crate::mesh::MeshStats;
use crate::samples::Sample;

/// Where a reference surface comes from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Source {
    Sample(Sample),
    File(String),
}

impl Source {
    /// "sample:dome" or "file:roof.obj".
    pub fn label(&self) -> String {
        match self {
            Source::Sample(s) => format!("sample:{}", s.key()),
            Source::File(name) => format!("file:{name}"),
        }
    }
}

/// A stage and its parameters. Every method adds its stages here.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum StageRequest {
    /// Jet-fitted curvature and central spheres (Sec. 2.6).
    Curvature(JetParams),
    /// ST mesh with support structure (Sec. 4), with panels and exports.
    StSupport(StSupportRequest),
    /// Angle-minimizing ST mesh with face size adapted to the surface (Sec. 3), with panels
    /// and exports.
    St(StRequest),
}

impl StageRequest {
    pub fn name(&self) -> &'static str {
        match self {
            StageRequest::Curvature(_) => "curvature",
            StageRequest::StSupport(_) => "st-support",
            StageRequest::St(_) => super::st_angle::STAGE,
        }
    }
}

/// Main thread to worker. A `LoadFile` carries the file bytes as its one binary field.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum ToWorker {
    LoadSample(Sample),
    LoadFile { name: String },
    Run(StageRequest),
    Cancel,
    /// Diagnostics: the worker panics on purpose, to exercise crash recovery end to end.
    Crash,
}

/// A named energy or statistic of an iteration.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Energy {
    pub name: String,
    pub value: f64,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Progress {
    pub stage: String,
    /// The step within the stage, e.g. "absolute_sphere".
    #[serde(default)]
    pub detail: String,
    pub iteration: u32,
    /// Total iterations when known (0 when open-ended).
    pub total: u32,
    pub energies: Vec<Energy>,
    pub elapsed_ms: f64,
}

/// Describes the loaded reference surface.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ReferenceInfo {
    pub source: Source,
    pub format: Option<Format>,
    pub stats: MeshStats,
    pub bbox_diagonal: f64,
    pub notes: Vec<String>,
}

/// The summary a finished stage returns (bulk data arrives as snapshot fields).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum StageResult {
    Curvature(CurvatureSummary),
    StSupport(Box<StSupportSummary>),
    St(Box<StSummary>),
}

/// Worker to main thread.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum FromWorker {
    /// The worker's wasm is initialised and waits for messages.
    Ready,
    /// A reference surface is loaded; its geometry arrives in the snapshot that follows.
    Loaded(ReferenceInfo),
    Progress(Progress),
    /// A snapshot: the stage's geometry and per-vertex data as fields.
    Snapshot { stage: String, iteration: u32, fields: Vec<FieldHeader> },
    /// Files for download (fields of raw bytes named by file name), with their MIME types.
    Files { stage: String, fields: Vec<FieldHeader>, mime: Vec<String> },
    Finished { stage: String, result: StageResult, elapsed_ms: f64 },
    Cancelled { stage: String },
    /// An error a user can act on. The previous design stays loaded.
    Error { message: String },
}

/// Well-known field names.
pub mod field {
    /// Vertex positions, f32 × 3.
    pub const POSITIONS: &str = "positions";
    /// Triangle indices, u32 × 3.
    pub const TRIANGLES: &str = "triangles";
    /// Unique undirected edges, u32 × 2.
    pub const EDGES: &str = "edges";
    pub const MEAN_CURVATURE: &str = "H";
    pub const K1: &str = "k1";
    pub const K2: &str = "k2";
    pub const K1_MINUS_K2: &str = "k1-k2";
    /// Vertex normals used for the curvature sign, f32 × 3.
    pub const NORMALS: &str = "normals";
    /// Normalized generalized central spheres (a, b.x, b.y, b.z, c), f32 × 5.
    pub const CENTRAL_SPHERES: &str = "central_spheres";
    /// 1 where the vertex is on the boundary, u32 × 1.
    pub const BOUNDARY: &str = "boundary";
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
    pub fn from_bytes(header: &FieldHeader, bytes: &[u8]) -> Result<Self, String> {
        let width = if header.kind == FieldKind::U8 { 1 } else { 4 };
        if bytes.len() != header.len as usize * width {
            return Err(format!(
                "field '{}': expected {} bytes, got {}",
                header.name,
                header.len as usize * width,
                bytes.len()
            ));
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

/// Find a field by name.
pub fn find<'a>(fields: &'a [Field], name: &str) -> Option<&'a Field> {
    fields.iter().find(|f| f.name == name)
}

/// A message encoded for transport: JSON header plus binary bodies in field order.
#[derive(Clone, Debug, PartialEq)]
pub struct Envelope {
    pub json: String,
    pub bodies: Vec<Vec<u8>>,
}

/// Encodes a message from the worker with its fields (the header lists them).
pub fn encode_from_worker(msg: &FromWorker, fields: &[Field]) -> Envelope {
    Envelope {
        json: serde_json::to_string(msg).expect("protocol types always serialize"),
        bodies: fields.iter().map(Field::to_bytes).collect(),
    }
}

/// Decodes a message from the worker; snapshot fields are rebuilt from the bodies.
pub fn decode_from_worker(env: &Envelope) -> Result<(FromWorker, Vec<Field>), String> {
    let msg: FromWorker =
        serde_json::from_str(&env.json).map_err(|e| format!("bad worker message: {e}"))?;
    let mut fields = Vec::new();
    if let FromWorker::Snapshot { fields: headers, .. } | FromWorker::Files { fields: headers, .. } = &msg {
        if headers.len() != env.bodies.len() {
            return Err(format!(
                "snapshot lists {} fields but carries {} buffers",
                headers.len(),
                env.bodies.len()
            ));
        }
        for (h, b) in headers.iter().zip(&env.bodies) {
            fields.push(Field::from_bytes(h, b)?);
        }
    }
    Ok((msg, fields))
}

/// Encodes a message to the worker; a file load carries its bytes as the one body.
pub fn encode_to_worker(msg: &ToWorker, file_bytes: Option<Vec<u8>>) -> Envelope {
    Envelope {
        json: serde_json::to_string(msg).expect("protocol types always serialize"),
        bodies: file_bytes.into_iter().collect(),
    }
}

pub fn decode_to_worker(env: &Envelope) -> Result<(ToWorker, Option<&[u8]>), String> {
    let msg: ToWorker =
        serde_json::from_str(&env.json).map_err(|e| format!("bad message to worker: {e}"))?;
    Ok((msg, env.bodies.first().map(|b| b.as_slice())))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn snapshot_round_trip() {
        let fields = vec![
            Field::f32(field::POSITIONS, 3, vec![0.0, 1.5, -2.0, 3.0, 4.0, 5.0]),
            Field::u32(field::TRIANGLES, 3, vec![0, 1, 0]),
        ];
        let msg = FromWorker::Snapshot {
            stage: "curvature".into(),
            iteration: 3,
            fields: fields.iter().map(Field::header).collect(),
        };
        let env = encode_from_worker(&msg, &fields);
        let (back, back_fields) = decode_from_worker(&env).unwrap();
        assert_eq!(back, msg);
        assert_eq!(back_fields, fields);
    }

    #[test]
    fn files_round_trip() {
        let fields = vec![Field::bytes("panels.glb", b"glTF\x02\x00\x00\x00abc".to_vec()), Field::bytes("panels.csv", b"id\n".to_vec())];
        let msg = FromWorker::Files {
            stage: "st-support".into(),
            fields: fields.iter().map(Field::header).collect(),
            mime: vec!["model/gltf-binary".into(), "text/csv".into()],
        };
        let (back, back_fields) = decode_from_worker(&encode_from_worker(&msg, &fields)).unwrap();
        assert_eq!(back, msg);
        assert_eq!(back_fields, fields);
    }

    #[test]
    fn truncated_body_is_rejected() {
        let fields = vec![Field::f32("x", 1, vec![1.0, 2.0])];
        let msg = FromWorker::Snapshot {
            stage: "s".into(),
            iteration: 0,
            fields: fields.iter().map(Field::header).collect(),
        };
        let mut env = encode_from_worker(&msg, &fields);
        env.bodies[0].pop();
        assert!(decode_from_worker(&env).is_err());
    }
}
