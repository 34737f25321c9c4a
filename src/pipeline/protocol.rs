//! The typed worker protocol, and the only file that lists the methods: [`methods!`] below
//! makes the wire's enums ([`MethodId`], [`MethodParams`], [`MethodSummary`]) and the dispatch
//! to each method's [`Method`] from one line per method. Headers travel as JSON (serde); bulk data
//! travels beside them as binary [`Field`]s, which the web layer moves as transferable
//! `ArrayBuffer`s.

use std::fmt;

use serde::{Deserialize, Serialize};

use super::fields::{Energy, Field, FieldHeader, FieldLengthError, Part, StepProgress};
use super::method::{same_result, Method, Request};
use super::stages;
use crate::congruence::central_spheres::{CurvatureSummary, JetParams};
use crate::export::Report;
use crate::geometry::mesh::topology::MeshStats;
use crate::import::Format;
use crate::panels::moulds::Fabrication;
use crate::params::{LinkFields, LinkReader, LinkWriter};
use crate::reference::bspline::BSplineInfo;
use crate::samples::Sample;

/// Runs a generic function of a method on the method a request names.
pub trait MethodVisitor {
    type Output;
    fn visit<M: OnWire>(self) -> Self::Output;
}

/// A method on the wire: its variants of the protocol's enums.
pub trait OnWire: Method {
    const ID: MethodId;
    fn unwrap_params(p: &MethodParams) -> Option<&Self::Params>;
    fn unwrap_params_mut(p: &mut MethodParams) -> Option<&mut Self::Params>;
    fn wrap_params(p: Self::Params) -> MethodParams;
    fn unwrap_summary(s: &MethodSummary) -> Option<&Self::Summary>;
    fn wrap_summary(s: Self::Summary) -> MethodSummary;
}

/// The methods: `Variant => its stage's Method`. A new method is one line here (the recipe in
/// ARCHITECTURE.md).
macro_rules! methods {
    ($($variant:ident => $stage:ty),* $(,)?) => {
        /// A method of the menu.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
        pub enum MethodId { $($variant),* }

        impl MethodId {
            pub const ALL: &'static [MethodId] = &[$(MethodId::$variant),*];

            /// The key of the wire, the design link, the command line and the report.
            pub fn key(self) -> &'static str {
                match self { $(MethodId::$variant => <$stage as Method>::KEY),* }
            }

            /// The method's name in the menu.
            pub fn label(self) -> &'static str {
                match self { $(MethodId::$variant => <$stage as Method>::LABEL),* }
            }

            /// The method's default parameters.
            pub fn default_params(self) -> MethodParams {
                match self { $(MethodId::$variant => MethodParams::$variant(Default::default())),* }
            }

            /// Runs `visitor` on the method.
            pub fn visit<V: MethodVisitor>(self, visitor: V) -> V::Output {
                match self { $(MethodId::$variant => visitor.visit::<$stage>()),* }
            }
        }

        /// A method's parameters.
        #[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
        pub enum MethodParams { $($variant(<$stage as Method>::Params)),* }

        impl MethodParams {
            pub fn method(&self) -> MethodId {
                match self { $(MethodParams::$variant(_) => MethodId::$variant),* }
            }
        }

        impl LinkFields for MethodParams {
            fn write_link(&self, link: &mut LinkWriter) {
                match self { $(MethodParams::$variant(p) => p.write_link(link)),* }
            }

            fn read_link(&mut self, link: &mut LinkReader) {
                match self { $(MethodParams::$variant(p) => p.read_link(link)),* }
            }
        }

        /// A method's summary of a finished run.
        #[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
        pub enum MethodSummary { $($variant(Box<<$stage as Method>::Summary>)),* }

        impl MethodSummary {
            pub fn method(&self) -> MethodId {
                match self { $(MethodSummary::$variant(_) => MethodId::$variant),* }
            }
        }

        $(
            impl OnWire for $stage {
                const ID: MethodId = MethodId::$variant;
                #[allow(unreachable_patterns)]
                fn unwrap_params(p: &MethodParams) -> Option<&Self::Params> {
                    match p { MethodParams::$variant(x) => Some(x), _ => None }
                }
                #[allow(unreachable_patterns)]
                fn unwrap_params_mut(p: &mut MethodParams) -> Option<&mut Self::Params> {
                    match p { MethodParams::$variant(x) => Some(x), _ => None }
                }
                fn wrap_params(p: Self::Params) -> MethodParams {
                    MethodParams::$variant(p)
                }
                #[allow(unreachable_patterns)]
                fn unwrap_summary(s: &MethodSummary) -> Option<&Self::Summary> {
                    match s { MethodSummary::$variant(x) => Some(x), _ => None }
                }
                fn wrap_summary(s: Self::Summary) -> MethodSummary {
                    MethodSummary::$variant(Box::new(s))
                }
            }
        )*
    };
}

methods! {
    StAdapted => stages::st_adapted::StAdaptedStage,
    StSupport => stages::st_support::StSupportStage,
    Sq => stages::sq::SqStage,
}

/// Every method's warm-up ([`Method::warm_up`]), at worker start.
pub fn warm_up() -> Result<(), String> {
    struct WarmUp;
    impl MethodVisitor for WarmUp {
        type Output = Result<(), String>;
        fn visit<M: OnWire>(self) -> Result<(), String> {
            M::warm_up()
        }
    }
    MethodId::ALL.iter().try_for_each(|m| m.visit(WarmUp))
}

impl MethodSummary {
    /// The run's report.
    pub fn report(&self) -> &Report {
        struct Get<'a>(&'a MethodSummary);
        impl<'a> MethodVisitor for Get<'a> {
            type Output = &'a Report;
            fn visit<M: OnWire>(self) -> &'a Report {
                M::report(M::unwrap_summary(self.0).expect("the summary's own method"))
            }
        }
        self.method().visit(Get(self))
    }
}

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

/// What a message of the worker is about: the import, the reference's geometry, the curvature,
/// or a part of a method's stream. Written as its key ("st-support", "st.sizing").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum StageId {
    Import,
    /// The reference's display geometry.
    Reference,
    Curvature,
    Method(MethodId, Part),
}

impl StageId {
    /// A method's own stage.
    pub fn of(method: MethodId) -> StageId {
        StageId::Method(method, Part::Main)
    }

    /// The key on the wire ("st-support", "st.sizing", "sq.refused"), as [`fmt::Display`]
    /// writes it.
    pub fn key(self) -> String {
        self.to_string()
    }

    /// The stage of a key on the wire, read without building any key.
    pub fn from_key(key: &str) -> Option<StageId> {
        match key {
            "import" => return Some(StageId::Import),
            "reference" => return Some(StageId::Reference),
            "curvature" => return Some(StageId::Curvature),
            _ => {}
        }
        let (method, suffix) = match key.split_once('.') {
            Some((_, "")) => return None,
            Some(pair) => pair,
            None => (key, ""),
        };
        let method = MethodId::ALL.iter().copied().find(|m| m.key() == method)?;
        Part::ALL.into_iter().find(|p| p.suffix() == suffix).map(|part| StageId::Method(method, part))
    }

    /// The method the stage belongs to, if any.
    pub fn method(self) -> Option<MethodId> {
        match self {
            StageId::Method(m, _) => Some(m),
            _ => None,
        }
    }
}

impl fmt::Display for StageId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StageId::Import => f.write_str("import"),
            StageId::Reference => f.write_str("reference"),
            StageId::Curvature => f.write_str("curvature"),
            StageId::Method(m, Part::Main) => f.write_str(m.key()),
            StageId::Method(m, part) => write!(f, "{}.{}", m.key(), part.suffix()),
        }
    }
}

impl PartialEq<str> for StageId {
    fn eq(&self, other: &str) -> bool {
        StageId::from_key(other) == Some(*self)
    }
}

impl Serialize for StageId {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

impl<'de> Deserialize<'de> for StageId {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let key = String::deserialize(d)?;
        StageId::from_key(&key).ok_or_else(|| serde::de::Error::custom(format!("unknown stage '{key}'")))
    }
}

/// A stage's progress as the worker reports it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StageProgress {
    pub stage: StageId,
    /// The step within the stage, e.g. "absolute_sphere".
    #[serde(default)]
    pub detail: String,
    pub iteration: u32,
    /// Total iterations when known (0 when open-ended).
    pub total: u32,
    pub energies: Vec<Energy>,
    pub elapsed_ms: f64,
}

impl StageProgress {
    pub fn of(stage: StageId, p: StepProgress) -> Self {
        let StepProgress { detail, iteration, total, energies, elapsed_ms } = p;
        Self { stage, detail, iteration, total, energies, elapsed_ms }
    }
}

/// A method's request on the wire: its parameters, the fabrication settings and the jet fit.
pub type MethodRequest = Request<MethodParams>;

impl MethodRequest {
    pub fn method(&self) -> MethodId {
        self.params.method()
    }

    /// The request of method `M`, if it is `M`'s.
    pub fn for_method<M: OnWire>(&self) -> Option<Request<M::Params>> {
        M::unwrap_params(&self.params).map(|p| Request { params: p.clone(), fabrication: self.fabrication, jet: self.jet.clone() })
    }
}

/// A stage and its parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum StageRequest {
    /// Jet-fitted curvature and central spheres (Sec. 2.6).
    Curvature(JetParams),
    /// A method, with its panels and files.
    Method(Box<MethodRequest>),
}

impl StageRequest {
    /// A method's request with the default fabrication settings and jet fit.
    pub fn method<M: OnWire>(params: M::Params) -> StageRequest {
        StageRequest::Method(Box::new(Request::new(M::wrap_params(params))))
    }

    /// A method's request with `fabrication` (the curvature has none).
    pub fn with_fabrication(self, fabrication: Fabrication) -> StageRequest {
        match self {
            StageRequest::Method(r) => StageRequest::Method(Box::new(Request { fabrication, ..*r })),
            curvature => curvature,
        }
    }

    /// Whether `self` asks for the very result `earlier` made, with other moulds at most (a new
    /// δ, K or unit): then that result is exported again, not computed again.
    pub fn same_result_as(&self, earlier: &StageRequest) -> bool {
        struct Same<'a>(&'a MethodRequest, &'a MethodRequest);
        impl MethodVisitor for Same<'_> {
            type Output = bool;
            fn visit<M: OnWire>(self) -> bool {
                match (self.0.for_method::<M>(), self.1.for_method::<M>()) {
                    (Some(a), Some(b)) => same_result::<M>(&a, &b),
                    _ => false,
                }
            }
        }
        match (self, earlier) {
            (StageRequest::Method(a), StageRequest::Method(b)) => a.method().visit(Same(a, b)),
            _ => false,
        }
    }

    /// The stage's name on the wire.
    pub fn name(&self) -> StageId {
        match self {
            StageRequest::Curvature(_) => StageId::Curvature,
            StageRequest::Method(r) => StageId::of(r.method()),
        }
    }
}

/// The summary a finished stage returns (bulk data arrives as snapshot fields).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum StageResult {
    Curvature(CurvatureSummary),
    Method(MethodSummary),
}

impl StageResult {
    /// The method's report (None: the curvature).
    pub fn report(&self) -> Option<&Report> {
        match self {
            StageResult::Curvature(_) => None,
            StageResult::Method(s) => Some(s.report()),
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

/// What an object of a Rhino file is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ObjectKind {
    /// A NURBS surface (read as a B-spline reference).
    Surface,
    Mesh,
}

impl fmt::Display for ObjectKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ObjectKind::Surface => "surface",
            ObjectKind::Mesh => "mesh",
        })
    }
}

/// One object of a file holding several (a Rhino .3dm: a NURBS surface or a mesh).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FileObject {
    pub name: String,
    pub kind: ObjectKind,
    pub summary: String,
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
            stage: StageId::of(MethodId::StSupport),
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
            stage: StageId::Method(MethodId::Sq, Part::Refused),
            iteration: 0,
            fields: fields.iter().map(Field::header).collect(),
        };
        let mut env = encode_from_worker(&msg, &fields);
        env.bodies[0].pop();
        assert!(decode_from_worker(&env).is_err());
    }

    #[test]
    fn every_stage_reads_back_from_its_key() {
        let methods = MethodId::ALL.iter().flat_map(|&m| Part::ALL.map(|p| StageId::Method(m, p)));
        for stage in [StageId::Import, StageId::Reference, StageId::Curvature].into_iter().chain(methods) {
            assert_eq!(StageId::from_key(&stage.key()), Some(stage));
            let json = serde_json::to_string(&stage).unwrap();
            assert_eq!(serde_json::from_str::<StageId>(&json).unwrap(), stage, "{json}");
        }
        assert_eq!(StageId::of(MethodId::StSupport).key(), "st-support");
        assert_eq!(StageId::Method(MethodId::StAdapted, Part::Sizing).key(), "st.sizing");
        assert!(serde_json::from_str::<StageId>("\"st.bogus\"").is_err());
        for bad in ["st.", ".sizing", "sq.refused.x", "", "bogus"] {
            assert_eq!(StageId::from_key(bad), None, "{bad}");
        }
        assert!(StageId::Method(MethodId::Sq, Part::Refused) == *"sq.refused");
    }
}
