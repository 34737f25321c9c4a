//! The typed worker protocol, and the only file that lists the methods. Headers travel as JSON
//! (serde); bulk data travels beside them as binary [`Field`]s, which the web layer moves as
//! transferable `ArrayBuffer`s.
//!
//! Adding a method: one [`StageRequest`] variant (its parameters), one [`StageResult`] variant
//! (its summary), one arm in [`StageRequest::name`], and one in the session.

use std::fmt;

use serde::{Deserialize, Serialize};

use super::fields::{Field, FieldHeader, FieldLengthError, StageId, StageProgress};
use super::stages::{curvature, sq, st_adapted, st_support};
use crate::congruence::central_spheres::{CurvatureSummary, JetParams};
use crate::export::Report;
use crate::geometry::mesh::topology::MeshStats;
use crate::import::Format;
use crate::panels::moulds::Fabrication;
use crate::reference::bspline::BSplineInfo;
use crate::samples::Sample;
use crate::sq::params::SqParams;
use crate::st_adapted::params::StAdaptedParams;
use crate::st_support::StSupportParams;

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

/// A stage and its parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum StageRequest {
    /// Jet-fitted curvature and central spheres (Sec. 2.6).
    Curvature(JetParams),
    /// Angle-minimizing ST mesh with face size adapted to the surface (Sec. 3), with panels
    /// and exports.
    StAdapted(StAdaptedParams),
    /// ST mesh with support structure (Sec. 4), with panels and exports.
    StSupport(StSupportParams),
    /// SQ mesh with support structure (Sec. 5): the congruence and its torsal field (5.1), the
    /// quad mesh, the final sphere optimization, panels and support structure (5.2), as far as
    /// its `until` asks, with its files.
    Sq(SqParams),
}

impl StageRequest {
    /// The stage's name on the wire.
    pub fn name(&self) -> StageId {
        match self {
            StageRequest::Curvature(_) => curvature::STAGE,
            StageRequest::StAdapted(_) => st_adapted::STAGE,
            StageRequest::StSupport(_) => st_support::STAGE,
            StageRequest::Sq(_) => sq::STAGE,
        }
    }

    /// The method's fabrication settings and whether it optimizes for its moulds (None: the
    /// curvature, which has no panels).
    fn fabrication_mut(&mut self) -> Option<(&mut Fabrication, bool)> {
        match self {
            StageRequest::Curvature(_) => None,
            StageRequest::StAdapted(p) => Some((&mut p.fabrication, p.optimize_moulds)),
            StageRequest::StSupport(p) => Some((&mut p.fabrication, p.optimize_moulds)),
            StageRequest::Sq(p) => Some((&mut p.fabrication, p.optimize_moulds)),
        }
    }

    /// Whether `self` asks for the very result `earlier` made, with other moulds at most (a new
    /// δ, K or unit): then that result is exported again, not computed again. A method that
    /// optimizes for its moulds makes a result that depends on them.
    pub fn same_result_as(&self, earlier: &StageRequest) -> bool {
        let (mut a, mut b) = (self.clone(), earlier.clone());
        match (a.fabrication_mut(), b.fabrication_mut()) {
            (Some((fa, false)), Some((fb, false))) => *fa = *fb,
            _ => return false,
        }
        a == b
    }
}

impl StageResult {
    /// The method's report (None: the curvature).
    pub fn report_mut(&mut self) -> Option<&mut Report> {
        match self {
            StageResult::Curvature(_) => None,
            StageResult::StAdapted(s) => Some(&mut s.report),
            StageResult::StSupport(s) => Some(&mut s.report),
            StageResult::Sq(s) => Some(&mut s.report),
        }
    }
}

/// Main thread to worker. A `LoadFile` carries the file bytes as its one binary field.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum ToWorker {
    LoadSample(Sample),
    LoadFile {
        name: String,
    },
    /// Loads another object of the multi-object file loaded last.
    PickObject(usize),
    Run(Box<StageRequest>),
    Cancel,
    /// Diagnostics: the worker panics on purpose, to exercise crash recovery end to end.
    Crash,
}

/// Describes the loaded reference surface.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ReferenceInfo {
    pub source: Source,
    pub format: Option<Format>,
    /// Of the mesh (a B-spline's tessellation).
    pub stats: MeshStats,
    pub bbox_diagonal: f64,
    pub notes: Vec<String>,
    /// Degrees, control grid, domain and curvature ranges of a B-spline reference.
    #[serde(default)]
    pub bspline: Option<BSplineInfo>,
    /// The objects of a file that holds several (a Rhino .3dm), and which one is loaded.
    #[serde(default)]
    pub objects: Vec<FileObject>,
    #[serde(default)]
    pub object: Option<usize>,
    /// The model unit the file names (a Rhino .3dm's unit system), if any.
    #[serde(default)]
    pub units: Option<crate::units::Units>,
}

/// One object of a file holding several (a Rhino .3dm: a NURBS surface or a mesh).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FileObject {
    pub name: String,
    /// "surface" or "mesh".
    pub kind: String,
    pub summary: String,
}

/// The summary a finished stage returns (bulk data arrives as snapshot fields).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum StageResult {
    Curvature(CurvatureSummary),
    StAdapted(Box<st_adapted::StAdaptedSummary>),
    StSupport(Box<st_support::StSupportSummary>),
    Sq(Box<sq::SqSummary>),
}

/// Worker to main thread.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum FromWorker {
    /// The worker's wasm is initialised and waits for messages.
    Ready,
    /// A reference surface is loaded; its geometry arrives in the snapshot that follows.
    Loaded(ReferenceInfo),
    Progress(StageProgress),
    /// A snapshot: the stage's geometry and per-vertex data as fields.
    Snapshot {
        stage: StageId,
        iteration: u32,
        fields: Vec<FieldHeader>,
    },
    /// Files for download (fields of raw bytes named by file name), with their MIME types.
    Files {
        stage: StageId,
        fields: Vec<FieldHeader>,
        mime: Vec<String>,
    },
    Finished {
        stage: StageId,
        result: StageResult,
        elapsed_ms: f64,
    },
    Cancelled {
        stage: StageId,
    },
    /// An error a user can act on. The previous design stays loaded. `remesh_to`: the method
    /// refused its input's size and asks for a remesh to about this many faces first.
    Error {
        message: String,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        remesh_to: Option<usize>,
    },
}

/// A message encoded for transport: JSON header plus binary bodies in field order.
#[derive(Clone, Debug, PartialEq)]
pub struct Envelope {
    pub json: String,
    pub bodies: Vec<Vec<u8>>,
}

/// Encodes a message from the worker with its fields (the header lists them).
pub fn encode_from_worker(msg: &FromWorker, fields: &[Field]) -> Envelope {
    Envelope { json: serde_json::to_string(msg).expect("protocol types always serialize"), bodies: fields.iter().map(Field::to_bytes).collect() }
}

/// A message that cannot be decoded.
#[derive(Clone, Debug, PartialEq)]
pub enum ProtocolError {
    /// The JSON header is not a message.
    Json(String),
    /// A snapshot lists another number of fields than it carries buffers.
    FieldCount {
        listed: usize,
        carried: usize,
    },
    Field(FieldLengthError),
}

impl fmt::Display for ProtocolError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ProtocolError::Json(e) => write!(f, "bad message: {e}"),
            ProtocolError::FieldCount { listed, carried } => {
                write!(f, "snapshot lists {listed} fields but carries {carried} buffers")
            }
            ProtocolError::Field(e) => e.fmt(f),
        }
    }
}

impl std::error::Error for ProtocolError {}

/// Decodes a message from the worker; snapshot fields are rebuilt from the bodies.
pub fn decode_from_worker(env: &Envelope) -> Result<(FromWorker, Vec<Field>), ProtocolError> {
    let msg: FromWorker = serde_json::from_str(&env.json).map_err(|e| ProtocolError::Json(e.to_string()))?;
    let mut fields = Vec::new();
    if let FromWorker::Snapshot { fields: headers, .. } | FromWorker::Files { fields: headers, .. } = &msg {
        if headers.len() != env.bodies.len() {
            return Err(ProtocolError::FieldCount { listed: headers.len(), carried: env.bodies.len() });
        }
        for (h, b) in headers.iter().zip(&env.bodies) {
            fields.push(Field::from_bytes(h, b).map_err(ProtocolError::Field)?);
        }
    }
    Ok((msg, fields))
}

/// Encodes a message to the worker; a file load carries its bytes as the one body.
pub fn encode_to_worker(msg: &ToWorker, file_bytes: Option<Vec<u8>>) -> Envelope {
    Envelope { json: serde_json::to_string(msg).expect("protocol types always serialize"), bodies: file_bytes.into_iter().collect() }
}

pub fn decode_to_worker(env: &Envelope) -> Result<(ToWorker, Option<&[u8]>), ProtocolError> {
    let msg: ToWorker = serde_json::from_str(&env.json).map_err(|e| ProtocolError::Json(e.to_string()))?;
    Ok((msg, env.bodies.first().map(|b| b.as_slice())))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::fields::field;

    #[test]
    fn snapshot_round_trip() {
        let fields = vec![Field::f32(field::POSITIONS, 3, vec![0.0, 1.5, -2.0, 3.0, 4.0, 5.0]), Field::u32(field::TRIANGLES, 3, vec![0, 1, 0])];
        let msg = FromWorker::Snapshot { stage: StageId::Curvature, iteration: 3, fields: fields.iter().map(Field::header).collect() };
        let env = encode_from_worker(&msg, &fields);
        let (back, back_fields) = decode_from_worker(&env).unwrap();
        assert_eq!(back, msg);
        assert_eq!(back_fields, fields);
    }

    #[test]
    fn files_round_trip() {
        let fields = vec![Field::bytes("panels.glb", b"glTF\x02\x00\x00\x00abc".to_vec()), Field::bytes("panels.csv", b"id\n".to_vec())];
        let msg = FromWorker::Files {
            stage: StageId::StSupport,
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
        let msg = FromWorker::Snapshot { stage: StageId::Sq, iteration: 0, fields: fields.iter().map(Field::header).collect() };
        let mut env = encode_from_worker(&msg, &fields);
        env.bodies[0].pop();
        assert!(decode_from_worker(&env).is_err());
    }
}
