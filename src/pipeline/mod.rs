//! The pipeline: a loaded reference surface and the stages that run on it. It knows nothing of
//! the browser; the worker (wasm) and the CLI (native) both drive a [`Session`] through a [`Sink`].

pub mod protocol;
pub mod st_angle;
pub mod st_support;

use crate::curvature::{jet_fit, CurvatureField, JetParams};
use crate::import::{import_mesh, Imported};
use crate::mesh::{Topology, TriMesh};
use crate::samples::Sample;
use crate::st_support::Clock;
use protocol::{field, Field, FromWorker, Progress, ReferenceInfo, Source, StageRequest, StageResult, ToWorker};

/// Where a stage streams its messages, and how it learns of a cancel request.
pub trait Sink {
    fn send(&mut self, msg: FromWorker, fields: Vec<Field>);
    /// Polled once per iteration; true stops the stage at the next iteration boundary.
    fn cancel_requested(&mut self) -> bool;
    /// Milliseconds from an arbitrary origin.
    fn now_ms(&self) -> f64;
}

/// A reference surface with its derived data.
pub struct Reference {
    pub mesh: TriMesh,
    pub topology: Topology,
    pub info: ReferenceInfo,
    pub curvature: Option<CurvatureField>,
    /// The parameters `curvature` was computed with.
    pub curvature_params: Option<JetParams>,
}

impl Reference {
    pub fn from_sample(sample: Sample) -> Self {
        let mesh = sample.mesh();
        let topology = Topology::new(&mesh);
        let info = ReferenceInfo {
            source: Source::Sample(sample),
            format: None,
            stats: topology.stats(&mesh),
            bbox_diagonal: mesh.bbox_diagonal(),
            notes: Vec::new(),
        };
        Self { mesh, topology, info, curvature: None, curvature_params: None }
    }

    pub fn from_file(bytes: &[u8], name: &str) -> Result<Self, String> {
        let Imported { mesh, stats, format, notes, .. } =
            import_mesh(bytes, name).map_err(|e| e.to_string())?;
        let topology = Topology::new(&mesh);
        let info = ReferenceInfo {
            source: Source::File(name.to_string()),
            format: Some(format),
            stats,
            bbox_diagonal: mesh.bbox_diagonal(),
            notes,
        };
        Ok(Self { mesh, topology, info, curvature: None, curvature_params: None })
    }

    /// Positions, triangles and normals for display.
    pub fn geometry_fields(&self) -> Vec<Field> {
        vec![
            Field::f32(field::POSITIONS, 3, flatten(self.mesh.positions.iter().map(|p| p.to_array()))),
            Field::u32(field::TRIANGLES, 3, self.mesh.triangles.iter().flatten().copied().collect()),
            Field::f32(field::NORMALS, 3, flatten(self.mesh.vertex_normals().iter().map(|n| n.to_array()))),
            Field::u32(field::EDGES, 2, self.topology.edges().iter().flatten().copied().collect()),
        ]
    }

    /// Runs jet fitting, streaming progress; `None` when cancelled.
    pub fn run_curvature(&mut self, params: &JetParams, sink: &mut dyn Sink) -> Option<&CurvatureField> {
        let start = sink.now_ms();
        let mut progress = |done: usize, total: usize| report_progress(sink, "curvature", "", done, total, start);
        self.curvature = jet_fit(&self.mesh, &self.topology, params, &mut progress);
        self.curvature_params = self.curvature.as_ref().map(|_| params.clone());
        self.curvature.as_ref()
    }
}

/// Per-vertex curvature fields for the viewer's colour maps and central spheres.
pub fn curvature_fields(c: &CurvatureField) -> Vec<Field> {
    let v = &c.vertices;
    vec![
        Field::f32(field::MEAN_CURVATURE, 1, v.iter().map(|x| x.mean as f32).collect()),
        Field::f32(field::K1, 1, v.iter().map(|x| x.k1 as f32).collect()),
        Field::f32(field::K2, 1, v.iter().map(|x| x.k2 as f32).collect()),
        Field::f32(field::K1_MINUS_K2, 1, v.iter().map(|x| (x.k1 - x.k2).abs() as f32).collect()),
        Field::f32(
            field::CENTRAL_SPHERES,
            5,
            c.central_spheres.iter().flat_map(|s| [s.a, s.b.x, s.b.y, s.b.z, s.c]).map(|x| x as f32).collect(),
        ),
        Field::u32(field::BOUNDARY, 1, c.boundary.iter().map(|&b| b as u32).collect()),
    ]
}

fn flatten(it: impl Iterator<Item = [f64; 3]>) -> Vec<f32> {
    it.flat_map(|a| a.map(|x| x as f32)).collect()
}

/// The worker's state: at most one loaded reference, which survives failed loads and stages.
#[derive(Default)]
pub struct Session {
    pub reference: Option<Reference>,
    /// Times the stages (none by default: timings read 0).
    pub clock: Clock,
}

impl Session {
    pub fn new() -> Self {
        Self::default()
    }

    /// Handles one message. `bytes` is the file body of a `LoadFile`.
    pub fn handle(&mut self, msg: ToWorker, bytes: Option<&[u8]>, sink: &mut dyn Sink) {
        match msg {
            ToWorker::LoadSample(sample) => self.install(Reference::from_sample(sample), sink),
            ToWorker::LoadFile { name } => match bytes {
                None => sink.send(FromWorker::Error { message: format!("{name}: no file data arrived") }, vec![]),
                Some(b) => match Reference::from_file(b, &name) {
                    Ok(r) => self.install(r, sink),
                    Err(message) => sink.send(FromWorker::Error { message }, vec![]),
                },
            },
            ToWorker::Run(stage) => self.run(stage, sink),
            // A cancel that arrives between stages has nothing to stop.
            ToWorker::Cancel => {}
            ToWorker::Crash => panic!("crash requested for diagnostics"),
        }
    }

    fn install(&mut self, r: Reference, sink: &mut dyn Sink) {
        sink.send(FromWorker::Loaded(r.info.clone()), vec![]);
        let fields = r.geometry_fields();
        sink.send(snapshot("reference", 0, &fields), fields);
        self.reference = Some(r);
    }

    fn run(&mut self, stage: StageRequest, sink: &mut dyn Sink) {
        let name = stage.name().to_string();
        let Some(reference) = self.reference.as_mut() else {
            sink.send(FromWorker::Error { message: "Load a reference surface first.".into() }, vec![]);
            return;
        };
        let start = sink.now_ms();
        match stage {
            StageRequest::Curvature(params) => match reference.run_curvature(&params, sink) {
                None => sink.send(FromWorker::Cancelled { stage: name }, vec![]),
                Some(c) => {
                    let fields = curvature_fields(c);
                    let summary = c.summary.clone();
                    sink.send(snapshot(&name, 1, &fields), fields);
                    let elapsed_ms = sink.now_ms() - start;
                    sink.send(FromWorker::Finished { stage: name, result: StageResult::Curvature(summary), elapsed_ms }, vec![]);
                }
            },
            StageRequest::StSupport(req) => {
                if reference.curvature_params.as_ref() != Some(&req.jet) && reference.run_curvature(&req.jet, sink).is_none() {
                    return sink.send(FromWorker::Cancelled { stage: name }, vec![]);
                }
                let Some(field) = reference.curvature.as_ref() else { return };
                let mut progress =
                    |detail: &str, done: usize, total: usize| report_progress(sink, "st-support", detail, done, total, start);
                match st_support::run(&reference.mesh, &reference.topology, field, &req, self.clock, &mut progress) {
                    Err(e) if e == "cancelled" => sink.send(FromWorker::Cancelled { stage: name }, vec![]),
                    Err(message) => sink.send(FromWorker::Error { message }, vec![]),
                    Ok(out) => {
                        let fields = st_support::display_fields(&out);
                        sink.send(snapshot(&name, 1, &fields), fields);
                        send_files(sink, &name, out.files);
                        let elapsed_ms = sink.now_ms() - start;
                        let result = StageResult::StSupport(Box::new(out.summary));
                        sink.send(FromWorker::Finished { stage: name, result, elapsed_ms }, vec![]);
                    }
                }
            }
            StageRequest::St(req) => match st_angle::run(&reference.mesh, &req, self.clock, sink) {
                Err(e) if e == "cancelled" => sink.send(FromWorker::Cancelled { stage: name }, vec![]),
                Err(message) => sink.send(FromWorker::Error { message }, vec![]),
                Ok((_, summary, files)) => {
                    send_files(sink, &name, files);
                    let elapsed_ms = sink.now_ms() - start;
                    let result = StageResult::St(Box::new(summary));
                    sink.send(FromWorker::Finished { stage: name, result, elapsed_ms }, vec![]);
                }
            },
        }
    }
}

/// Offers `files` for download, as byte fields with their MIME types.
fn send_files(sink: &mut dyn Sink, stage: &str, files: Vec<st_support::ExportFile>) {
    let mime = files.iter().map(|f| f.mime.clone()).collect();
    let fields: Vec<Field> = files.into_iter().map(|f| Field::bytes(&f.name, f.bytes)).collect();
    let headers = fields.iter().map(Field::header).collect();
    sink.send(FromWorker::Files { stage: stage.into(), fields: headers, mime }, fields);
}

/// Sends a progress message; returns false when the stage should stop (cancel requested).
fn report_progress(sink: &mut dyn Sink, stage: &str, detail: &str, done: usize, total: usize, start: f64) -> bool {
    let elapsed_ms = sink.now_ms() - start;
    let progress = Progress {
        stage: stage.into(),
        detail: detail.into(),
        iteration: done as u32,
        total: total as u32,
        energies: Vec::new(),
        elapsed_ms,
    };
    sink.send(FromWorker::Progress(progress), Vec::new());
    !sink.cancel_requested()
}

/// The snapshot header for `fields`.
pub fn snapshot(stage: &str, iteration: u32, fields: &[Field]) -> FromWorker {
    FromWorker::Snapshot { stage: stage.into(), iteration, fields: fields.iter().map(Field::header).collect() }
}
