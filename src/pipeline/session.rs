//! The worker's state: at most one loaded reference, which survives failed loads and stages.
//! The worker (wasm), the tests and the CLI drive the same [`Session`] through an [`Outbox`].

use super::fields::{Field, Part, StepProgress};
use super::method::{reexport, run, same_result, Computed, Method, Request};
use super::panel_output::mesh_fields;
use super::protocol::{
    FileObject, FromWorker, MethodRequest, MethodSummary, MethodVisitor, ObjectKind, OnWire, ReferenceInfo, Source, StageId, StageProgress,
    StageRequest, StageResult, ToWorker,
};
use super::sink::Sink;
use super::stages::{curvature, StageError};
use crate::export::ExportFile;
use crate::geometry::bspline::BSplineSurface;
use crate::geometry::mesh::topology::Topology;
use crate::import::{import_file, Format, ImportError, ImportedFile};
use crate::progress::Clock;
use crate::reference::bspline::SplineReferenceError;
use crate::reference::Reference;
use crate::samples::Sample;
use crate::units::Units;

/// Where the session's messages go (the worker posts them to the main thread), and how it
/// learns of a cancel request.
pub trait Outbox {
    fn send(&mut self, msg: FromWorker, fields: Vec<Field>);
    /// Polled at every step boundary; true stops the running stage there.
    fn cancel_requested(&mut self) -> bool;
    /// Milliseconds from an arbitrary origin.
    fn now_ms(&self) -> f64;
}

/// A loaded reference surface and what the UI is told about it.
pub struct Loaded {
    pub surface: Reference,
    pub info: ReferenceInfo,
}

/// Why a file could not be loaded.
#[derive(Clone, Debug, PartialEq)]
pub enum LoadError {
    Import(ImportError),
    /// A B-spline surface that cannot be a reference (in file `file`).
    Spline {
        file: String,
        error: SplineReferenceError,
    },
}

impl std::fmt::Display for LoadError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LoadError::Import(e) => e.fmt(f),
            LoadError::Spline { file, error } => write!(f, "{file}: {error}"),
        }
    }
}

impl std::error::Error for LoadError {}

impl Loaded {
    pub fn from_sample(sample: Sample) -> Self {
        let source = Source::Sample(sample);
        match sample.bspline() {
            Some(s) => Self::of_bspline(source, None, s, Vec::new()).expect("the built-in B-spline samples are regular"),
            None => Self::of_mesh(source, None, Reference::from_triangles(sample.mesh()), Vec::new()),
        }
    }

    pub fn from_file(bytes: &[u8], name: &str) -> Result<Self, LoadError> {
        let source = Source::File(name.to_string());
        match import_file(bytes, name).map_err(LoadError::Import)? {
            ImportedFile::Mesh(imported) => {
                let surface = Reference::new(imported.surface());
                Ok(Self::of_mesh(source, Some(imported.format), surface, imported.notes))
            }
            ImportedFile::BSpline(b) => Self::of_bspline(source, Some(Format::BSplineJson), b.surface, b.notes)
                .map_err(|error| LoadError::Spline { file: name.rsplit(['/', '\\']).next().unwrap_or(name).to_string(), error }),
        }
    }

    fn of_mesh(source: Source, format: Option<Format>, surface: Reference, notes: Vec<String>) -> Self {
        let mesh = surface.mesh();
        let info = ReferenceInfo {
            source,
            format,
            stats: surface.topology().stats(mesh),
            bbox_diagonal: surface.diagonal(),
            notes,
            bspline: None,
            objects: Vec::new(),
            object: None,
            units: None,
        };
        Self { surface, info }
    }

    fn of_bspline(source: Source, format: Option<Format>, spline: BSplineSurface, notes: Vec<String>) -> Result<Self, SplineReferenceError> {
        let surface = Reference::from_bspline(spline)?;
        let mut loaded = Self::of_mesh(source, format, surface, notes);
        loaded.info.bspline = loaded.surface.spline_reference().map(|s| s.info());
        Ok(loaded)
    }

    /// Positions, triangles, normals and the edges of the faces as loaded, for display.
    pub(crate) fn geometry_fields(&self) -> Vec<Field> {
        let edges = Topology::new(self.surface.surface()).edges().to_vec();
        mesh_fields(self.surface.mesh(), &edges)
    }
}

/// The session.
#[derive(Default)]
pub struct Session {
    pub reference: Option<Loaded>,
    /// The objects of the multi-object file loaded last, with their texts (B-spline JSON or OBJ).
    objects: Option<FileObjects>,
    /// Times the stages (none by default: timings read 0).
    pub clock: Clock,
    /// The last method's result on the loaded reference, for new moulds without a new run.
    last: Option<Box<dyn Kept>>,
}

/// A method's result as the session keeps it: its request, its summary and the result, behind
/// the one method seam.
trait Kept {
    /// Whether `request` asks for this very result with other moulds at most.
    fn same_result(&self, request: &MethodRequest) -> bool;
    /// Exports the result again for `request` (other moulds); returns the new summary.
    fn reexport(&mut self, reference: &Reference, request: &MethodRequest, clock: Clock, sink: &mut dyn Sink) -> MethodSummary;
}

struct KeptResult<M: Method> {
    request: Request<M::Params>,
    summary: M::Summary,
    computed: Computed<M::Result>,
}

impl<M: OnWire> Kept for KeptResult<M> {
    fn same_result(&self, request: &MethodRequest) -> bool {
        request.for_method::<M>().is_some_and(|r| same_result::<M>(&r, &self.request))
    }

    fn reexport(&mut self, reference: &Reference, request: &MethodRequest, clock: Clock, sink: &mut dyn Sink) -> MethodSummary {
        self.request = request.for_method::<M>().expect("same_result compares requests of one method");
        *M::report_mut(&mut self.summary) = reexport::<M>(reference, &self.computed, &self.request, clock, sink);
        M::wrap_summary(self.summary.clone())
    }
}

/// Runs the method a request names and keeps its result.
struct RunMethod<'a> {
    reference: &'a Reference,
    request: &'a MethodRequest,
    clock: Clock,
    sink: &'a mut dyn Sink,
}

impl MethodVisitor for RunMethod<'_> {
    type Output = Result<(MethodSummary, Box<dyn Kept>), StageError>;

    fn visit<M: OnWire>(self) -> Self::Output {
        let request = self.request.for_method::<M>().expect("the request's own method");
        let (summary, computed) = run::<M>(self.reference, &request, self.clock, self.sink)?;
        Ok((M::wrap_summary(summary.clone()), Box::new(KeptResult::<M> { request, summary, computed })))
    }
}

/// A file of several objects and their texts.
struct FileObjects {
    file: String,
    objects: Vec<FileObject>,
    texts: Vec<String>,
    notes: Vec<String>,
    units: Option<Units>,
}

/// A stage's [`Sink`] over the session's [`Outbox`]: names the stage in every message.
struct Messages<'a> {
    out: &'a mut dyn Outbox,
    stage: StageId,
}

impl Messages<'_> {
    /// The stage of a part of this stage's stream.
    fn part(&self, part: Part) -> StageId {
        match self.stage {
            StageId::Method(m, _) => StageId::Method(m, part),
            stage => stage,
        }
    }
}

impl Sink for Messages<'_> {
    fn progress(&mut self, progress: StepProgress) {
        self.out.send(FromWorker::Progress(StageProgress::of(self.stage, progress)), Vec::new());
    }

    fn snapshot(&mut self, part: Part, iteration: u32, fields: Vec<Field>) {
        self.out.send(snapshot(self.part(part), iteration, &fields), fields);
    }

    fn files(&mut self, files: Vec<ExportFile>) {
        let mime = files.iter().map(|f| f.mime.clone()).collect();
        let fields: Vec<Field> = files.into_iter().map(|f| Field::bytes(&f.name, f.bytes)).collect();
        let headers = fields.iter().map(Field::header).collect();
        self.out.send(FromWorker::Files { stage: self.stage, fields: headers, mime }, fields);
    }

    fn cancel_requested(&mut self) -> bool {
        self.out.cancel_requested()
    }

    fn now_ms(&self) -> f64 {
        self.out.now_ms()
    }
}

impl Session {
    pub fn new() -> Self {
        Self::default()
    }

    /// Handles one message. `bytes` is the file body of a `LoadFile`.
    pub fn handle(&mut self, msg: ToWorker, bytes: Option<&[u8]>, out: &mut dyn Outbox) {
        match msg {
            ToWorker::LoadSample(sample) => {
                self.objects = None;
                self.install(Loaded::from_sample(sample), out)
            }
            ToWorker::PickObject(k) => self.load_object(k, out),
            ToWorker::LoadFile { name } => match bytes {
                None => out.send(FromWorker::Error { message: format!("{name}: no file data arrived"), remesh_to: None }, vec![]),
                Some(b) => match Loaded::from_file(b, &name) {
                    Ok(r) => {
                        self.objects = None;
                        self.install(r, out)
                    }
                    Err(e) => out.send(FromWorker::Error { message: e.to_string(), remesh_to: None }, vec![]),
                },
            },
            ToWorker::Run(stage) => self.run(*stage, out),
            // A cancel that arrives between stages has nothing to stop.
            ToWorker::Cancel => {}
            ToWorker::Crash => panic!("crash requested for diagnostics"),
        }
    }

    /// Loads a file of several objects, converted outside (a Rhino .3dm, by rhino3dm.js in the
    /// worker): `texts[k]` is object k as B-spline JSON or OBJ. The first surface is loaded (else
    /// the first object); [`ToWorker::PickObject`] loads another.
    /// `units`: the file's model unit, when it names one of [`Units`].
    pub fn load_objects(
        &mut self,
        file: &str,
        objects: Vec<FileObject>,
        texts: Vec<String>,
        notes: Vec<String>,
        units: Option<Units>,
        out: &mut dyn Outbox,
    ) {
        let file = crate::text::clip(file, 120);
        if objects.is_empty() || objects.len() != texts.len() {
            out.send(FromWorker::Error { message: format!("{file}: no NURBS surface or mesh in it"), remesh_to: None }, vec![]);
            return;
        }
        let first = objects.iter().position(|o| o.kind == ObjectKind::Surface).unwrap_or(0);
        self.objects = Some(FileObjects { file, objects, texts, notes, units });
        self.load_object(first, out);
    }

    fn load_object(&mut self, k: usize, out: &mut dyn Outbox) {
        let Some(f) = self.objects.as_ref() else {
            out.send(FromWorker::Error { message: "no file with several objects is loaded".into(), remesh_to: None }, vec![]);
            return;
        };
        let Some(object) = f.objects.get(k) else {
            out.send(FromWorker::Error { message: format!("{}: no object {k}", f.file), remesh_to: None }, vec![]);
            return;
        };
        let name = format!("{} › {}", f.file, crate::text::clip(&object.name, 80));
        match Loaded::from_file(f.texts[k].as_bytes(), &name) {
            Ok(mut r) => {
                r.info.objects = f.objects.clone();
                r.info.object = Some(k);
                r.info.units = f.units;
                r.info.notes.extend(f.notes.iter().map(|n| crate::text::printable(n)));
                self.install(r, out)
            }
            Err(e) => out.send(FromWorker::Error { message: e.to_string(), remesh_to: None }, vec![]),
        }
    }

    fn install(&mut self, r: Loaded, out: &mut dyn Outbox) {
        self.last = None;
        out.send(FromWorker::Loaded(r.info.clone()), vec![]);
        let fields = r.geometry_fields();
        out.send(snapshot(StageId::Reference, 0, &fields), fields);
        self.reference = Some(r);
    }

    fn run(&mut self, stage: StageRequest, out: &mut dyn Outbox) {
        let name = stage.name();
        let Some(loaded) = self.reference.as_ref() else {
            out.send(FromWorker::Error { message: "Load a reference surface first.".into(), remesh_to: None }, vec![]);
            return;
        };
        let reference = &loaded.surface;
        let start = out.now_ms();
        let clock = self.clock;
        let mut sink = Messages { out: &mut *out, stage: name };
        let result = match &stage {
            StageRequest::Curvature(p) => curvature::run(reference, p, &mut sink).map(StageResult::Curvature),
            // New moulds for the last result: exported again, in milliseconds.
            StageRequest::Method(request) if self.last.as_ref().is_some_and(|l| l.same_result(request)) => {
                let last = self.last.as_mut().expect("checked above");
                Ok(StageResult::Method(last.reexport(reference, request, clock, &mut sink)))
            }
            StageRequest::Method(request) => {
                request.method().visit(RunMethod { reference, request, clock, sink: &mut sink }).map(|(summary, kept)| {
                    self.last = Some(kept);
                    StageResult::Method(summary)
                })
            }
        };
        match result {
            Ok(result) => {
                let elapsed_ms = out.now_ms() - start;
                out.send(FromWorker::Finished { stage: name, result, elapsed_ms }, vec![]);
            }
            Err(StageError::Cancelled) => out.send(FromWorker::Cancelled { stage: name }, vec![]),
            Err(e) => out.send(FromWorker::Error { message: e.to_string(), remesh_to: e.remesh_to() }, vec![]),
        }
    }
}

/// The snapshot header for `fields`.
pub fn snapshot(stage: StageId, iteration: u32, fields: &[Field]) -> FromWorker {
    FromWorker::Snapshot { stage, iteration, fields: fields.iter().map(Field::header).collect() }
}
