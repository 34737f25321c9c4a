//! The main-thread app: an immediate-mode egui UI over the wgpu viewport. It never computes
//! geometry; it sends the design to the worker and draws the snapshots that come back.

use std::cell::RefCell;
use std::rc::Rc;
use std::sync::Arc;

use egui::{Color32, Pos2, Rect, RichText, Sense, Vec2};
use glam::{Mat4, Vec3};
use wasm_bindgen::prelude::*;

use super::colormap;
use super::viewer::{ColorMap, Geometry, Layer, MeshData, OrbitCamera, ScalarData, Style, ViewerFrame, ViewerResources};
use super::worker_client::{Incoming, WorkerClient};
use crate::curvature::CurvatureSummary;
use crate::design_link::{CameraState, ColorBy, Design, Method, Reference, Shading, SizingKind};
use crate::pipeline::st_angle::{self as st_stage, StRequest, StSummary};
use crate::pipeline::st_support::{fields as stf, StSupportRequest, StSupportSummary};
use crate::st_angle::StVariant;
use crate::absolute_sphere::Histogram;
use crate::sphere_mesh::AbsoluteSphere;
use crate::pipeline::protocol::{field, find, Field, FieldData, FromWorker, Progress, ReferenceInfo, Source, StageRequest, StageResult, ToWorker};
use crate::samples::Sample;

/// How many frames' `ui` times are kept for the state's percentiles.
const UI_TIMES: usize = 120;

/// Milliseconds from the page's time origin.
fn now_ms() -> f64 {
    web_sys::window().and_then(|w| w.performance()).map_or(0.0, |p| p.now())
}

/// The q-quantile (nearest rank) of `values`; 0 when empty.
fn percentile(values: &std::collections::VecDeque<f64>, q: f64) -> f64 {
    let mut v: Vec<f64> = values.iter().copied().collect();
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    v[((q * v.len() as f64).ceil() as usize).clamp(1, v.len()) - 1]
}

/// Viewport background, also reported to tests.
pub const CLEAR_COLOR: Color32 = Color32::from_rgb(28, 30, 36);

struct Loaded {
    info: ReferenceInfo,
    mesh: Arc<MeshData>,
    center: Vec3,
    radius: f32,
    curvature: Option<CurvatureView>,
    st: Option<StView>,
    angle: Option<AngleView>,
}

/// The "ST, adapted face size" run as it streams in: sizing field, remeshed triangulation,
/// the latest panels and the energy of every iteration.
#[derive(Default)]
struct AngleView {
    /// g at the reference vertices.
    sizing: Option<Vec<f32>>,
    remeshed: Option<Arc<MeshData>>,
    panels: Option<Arc<MeshData>>,
    /// Iteration of the panels shown, and how many panel snapshots arrived.
    panel_iteration: u32,
    panel_snapshots: u32,
    /// (iteration, optimizer stage, total energy).
    energy: Vec<(u32, String, f64)>,
    summary: Option<StSummary>,
}

/// The ST-with-support-structure result as display meshes.
struct StView {
    panels: Arc<MeshData>,
    support: Arc<MeshData>,
    axes: Arc<MeshData>,
    envelope: Option<Arc<MeshData>>,
    summary: Option<StSupportSummary>,
}

/// A display mesh from snapshot fields (missing fields are empty).
fn mesh_from_fields(fields: &[Field], generation: &mut u64, names: [&str; 4]) -> Arc<MeshData> {
    let f = |n| find(fields, n).and_then(Field::as_f32).map(<[f32]>::to_vec).unwrap_or_default();
    let u = |n| find(fields, n).and_then(Field::as_u32).map(<[u32]>::to_vec).unwrap_or_default();
    *generation += 1;
    Arc::new(MeshData { generation: *generation, positions: f(names[0]), normals: f(names[1]), triangles: u(names[2]), edges: u(names[3]) })
}

const PANEL_FIELDS: [&str; 4] = [stf::PANEL_POSITIONS, stf::PANEL_NORMALS, stf::PANEL_TRIANGLES, stf::PANEL_EDGES];
const MESH_FIELDS: [&str; 4] = [field::POSITIONS, field::NORMALS, field::TRIANGLES, field::EDGES];

impl StView {
    fn from_fields(fields: &[Field], generation: &mut u64) -> Self {
        let f = |n| find(fields, n).and_then(Field::as_f32).map(<[f32]>::to_vec).unwrap_or_default();
        let u = |n| find(fields, n).and_then(Field::as_u32).map(<[u32]>::to_vec).unwrap_or_default();
        let env_pos = f(stf::ENVELOPE_POSITIONS);
        let panels = mesh_from_fields(fields, generation, PANEL_FIELDS);
        let mut mesh = |positions: Vec<f32>, normals: Vec<f32>, triangles: Vec<u32>, edges: Vec<u32>| {
            *generation += 1;
            Arc::new(MeshData { generation: *generation, positions, normals, triangles, edges })
        };
        Self {
            panels,
            support: mesh(f(stf::SUPPORT_POSITIONS), Vec::new(), u(stf::SUPPORT_TRIANGLES), Vec::new()),
            axes: mesh(f(stf::AXES_POSITIONS), Vec::new(), Vec::new(), u(stf::AXES_LINES)),
            envelope: (!env_pos.is_empty())
                .then(|| mesh(env_pos, Vec::new(), u(stf::ENVELOPE_TRIANGLES), Vec::new())),
            summary: None,
        }
    }
}

struct CurvatureView {
    fields: Vec<Field>,
    summary: Option<CurvatureSummary>,
}

/// A file the worker produced, offered for download.
struct Download {
    name: String,
    mime: String,
    bytes: Vec<u8>,
}

struct Busy {
    stage: String,
    progress: Option<Progress>,
}

/// The colour map currently uploaded.
struct ScalarView {
    color: ColorBy,
    data: Arc<ScalarData>,
    range: (f32, f32),
    diverging: bool,
}

pub struct App {
    design: Design,
    notices: Vec<String>,
    error: Option<String>,
    worker: Option<WorkerClient>,
    loaded: Option<Loaded>,
    /// The file behind the loaded design, kept to restore it in a fresh worker.
    file: Option<web_sys::File>,
    /// A file sent to the worker but not yet confirmed as loaded.
    file_in_flight: Option<web_sys::File>,
    busy: Option<Busy>,
    downloads: Vec<Download>,
    /// Method parameters changed while a slider is held: rerun on release.
    st_dirty: bool,
    show_reference: bool,
    show_envelope: bool,
    show_remeshed: bool,
    /// A fresh worker is being given the current design back: keep the view and the message.
    restoring: bool,
    camera: OrbitCamera,
    camera_from_link: Option<CameraState>,
    selected: Option<usize>,
    scalars: Option<ScalarView>,
    generation: u64,
    backend: String,
    frames: u64,
    /// Main-thread time of the last frames' `ui` (ms), newest last.
    ui_ms: std::collections::VecDeque<f64>,
    drawn: bool,
    viewport: Rect,
    last_fragment: String,
    last_state: String,
    picked_files: Rc<RefCell<Vec<web_sys::File>>>,
    crash_requests: Rc<RefCell<u32>>,
    _crash_listener: Closure<dyn FnMut()>,
    cancel_requests: Rc<RefCell<u32>>,
    _cancel_listener: Closure<dyn FnMut()>,
    download_requests: Rc<RefCell<Vec<String>>>,
    _download_listener: Option<Closure<dyn FnMut(web_sys::CustomEvent)>>,
    file_input: Option<web_sys::HtmlInputElement>,
    _file_input_closure: Option<Closure<dyn FnMut()>>,
}

impl App {
    pub fn new(cc: &eframe::CreationContext<'_>) -> Self {
        let mut backend = String::new();
        if let Some(rs) = cc.wgpu_render_state.as_ref() {
            rs.renderer.write().callback_resources.insert(ViewerResources::new(&rs.device, rs.target_format));
            backend = match rs.adapter.get_info().backend {
                egui_wgpu::wgpu::Backend::BrowserWebGpu => "WebGPU".into(),
                egui_wgpu::wgpu::Backend::Gl => "WebGL2".into(),
                other => format!("{other:?}"),
            };
        }
        cc.egui_ctx.set_theme(egui::Theme::Dark);
        let fragment = location_hash();
        let (design, notices) = Design::from_fragment(&fragment);
        let ctx = cc.egui_ctx.clone();
        let repaint: Rc<dyn Fn()> = Rc::new(move || ctx.request_repaint());
        let (worker, error) = match WorkerClient::spawn(repaint) {
            Ok(w) => (Some(w), None),
            Err(e) => (None, Some(e)),
        };
        let picked_files = Rc::new(RefCell::new(Vec::new()));
        let (file_input, closure) = make_file_input(picked_files.clone(), cc.egui_ctx.clone());
        // Diagnostics: `window.dispatchEvent(new Event('sf-crash-worker'))` makes the worker panic.
        let (crash_requests, crash_listener) = count_events("sf-crash-worker", &cc.egui_ctx);
        // Automation: `new Event('sf-cancel')` presses Cancel.
        let (cancel_requests, cancel_listener) = count_events("sf-cancel", &cc.egui_ctx);
        // Automation: `new CustomEvent('sf-download', {detail: 'panels.glb'})` saves that file.
        let download_requests = Rc::new(RefCell::new(Vec::new()));
        let download_listener = {
            let (queue, ctx) = (download_requests.clone(), cc.egui_ctx.clone());
            let c = Closure::<dyn FnMut(web_sys::CustomEvent)>::new(move |ev: web_sys::CustomEvent| {
                if let Some(name) = ev.detail().as_string() {
                    queue.borrow_mut().push(name);
                    ctx.request_repaint();
                }
            });
            web_sys::window().map(|w| w.add_event_listener_with_callback("sf-download", c.as_ref().unchecked_ref()));
            Some(c)
        };
        let mut app = Self {
            camera_from_link: design.camera,
            design,
            notices,
            error,
            worker,
            loaded: None,
            file: None,
            file_in_flight: None,
            busy: None,
            downloads: Vec::new(),
            st_dirty: false,
            show_reference: false,
            show_envelope: false,
            show_remeshed: false,
            restoring: false,
            camera: OrbitCamera::framing(Vec3::ZERO, 1.0),
            selected: None,
            scalars: None,
            generation: 0,
            backend,
            frames: 0,
            ui_ms: std::collections::VecDeque::with_capacity(UI_TIMES),
            drawn: false,
            viewport: Rect::NOTHING,
            last_fragment: fragment,
            last_state: String::new(),
            picked_files,
            crash_requests,
            _crash_listener: crash_listener,
            cancel_requests,
            _cancel_listener: cancel_listener,
            download_requests,
            _download_listener: download_listener,
            file_input,
            _file_input_closure: closure,
        };
        app.load_design_reference();
        app
    }

    /// Sends the design's reference surface to the worker (own files need the file itself).
    fn load_design_reference(&mut self) {
        let sample = match &self.design.reference {
            Reference::Sample(s) => *s,
            Reference::OwnFile(_) => match self.file.clone() {
                Some(f) => return self.load_file(f),
                // The link names a file we do not have: open on the default sample meanwhile.
                None => Sample::Dome,
            },
        };
        self.send(&ToWorker::LoadSample(sample), None);
    }

    fn load_file(&mut self, file: web_sys::File) {
        self.send(&ToWorker::LoadFile { name: file.name() }, Some(&file));
        self.file_in_flight = Some(file);
        self.busy = Some(Busy { stage: "import".into(), progress: None });
    }

    fn send(&mut self, msg: &ToWorker, file: Option<&web_sys::File>) {
        match &self.worker {
            Some(w) => w.send(msg, file),
            None => self.error = Some("The pipeline worker is not running; reload the page.".into()),
        }
    }

    fn run_method(&mut self) {
        if self.loaded.is_none() {
            return;
        }
        if self.busy.as_ref().is_some_and(|b| b.stage != "import") {
            self.cancel();
        }
        // Curvature first (its colour maps and central spheres); methods reuse it in the worker.
        let mut stages = vec![StageRequest::Curvature(self.design.jet.clone())];
        match self.design.method {
            Method::Curvature => {}
            Method::StSupport => {
                let st = self.design.st;
                stages.push(StageRequest::StSupport(StSupportRequest {
                    optimize_radius: st.optimize_radius,
                    support_depth: st.support_depth,
                    axis_length: st.axis_length,
                    radius_tolerance: st.radius_tolerance,
                    remesh: st.remesh.to_sizing(),
                    jet: self.design.jet.clone(),
                }));
            }
            Method::St => {
                let a = self.design.st_angle;
                stages.push(StageRequest::St(StRequest {
                    sizing: a.sizing.to_sizing(),
                    variant: a.variant,
                    radius_tolerance: self.design.st.radius_tolerance,
                    jet: self.design.jet.clone(),
                }));
            }
        }
        if let Some(l) = self.loaded.as_mut() {
            l.st = None;
            l.angle = (self.design.method == Method::St).then(AngleView::default);
        }
        if self.design.color == ColorBy::Sizing {
            self.scalars = None;
        }
        self.downloads.clear();
        let last = stages.last().map(|s| s.name().to_string()).unwrap_or_default();
        self.busy = Some(Busy { stage: last, progress: None });
        for stage in stages {
            self.send(&ToWorker::Run(stage), None);
        }
    }

    fn cancel(&mut self) {
        if let Some(w) = self.worker.as_mut() {
            if !w.cancel() {
                // Without shared memory the worker was replaced; its Ready reloads the design.
                self.notices.push("Cancelled (the worker was restarted).".into());
            }
        }
        self.busy = None;
    }

    fn handle_messages(&mut self) {
        loop {
            let Some(item) = self.worker.as_ref().and_then(|w| w.poll()) else { break };
            match item {
                Incoming::Crashed(message) => {
                    self.error = Some(format!("{message}. The worker was restarted; your design is kept."));
                    self.busy = None;
                    if let Some(w) = self.worker.as_mut() {
                        w.restart();
                    }
                }
                Incoming::Message(msg, fields) => self.handle_message(msg, fields),
            }
        }
    }

    fn handle_message(&mut self, msg: FromWorker, fields: Vec<Field>) {
        match msg {
            FromWorker::Ready => {
                // A fresh worker (first start or after a crash): restore the design in it.
                if let Some(l) = &self.loaded {
                    self.restoring = true;
                    match l.info.source.clone() {
                        Source::Sample(s) => self.send(&ToWorker::LoadSample(s), None),
                        Source::File(_) => {
                            if let Some(f) = self.file.clone() {
                                self.send(&ToWorker::LoadFile { name: f.name() }, Some(&f));
                            }
                        }
                    }
                }
            }
            FromWorker::Loaded(info) => {
                if !self.restoring {
                    self.error = None;
                }
                match &info.source {
                    Source::Sample(s) => {
                        self.design.reference = Reference::Sample(*s);
                        self.file = None;
                    }
                    Source::File(name) => {
                        self.design.reference = Reference::OwnFile(name.clone());
                        if let Some(f) = self.file_in_flight.take() {
                            self.file = Some(f);
                        }
                    }
                }
                for n in &info.notes {
                    self.notices.push(n.clone());
                }
                self.loaded = Some(Loaded {
                    info,
                    mesh: Arc::new(empty_mesh()),
                    center: Vec3::ZERO,
                    radius: 1.0,
                    curvature: None,
                    st: None,
                    angle: None,
                });
            }
            FromWorker::Snapshot { stage, .. } if stage == "reference" => self.install_geometry(&fields),
            FromWorker::Files { mime, .. } => {
                self.downloads = fields
                    .into_iter()
                    .zip(mime)
                    .filter_map(|(f, m)| match f.data {
                        FieldData::Bytes(b) => Some(Download { name: f.name, mime: m, bytes: b }),
                        _ => None,
                    })
                    .collect();
            }
            FromWorker::Snapshot { stage, .. } if stage == "st-support" => {
                if let Some(l) = self.loaded.as_mut() {
                    l.st = Some(StView::from_fields(&fields, &mut self.generation));
                }
            }
            FromWorker::Snapshot { stage, iteration, .. } if stage.starts_with(st_stage::STAGE) && stage != "st-support" => {
                let Some(a) = self.loaded.as_mut().and_then(|l| l.angle.as_mut()) else { return };
                if stage == st_stage::SIZING_STAGE {
                    a.sizing = find(&fields, st_stage::fields::SIZING).and_then(Field::as_f32).map(<[f32]>::to_vec);
                    self.scalars = None;
                } else if stage == st_stage::REMESHED_STAGE {
                    a.remeshed = Some(mesh_from_fields(&fields, &mut self.generation, MESH_FIELDS));
                } else {
                    a.panels = Some(mesh_from_fields(&fields, &mut self.generation, PANEL_FIELDS));
                    a.panel_iteration = iteration;
                    a.panel_snapshots += 1;
                }
            }
            FromWorker::Snapshot { .. } => {
                if let Some(l) = self.loaded.as_mut() {
                    let summary = l.curvature.take().and_then(|c| c.summary);
                    l.curvature = Some(CurvatureView { fields, summary });
                    self.scalars = None;
                }
            }
            FromWorker::Progress(p) => {
                if let (Some(a), Some(total)) = (self.loaded.as_mut().and_then(|l| l.angle.as_mut()), p.energies.first()) {
                    if p.stage == st_stage::STAGE {
                        a.energy.push((p.iteration, p.detail.clone(), total.value));
                    }
                }
                if let Some(b) = self.busy.as_mut() {
                    b.progress = Some(p);
                }
            }
            FromWorker::Finished { stage, result, .. } => {
                if self.busy.as_ref().is_some_and(|b| b.stage == stage) {
                    self.busy = None;
                }
                match result {
                    StageResult::Curvature(summary) => {
                        if let Some(c) = self.loaded.as_mut().and_then(|l| l.curvature.as_mut()) {
                            c.summary = Some(summary);
                        }
                    }
                    StageResult::StSupport(summary) => {
                        if let Some(st) = self.loaded.as_mut().and_then(|l| l.st.as_mut()) {
                            st.summary = Some(*summary);
                        }
                    }
                    StageResult::St(summary) => {
                        if let Some(a) = self.loaded.as_mut().and_then(|l| l.angle.as_mut()) {
                            a.summary = Some(*summary);
                        }
                    }
                }
            }
            FromWorker::Cancelled { stage } => {
                self.busy = None;
                self.notices.push(format!("Stage '{stage}' cancelled."));
            }
            FromWorker::Error { message } => {
                // A failed stage also ends the stages queued after it.
                self.busy = None;
                self.file_in_flight = None;
                self.error = Some(message);
            }
        }
    }

    fn install_geometry(&mut self, fields: &[Field]) {
        let Some(l) = self.loaded.as_mut() else { return };
        let get_f = |n| find(fields, n).and_then(Field::as_f32).map(<[f32]>::to_vec).unwrap_or_default();
        let get_u = |n| find(fields, n).and_then(Field::as_u32).map(<[u32]>::to_vec).unwrap_or_default();
        self.generation += 1;
        let mesh = MeshData {
            generation: self.generation,
            positions: get_f(field::POSITIONS),
            normals: get_f(field::NORMALS),
            triangles: get_u(field::TRIANGLES),
            edges: get_u(field::EDGES),
        };
        let (lo, hi) = mesh.positions.chunks_exact(3).fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(Vec3::from_slice(p)), hi.max(Vec3::from_slice(p))),
        );
        l.center = (lo + hi) * 0.5;
        l.radius = ((hi - lo).length() * 0.5).max(1e-6);
        l.mesh = Arc::new(mesh);
        l.curvature = None;
        l.st = None;
        l.angle = None;
        self.scalars = None;
        if !self.restoring {
            self.selected = None;
        }
        if std::mem::take(&mut self.restoring) {
            self.camera.scene_radius = l.radius;
        } else {
            self.camera = OrbitCamera::framing(l.center, l.radius);
        }
        if let Some(c) = self.camera_from_link.take() {
            self.camera.yaw = c.yaw as f32;
            self.camera.pitch = c.pitch as f32;
            self.camera.distance = c.distance as f32;
            self.camera.target = Vec3::new(c.target[0] as f32, c.target[1] as f32, c.target[2] as f32);
        }
        self.busy = None;
        self.run_method();
    }

    /// Scalars for the current colour choice, with a robust range (2nd to 98th percentile).
    fn scalar_view(&mut self) -> Option<&ScalarView> {
        let color = self.design.color;
        let fresh = self.scalars.as_ref().is_some_and(|s| s.color == color);
        if !fresh {
            self.scalars = None;
            let l = self.loaded.as_ref()?;
            let key = match color {
                ColorBy::None => return None,
                ColorBy::Sizing => "",
                ColorBy::MeanCurvature => field::MEAN_CURVATURE,
                ColorBy::K1 => field::K1,
                ColorBy::K2 => field::K2,
                ColorBy::K1MinusK2 => field::K1_MINUS_K2,
            };
            let values = if color == ColorBy::Sizing {
                l.angle.as_ref()?.sizing.clone()?
            } else {
                find(&l.curvature.as_ref()?.fields, key)?.as_f32()?.to_vec()
            };
            let (range, diverging) = colormap::robust_range(&values);
            self.generation += 1;
            self.scalars = Some(ScalarView {
                color,
                data: Arc::new(ScalarData { generation: self.generation, values }),
                range,
                diverging,
            });
        }
        self.scalars.as_ref()
    }

    fn apply_link_if_changed(&mut self) {
        let hash = location_hash();
        if hash == self.last_fragment {
            return;
        }
        // The user edited or navigated the link: apply it.
        self.last_fragment = hash.clone();
        let (design, notices) = Design::from_fragment(&hash);
        self.notices = notices;
        let reference_changed = design.reference != self.design.reference;
        let jet_changed = design.jet != self.design.jet || design.method != self.design.method
            || design.st != self.design.st
            || design.st_angle != self.design.st_angle;
        self.camera_from_link = design.camera;
        self.design = design;
        if reference_changed {
            self.load_design_reference();
        } else {
            if let Some(c) = self.camera_from_link.take() {
                self.camera.yaw = c.yaw as f32;
                self.camera.pitch = c.pitch as f32;
                self.camera.distance = c.distance as f32;
                self.camera.target = Vec3::new(c.target[0] as f32, c.target[1] as f32, c.target[2] as f32);
            }
            if jet_changed {
                self.run_method();
            }
        }
    }

    fn write_link(&mut self, dragging: bool) {
        if self.loaded.is_none() || dragging {
            return;
        }
        let mut d = self.design.clone();
        d.camera = Some(CameraState {
            yaw: self.camera.yaw as f64,
            pitch: self.camera.pitch as f64,
            distance: self.camera.distance as f64,
            target: [self.camera.target.x as f64, self.camera.target.y as f64, self.camera.target.z as f64],
        });
        let frag = d.to_fragment();
        if frag != self.last_fragment {
            if let Some(w) = web_sys::window() {
                if let Ok(h) = w.history() {
                    let _ = h.replace_state_with_url(&JsValue::NULL, "", Some(&frag));
                }
            }
            self.last_fragment = frag;
        }
    }

    fn share_url(&self) -> String {
        let w = web_sys::window();
        let base = w
            .and_then(|w| {
                let l = w.location();
                Some(format!("{}{}{}", l.origin().ok()?, l.pathname().ok()?, l.search().ok()?))
            })
            .unwrap_or_default();
        format!("{base}{}", self.last_fragment)
    }

    fn publish_state(&mut self) {
        let (v, f, bl, nm, source) = match &self.loaded {
            Some(l) => (
                l.info.stats.vertices,
                l.info.stats.faces,
                l.info.stats.boundary_loops,
                l.info.stats.non_manifold_edges,
                l.info.source.label(),
            ),
            None => (0, 0, 0, 0, String::new()),
        };
        let curvature_ready =
            self.loaded.as_ref().and_then(|l| l.curvature.as_ref()).is_some_and(|c| c.summary.is_some());
        let vp = self.viewport;
        let state = serde_json::json!({
            "ready": self.drawn,
            "backend": self.backend,
            "frames": self.frames,
            "source": source,
            "vertices": v, "faces": f, "boundary_loops": bl, "non_manifold_edges": nm,
            "busy": self.busy.is_some(),
            "stage": self.busy.as_ref().map(|b| b.stage.clone()).unwrap_or_default(),
            "curvature_ready": curvature_ready,
            "color_by": self.design.color.key(),
            "shading": self.design.shading.key(),
            "edges": self.design.edges,
            "jet_degree": self.design.jet.degree,
            "error": self.error,
            "notices": self.notices,
            "design_link": self.last_fragment,
            "clear_color": [CLEAR_COLOR.r(), CLEAR_COLOR.g(), CLEAR_COLOR.b()],
            "viewport": [vp.min.x, vp.min.y, vp.width(), vp.height()],
            "worker_restarts": self.worker.as_ref().map_or(0, |w| w.restarts),
            "ui_ms_median": percentile(&self.ui_ms, 0.5),
            "ui_ms_p95": percentile(&self.ui_ms, 0.95),
            "ui_ms_max": self.ui_ms.iter().copied().fold(0.0, f64::max),
            "selected_vertex": self.selected,
            "method": self.design.method.key(),
            "st_ready": self.loaded.as_ref().and_then(|l| l.st.as_ref()).is_some_and(|s| s.summary.is_some()),
            "panels": self.loaded.as_ref().and_then(|l| l.st.as_ref()).and_then(|s| s.summary.as_ref()).map_or(0, |s| s.report.output.panels),
            "downloads": self.downloads.iter().map(|d| d.name.clone()).collect::<Vec<_>>(),
            "st_angle": self.loaded.as_ref().and_then(|l| l.angle.as_ref()).map(|a| serde_json::json!({
                "sizing": a.sizing.as_ref().map_or(0, Vec::len),
                "remeshed_faces": a.remeshed.as_ref().map_or(0, |m| m.triangles.len() / 3),
                "panel_iteration": a.panel_iteration,
                "panel_snapshots": a.panel_snapshots,
                "panel_triangles": a.panels.as_ref().map_or(0, |m| m.triangles.len() / 3),
                "energies": a.energy.len(),
                "ready": a.summary.is_some(),
                "panels": a.summary.as_ref().map_or(0, |s| s.report.output.panels),
            })),
        })
        .to_string();
        if state != self.last_state {
            if let Some(el) = web_sys::window().and_then(|w| w.document()).and_then(|d| d.get_element_by_id("sf-state")) {
                el.set_text_content(Some(&state));
            }
            self.last_state = state;
        }
    }

    // --- UI --------------------------------------------------------------------------------

    fn top_bar(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            ui.heading("Spherical Faces");
            ui.separator();
            let current = match &self.design.reference {
                Reference::Sample(s) => s.title().to_string(),
                Reference::OwnFile(name) => name.clone(),
            };
            egui::ComboBox::from_id_salt("sample").selected_text(current).show_ui(ui, |ui| {
                for s in Sample::ALL {
                    let selected = self.design.reference == Reference::Sample(s);
                    if ui.selectable_label(selected, s.title()).on_hover_text(s.description()).clicked() && !selected {
                        self.send(&ToWorker::LoadSample(s), None);
                        self.busy = Some(Busy { stage: "import".into(), progress: None });
                    }
                }
            });
            if ui.button("Open…").on_hover_text("OBJ, glTF (.gltf with embedded data) or GLB; or drop a file on the view").clicked() {
                if let Some(input) = &self.file_input {
                    input.set_value("");
                    input.click();
                }
            }
            if ui.button("Copy link").on_hover_text("Copy a link that restores this design").clicked() {
                let url = self.share_url();
                ui.ctx().copy_text(url);
                self.notices.push("Design link copied.".into());
            }
            ui.with_layout(egui::Layout::right_to_left(egui::Align::Center), |ui| {
                let label = if self.backend.is_empty() { "no GPU backend".to_string() } else { self.backend.clone() };
                ui.label(RichText::new(label).monospace()).on_hover_text("Graphics backend in use");
            });
        });
    }

    fn side_panel(&mut self, ui: &mut egui::Ui) {
        egui::ScrollArea::vertical().show(ui, |ui| {
            if let Some(err) = self.error.clone() {
                egui::Frame::new().fill(Color32::from_rgb(90, 24, 24)).inner_margin(6.0).corner_radius(4.0).show(ui, |ui| {
                    ui.label(RichText::new(err).color(Color32::WHITE));
                    if ui.small_button("Dismiss").clicked() {
                        self.error = None;
                    }
                });
                ui.add_space(6.0);
            }
            ui.strong("Method");
            let mut method = self.design.method;
            egui::ComboBox::from_id_salt("method").selected_text(method.title()).show_ui(ui, |ui| {
                for m in Method::ALL {
                    ui.selectable_value(&mut method, m, m.title());
                }
            });
            if method != self.design.method {
                self.design.method = method;
                if method == Method::St && self.design.color == ColorBy::MeanCurvature {
                    self.design.color = ColorBy::Sizing;
                } else if method != Method::St && self.design.color == ColorBy::Sizing {
                    self.design.color = ColorBy::MeanCurvature;
                }
                self.run_method();
            }
            ui.label(RichText::new("Curvature by jet fitting (Sec. 2.6)").small());
            let mut jet = self.design.jet.clone();
            let mut degree = jet.degree as u32;
            ui.add(egui::Slider::new(&mut degree, 2..=4).text("jet degree"));
            jet.degree = degree as u8;
            ui.add(egui::Slider::new(&mut jet.max_rings, 1..=8).text("max rings"));
            if jet != self.design.jet {
                self.design.jet = jet;
                self.run_method();
            }
            if self.design.method == Method::StSupport {
                let mut st = self.design.st;
                ui.checkbox(&mut st.optimize_radius, "optimize R (Fig. 16, right)");
                ui.add(egui::Slider::new(&mut st.support_depth, 0.0..=0.1).text("support depth"));
                ui.add(egui::Slider::new(&mut st.axis_length, 0.0..=0.5).text("axis length"));
                ui.add(egui::Slider::new(&mut st.radius_tolerance, 1e-5..=1e-1).logarithmic(true).text("radius tolerance"));
                ui.label(RichText::new("lengths relative to the bbox diagonal").small());
                ui.label(RichText::new("Remesh first (Fig. 16, bottom)").small());
                sizing_controls(ui, "st-remesh", &mut st.remesh, &[SizingKind::None, SizingKind::Adaptive, SizingKind::Faces]);
                let changed = st != self.design.st;
                let released = !ui.input(|i| i.pointer.any_down());
                self.design.st = st;
                if changed {
                    self.st_dirty = true;
                }
                if self.st_dirty && released {
                    self.st_dirty = false;
                    self.run_method();
                }
                ui.checkbox(&mut self.show_reference, "show reference surface");
                ui.checkbox(&mut self.show_envelope, "show second envelope");
            }
            if self.design.method == Method::St {
                let mut a = self.design.st_angle;
                sizing_controls(ui, "st-sizing", &mut a.sizing, &SizingKind::ALL);
                ui.horizontal(|ui| {
                    ui.label("edges");
                    ui.radio_value(&mut a.variant, StVariant::A, "(a) sphere intersections")
                        .on_hover_text("Fig. 12 (a): edges are the intersection circles of adjacent face spheres");
                    ui.radio_value(&mut a.variant, StVariant::B, "(b) bisecting planes")
                        .on_hover_text("Fig. 12 (b): each sphere is cut by the bisecting face planes; small gaps remain");
                });
                if a != self.design.st_angle {
                    self.st_dirty = true;
                }
                self.design.st_angle = a;
                if self.st_dirty && !ui.input(|i| i.pointer.any_down()) {
                    self.st_dirty = false;
                    self.run_method();
                }
                ui.checkbox(&mut self.show_reference, "show reference surface (sizing colours)");
                ui.checkbox(&mut self.show_remeshed, "overlay the remeshed triangulation (before optimization)");
            }
            ui.separator();
            ui.strong("Display");
            ui.horizontal(|ui| {
                for s in Shading::ALL {
                    ui.radio_value(&mut self.design.shading, s, s.key());
                }
            });
            ui.checkbox(&mut self.design.edges, "edges");
            egui::ComboBox::from_label("colour by").selected_text(self.design.color.label()).show_ui(ui, |ui| {
                for c in ColorBy::ALL {
                    ui.selectable_value(&mut self.design.color, c, c.label());
                }
            });
            ui.separator();
            self.info_section(ui);
            self.st_section(ui);
            self.st_angle_section(ui);
            if !self.downloads.is_empty() {
                ui.separator();
                ui.strong("Downloads");
                ui.horizontal_wrapped(|ui| {
                    for d in &self.downloads {
                        if ui.button(&d.name).on_hover_text(format!("{} bytes", d.bytes.len())).clicked() {
                            if let Err(e) = save_file(&d.name, &d.mime, &d.bytes) {
                                self.error = Some(format!("could not save {}: {e:?}", d.name));
                            }
                        }
                    }
                });
            }
            if !self.notices.is_empty() {
                ui.separator();
                ui.horizontal(|ui| {
                    ui.strong("Notices");
                    if ui.small_button("clear").clicked() {
                        self.notices.clear();
                    }
                });
                for n in self.notices.iter().rev().take(8) {
                    ui.label(RichText::new(n).small());
                }
            }
        });
    }

    fn info_section(&mut self, ui: &mut egui::Ui) {
        ui.strong("Reference");
        let Some(l) = &self.loaded else {
            ui.label("loading…");
            return;
        };
        let s = &l.info.stats;
        key_values(
            ui,
            "info",
            &[
                ("source", l.info.source.label()),
                ("vertices", s.vertices.to_string()),
                ("faces", s.faces.to_string()),
                ("boundary loops", s.boundary_loops.to_string()),
                ("non-manifold edges", s.non_manifold_edges.to_string()),
                ("bbox diagonal", format!("{:.4}", l.info.bbox_diagonal)),
            ],
        );
        if let Some(sum) = l.curvature.as_ref().and_then(|c| c.summary.as_ref()) {
            ui.add_space(4.0);
            ui.strong("Curvature");
            key_values(
                ui,
                "curvature",
                &[
                    ("H min / max", format!("{:.4} / {:.4}", sum.min_h, sum.max_h)),
                    ("H mean", format!("{:.4}", sum.mean_h)),
                    ("boundary vertices", sum.boundary_vertices.to_string()),
                    ("H ≈ 0 vertices", sum.planar_vertices.to_string()),
                    ("low-degree / failed fits", format!("{} / {}", sum.low_degree_fits, sum.failed_fits)),
                ],
            );
            if sum.h_changes_sign {
                ui.colored_label(
                    Color32::from_rgb(240, 180, 80),
                    "H changes sign: central spheres flip through planes there; the sphere methods need H of one sign.",
                );
            }
            if sum.planar_vertices > 0 {
                ui.label(RichText::new(format!("{} vertices have H ≈ 0: their central spheres are planes.", sum.planar_vertices)).small());
            }
        }
        if let Some(v) = self.selected {
            ui.add_space(4.0);
            ui.strong(format!("Vertex {v}"));
            if let Some(text) = self.selected_vertex_text(v) {
                ui.label(RichText::new(text).monospace().small());
            }
        } else {
            ui.label(RichText::new("Click the surface to see a vertex's central sphere.").small());
        }
    }

    /// Ω, the report metrics and the histograms of Fig. 14.
    fn st_section(&self, ui: &mut egui::Ui) {
        if self.design.method != Method::StSupport {
            return;
        }
        let Some(sum) = self.loaded.as_ref().and_then(|l| l.st.as_ref()).and_then(|s| s.summary.as_ref()) else { return };
        ui.separator();
        ui.strong("ST mesh with support structure");
        let omega = match sum.omega {
            AbsoluteSphere::Sphere { center, r2 } => {
                format!("m = ({:.3}, {:.3}, {:.3})\nR² = {:.4}{}", center.x, center.y, center.z, r2, if r2 < 0.0 { " (imaginary Ω)" } else { "" })
            }
            AbsoluteSphere::Plane { axis, d } => format!("plane at infinity: a = ({:.3}, {:.3}, {:.3}), d = {:.4}", axis.x, axis.y, axis.z, d),
        };
        ui.label(RichText::new(omega).monospace().small());
        let r = &sum.report;
        let m = &r.metrics;
        let g = |x: Option<f64>| x.map_or("–".to_string(), |v| format!("{v:.3e}"));
        let d = |x: Option<f64>| x.map_or("–".to_string(), |v| format!("{v:.3}°"));
        key_values(
            ui,
            "st-metrics",
            &[
                ("panels", r.output.panels.to_string()),
                ("distinct radii", sum.distinct_radii.to_string()),
                ("kink mean / max", format!("{} / {}", d(m.mean_kink_angle_deg), d(m.max_kink_angle_deg))),
                ("axis–normal mean / max", format!("{} / {}", d(m.mean_axis_normal_angle_deg), d(m.max_axis_normal_angle_deg))),
                ("vertex–sphere residual", g(m.max_vertex_sphere_residual)),
                ("orthogonality residual", g(m.max_orthogonality_residual)),
                ("node-axis offset", g(m.max_node_axis_offset)),
                ("distance to reference", g(m.max_distance_to_reference)),
            ],
        );
        ui.label(RichText::new("∠(v − m, n): m0 (green) and optimized m (red)").small());
        histogram(ui, &[(&sum.angles_m0, Color32::from_rgb(90, 190, 90)), (&sum.angles_m, Color32::from_rgb(220, 80, 70))], "°");
        ui.label(RichText::new(if matches!(sum.omega, AbsoluteSphere::Plane { .. }) { "distances dᵢ" } else { "Rᵢ² of the central spheres" }).small());
        histogram(ui, &[(&sum.r2, Color32::from_rgb(110, 150, 230))], "");
    }

    /// The live energy plot and, when done, the report metrics of the "st" method.
    fn st_angle_section(&self, ui: &mut egui::Ui) {
        if self.design.method != Method::St {
            return;
        }
        let Some(a) = self.loaded.as_ref().and_then(|l| l.angle.as_ref()) else { return };
        ui.separator();
        ui.strong("ST mesh, adapted face size");
        if let Some(m) = &a.remeshed {
            ui.label(RichText::new(format!("remeshed: {} faces; panels at iteration {}", m.triangles.len() / 3, a.panel_iteration)).small());
        }
        if !a.energy.is_empty() {
            ui.label(RichText::new("energy per iteration (log scale; weights change between stages)").small());
            energy_plot(ui, &a.energy);
        }
        let Some(sum) = &a.summary else { return };
        let m = &sum.report.metrics;
        let g = |x: Option<f64>| x.map_or("–".to_string(), |v| format!("{v:.3e}"));
        let mut rows = vec![
            ("panels", sum.report.output.panels.to_string()),
            ("iterations", sum.iterations.to_string()),
            ("kink mean, initial → final", format!("{:.3}° → {:.3}°", sum.initial.mean_kink_angle_deg, sum.metrics.mean_kink_angle_deg)),
            ("kink max, initial → final", format!("{:.3}° → {:.3}°", sum.initial.max_kink_angle_deg, sum.metrics.max_kink_angle_deg)),
            ("vertex–sphere residual", g(m.max_vertex_sphere_residual)),
            ("distance to reference", g(m.max_distance_to_reference)),
        ];
        if let Some(gap) = sum.metrics.max_gap {
            rows.push(("max gap (b)", format!("{gap:.3e}")));
        }
        if let Some((lo, hi)) = sum.sizing_range {
            rows.push(("sizing g min / max", format!("{lo:.4} / {hi:.4}")));
        }
        if let Some(ms) = sum.report.timings_ms.get("angle_iteration_median") {
            rows.push(("median iteration", format!("{ms:.2} ms")));
        }
        key_values(ui, "st-angle-metrics", &rows);
        if sum.metrics.flipped_faces > 0 {
            ui.colored_label(Color32::from_rgb(240, 180, 80), format!("{} faces ended flipped against the reference.", sum.metrics.flipped_faces));
        }
    }

    fn selected_vertex_text(&self, v: usize) -> Option<String> {
        let c = self.loaded.as_ref()?.curvature.as_ref()?;
        let val = |k| find(&c.fields, k).and_then(Field::as_f32).and_then(|x| x.get(v).copied());
        let (h, k1, k2) = (val(field::MEAN_CURVATURE)?, val(field::K1)?, val(field::K2)?);
        let sphere = central_sphere(&c.fields, v)?;
        let desc = match sphere_center_radius(&sphere) {
            Some((center, r)) => format!("centre ({:.3}, {:.3}, {:.3})\nradius {:.4}", center.x, center.y, center.z, r.abs()),
            None => "central sphere is a plane (H ≈ 0)".into(),
        };
        let boundary = find(&c.fields, field::BOUNDARY).and_then(Field::as_u32).and_then(|b| b.get(v).copied()) == Some(1);
        Some(format!(
            "H  {h:.5}\nκ1 {k1:.5}\nκ2 {k2:.5}\n{desc}{}",
            if boundary { "\n(boundary vertex: one-sided fit)" } else { "" }
        ))
    }

    fn viewport(&mut self, ui: &mut egui::Ui) {
        let rect = ui.available_rect_before_wrap();
        self.viewport = rect;
        let response = ui.allocate_rect(rect, Sense::click_and_drag());
        ui.painter().rect_filled(rect, 0.0, CLEAR_COLOR);

        // Camera: orbit (primary), pan (secondary, middle or shift), zoom (wheel, pinch).
        let shift = ui.input(|i| i.modifiers.shift);
        if response.dragged_by(egui::PointerButton::Primary) && !shift {
            let d = response.drag_delta();
            self.camera.orbit(d.x, d.y);
        } else if response.dragged_by(egui::PointerButton::Secondary)
            || response.dragged_by(egui::PointerButton::Middle)
            || (response.dragged_by(egui::PointerButton::Primary) && shift)
        {
            let d = response.drag_delta();
            self.camera.pan(d.x, d.y, rect.height());
        }
        if response.hovered() {
            let (scroll, zoom, touch) = ui.input(|i| (i.smooth_scroll_delta.y, i.zoom_delta(), i.multi_touch()));
            if scroll != 0.0 {
                self.camera.zoom((scroll * 0.002).exp());
            }
            if zoom != 1.0 {
                self.camera.zoom(zoom);
            }
            if let Some(t) = touch {
                self.camera.pan(t.translation_delta.x, t.translation_delta.y, rect.height());
            }
        }
        if response.double_clicked() {
            if let Some(l) = &self.loaded {
                self.camera = OrbitCamera { target: l.center, ..OrbitCamera::framing(l.center, l.radius) };
            }
        } else if response.clicked() {
            if let Some(pos) = response.interact_pointer_pos() {
                self.selected = self.pick(pos, rect);
            }
        }

        let Some(l) = &self.loaded else {
            ui.painter().text(rect.center(), egui::Align2::CENTER_CENTER, "loading…", egui::FontId::proportional(18.0), Color32::GRAY);
            return;
        };
        if l.mesh.triangles.is_empty() {
            return;
        }
        let mesh = l.mesh.clone();
        self.camera.scene_radius = l.radius;
        let aspect = rect.width() / rect.height().max(1.0);
        let shading = match self.design.shading {
            Shading::Flat => 0,
            Shading::Smooth => 1,
            Shading::Reflective => 2,
        };
        let color_map = self.scalar_view().map(|s| ColorMap { scalars: s.data.clone(), range: s.range, diverging: s.diverging });
        let st = self.loaded.as_ref().and_then(|l| l.st.as_ref()).filter(|_| self.design.method == Method::StSupport);
        let angle = self.loaded.as_ref().and_then(|l| l.angle.as_ref()).filter(|_| self.design.method == Method::St);
        let angle_shown = angle.is_some_and(|a| a.panels.is_some() || a.remeshed.is_some());
        let edge_color = [0.05, 0.06, 0.08, 1.0];
        let mut layers = Vec::new();
        let reference_shown = (st.is_none() && !angle_shown) || self.show_reference;
        if reference_shown {
            layers.push(Layer {
                geometry: Geometry::Mesh(mesh.clone()),
                model: Mat4::IDENTITY,
                style: Style::Surface { shading, color: [0.72, 0.78, 0.86, 1.0], color_map },
            });
            if self.design.edges {
                layers.push(Layer { geometry: Geometry::Mesh(mesh), model: Mat4::IDENTITY, style: Style::Lines { color: edge_color } });
            }
        }
        if let Some(st) = st {
            layers.extend(self.st_layers(st, shading, edge_color));
        }
        if let Some(a) = angle {
            let id = Mat4::IDENTITY;
            match (&a.panels, &a.remeshed) {
                (Some(p), _) => {
                    layers.push(Layer { geometry: Geometry::Mesh(p.clone()), model: id, style: Style::Surface { shading, color: [0.70, 0.80, 0.88, 1.0], color_map: None } });
                    layers.push(Layer { geometry: Geometry::Mesh(p.clone()), model: id, style: Style::Lines { color: edge_color } });
                }
                (None, Some(r)) => {
                    layers.push(Layer { geometry: Geometry::Mesh(r.clone()), model: id, style: Style::Surface { shading, color: [0.70, 0.80, 0.88, 1.0], color_map: None } });
                }
                (None, None) => {}
            }
            // The remeshed triangulation: alone until the first panels arrive, then on request.
            if let Some(r) = a.remeshed.as_ref().filter(|_| self.show_remeshed || a.panels.is_none()) {
                layers.push(Layer { geometry: Geometry::Mesh(r.clone()), model: id, style: Style::Lines { color: [0.95, 0.55, 0.20, 1.0] } });
            }
        }
        layers.extend(self.selected.and_then(|v| self.central_sphere_layer(v)));
        let frame = ViewerFrame {
            view_proj: self.camera.proj(aspect) * self.camera.view(),
            eye: self.camera.eye(),
            line_bias: 2e-3 * self.camera.distance.min(4.0 * self.camera.scene_radius),
            layers,
        };
        ui.painter().add(egui_wgpu::Callback::new_paint_callback(rect, frame));
        self.drawn = true;
        if let Some(s) = self.scalars.as_ref().filter(|_| reference_shown) {
            colormap::legend(ui.painter(), rect, self.design.color.label(), s.range, s.diverging);
        }
        if let Some(b) = &self.busy {
            let text = match &b.progress {
                Some(p) if p.total > 0 => format!("{} {}: {}/{} · {:.0} ms", b.stage, p.detail, p.iteration, p.total, p.elapsed_ms),
                _ => format!("{}…", b.stage),
            };
            ui.painter().text(rect.left_top() + Vec2::new(10.0, 10.0), egui::Align2::LEFT_TOP, text, egui::FontId::proportional(13.0), Color32::LIGHT_GRAY);
        }
    }

    /// Panels (with their arcs), support structure, node axes, Ω and m, and the second envelope.
    fn st_layers(&self, st: &StView, shading: u32, edge_color: [f32; 4]) -> Vec<Layer> {
        let id = Mat4::IDENTITY;
        let radius = self.loaded.as_ref().map_or(1.0, |l| l.radius);
        let mut layers = vec![
            Layer { geometry: Geometry::Mesh(st.panels.clone()), model: id, style: Style::Surface { shading, color: [0.70, 0.80, 0.88, 1.0], color_map: None } },
            Layer { geometry: Geometry::Mesh(st.panels.clone()), model: id, style: Style::Lines { color: edge_color } },
            Layer { geometry: Geometry::Mesh(st.support.clone()), model: id, style: Style::Surface { shading: 0, color: [0.80, 0.55, 0.30, 1.0], color_map: None } },
            Layer { geometry: Geometry::Mesh(st.axes.clone()), model: id, style: Style::Lines { color: [0.85, 0.15, 0.12, 1.0] } },
        ];
        if self.show_envelope {
            if let Some(env) = &st.envelope {
                layers.push(Layer { geometry: Geometry::Mesh(env.clone()), model: id, style: Style::Surface { shading: 0, color: [0.55, 0.75, 0.55, 1.0], color_map: None } });
            }
        }
        if let Some(AbsoluteSphere::Plane { axis, d }) = st.summary.as_ref().map(|s| s.omega) {
            // Ω at infinity: a disc of the plane ⟨x, a⟩ = d under the mesh centre.
            let (a, center) = (axis.as_vec3().normalize_or(Vec3::Z), self.loaded.as_ref().map_or(Vec3::ZERO, |l| l.center));
            let foot = center + a * (d as f32 - center.dot(a));
            layers.push(Layer {
                geometry: Geometry::UnitDisc,
                model: Mat4::from_scale_rotation_translation(Vec3::splat(radius * 1.2), glam::Quat::from_rotation_arc(Vec3::Z, a), foot),
                style: Style::Translucent { color: [0.95, 0.75, 0.30, 0.15] },
            });
        }
        if let Some(AbsoluteSphere::Sphere { center, r2 }) = st.summary.as_ref().map(|s| s.omega) {
            let m = center.as_vec3();
            // m itself, and Ω when real and not too large to see.
            layers.push(Layer {
                geometry: Geometry::UnitSphere,
                model: Mat4::from_translation(m) * Mat4::from_scale(Vec3::splat(radius * 0.02)),
                style: Style::Surface { shading: 1, color: [0.85, 0.15, 0.12, 1.0], color_map: None },
            });
            if r2 > 0.0 && (r2.sqrt() as f32) < 20.0 * radius {
                layers.push(Layer {
                    geometry: Geometry::UnitSphere,
                    model: Mat4::from_translation(m) * Mat4::from_scale(Vec3::splat(r2.sqrt() as f32)),
                    style: Style::Translucent { color: [0.95, 0.75, 0.30, 0.15] },
                });
            }
        }
        layers
    }

    /// The translucent central sphere (or plane) at vertex `v`.
    fn central_sphere_layer(&self, v: usize) -> Option<Layer> {
        let l = self.loaded.as_ref()?;
        let sphere = central_sphere(&l.curvature.as_ref()?.fields, v)?;
        let p = Vec3::from_slice(l.mesh.positions.get(3 * v..3 * v + 3)?);
        let color = [0.35, 0.65, 1.0, 0.28];
        match sphere_center_radius(&sphere) {
            Some((c, r)) if r.abs() < 50.0 * l.radius => Some(Layer {
                geometry: Geometry::UnitSphere,
                model: Mat4::from_translation(c) * Mat4::from_scale(Vec3::splat(r.abs())),
                style: Style::Translucent { color },
            }),
            _ => {
                // A plane (or a sphere too large to draw): a disc in the tangent plane at v.
                let n = Vec3::new(sphere[1], sphere[2], sphere[3]).normalize_or(Vec3::Z);
                let rot = glam::Quat::from_rotation_arc(Vec3::Z, n);
                Some(Layer {
                    geometry: Geometry::UnitDisc,
                    model: Mat4::from_scale_rotation_translation(Vec3::splat(l.radius * 0.6), rot, p),
                    style: Style::Translucent { color },
                })
            }
        }
    }

    /// The mesh vertex nearest to the surface point under the pointer.
    fn pick(&self, pos: Pos2, rect: Rect) -> Option<usize> {
        let l = self.loaded.as_ref()?;
        let ndc_x = (pos.x - rect.min.x) / rect.width() * 2.0 - 1.0;
        let ndc_y = 1.0 - (pos.y - rect.min.y) / rect.height() * 2.0;
        let (o, d) = self.camera.ray(ndc_x, ndc_y, rect.width() / rect.height().max(1.0));
        let p = &l.mesh.positions;
        let vtx = |i: u32| Vec3::from_slice(&p[3 * i as usize..3 * i as usize + 3]);
        let mut best: Option<(f32, [u32; 3], Vec3)> = None;
        for t in l.mesh.triangles.chunks_exact(3) {
            let (a, b, c) = (vtx(t[0]), vtx(t[1]), vtx(t[2]));
            if let Some(s) = ray_triangle(o, d, a, b, c) {
                if best.is_none_or(|(bs, ..)| s < bs) {
                    best = Some((s, [t[0], t[1], t[2]], o + d * s));
                }
            }
        }
        let (_, tri, hit) = best?;
        tri.into_iter().min_by(|&a, &b| (vtx(a) - hit).length().total_cmp(&(vtx(b) - hit).length())).map(|v| v as usize)
    }
}

impl eframe::App for App {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        let started = now_ms();
        self.frames += 1;
        self.handle_messages();
        self.apply_link_if_changed();
        let requested: Vec<String> = self.download_requests.borrow_mut().drain(..).collect();
        for name in requested {
            match self.downloads.iter().find(|d| d.name == name) {
                Some(d) => {
                    if let Err(e) = save_file(&d.name, &d.mime, &d.bytes) {
                        self.error = Some(format!("could not save {name}: {e:?}"));
                    }
                }
                None => self.notices.push(format!("no file named '{name}' to download yet")),
            }
        }
        let crashes = std::mem::take(&mut *self.crash_requests.borrow_mut());
        if crashes > 0 {
            self.send(&ToWorker::Crash, None);
        }
        if std::mem::take(&mut *self.cancel_requests.borrow_mut()) > 0 && self.busy.is_some() {
            self.cancel();
        }

        // Dropped files (eframe) and picked files (the Open… dialog).
        let dropped: Vec<web_sys::File> =
            ui.input(|i| i.raw.dropped_files.iter().filter_map(|f| f.web_file().cloned()).collect());
        let picked: Vec<web_sys::File> = self.picked_files.borrow_mut().drain(..).collect();
        if let Some(f) = dropped.into_iter().chain(picked).last() {
            self.load_file(f);
        }

        egui::Panel::top("top").show(ui, |ui| self.top_bar(ui));
        if self.busy.is_some() {
            egui::Panel::bottom("progress").show(ui, |ui| {
                ui.horizontal(|ui| {
                    let (frac, text) = match self.busy.as_ref().and_then(|b| b.progress.as_ref()) {
                        Some(p) if p.total > 0 => (p.iteration as f32 / p.total as f32, format!("{} {} {}/{}", p.stage, p.detail, p.iteration, p.total)),
                        _ => (0.0, self.busy.as_ref().map(|b| b.stage.clone()).unwrap_or_default()),
                    };
                    if ui.button("Cancel").clicked() {
                        self.cancel();
                    }
                    ui.add(egui::ProgressBar::new(frac).text(text).animate(true));
                });
            });
        }
        egui::Panel::left("side").default_size(290.0).resizable(true).show(ui, |ui| self.side_panel(ui));
        let hovering = ui.input(|i| !i.raw.hovered_files.is_empty());
        egui::CentralPanel::no_frame().show(ui, |ui| {
            self.viewport(ui);
            if hovering {
                ui.painter().rect_filled(self.viewport, 0.0, Color32::from_black_alpha(140));
                ui.painter().text(self.viewport.center(), egui::Align2::CENTER_CENTER, "Drop OBJ, glTF or GLB to load", egui::FontId::proportional(22.0), Color32::WHITE);
            }
        });
        let dragging = ui.input(|i| i.pointer.any_down());
        self.write_link(dragging);
        self.publish_state();
        if self.ui_ms.len() == UI_TIMES {
            self.ui_ms.pop_front();
        }
        self.ui_ms.push_back(now_ms() - started);
        if self.busy.is_some() || !self.drawn {
            ui.ctx().request_repaint();
        }
    }

    fn clear_color(&self, _visuals: &egui::Visuals) -> [f32; 4] {
        CLEAR_COLOR.to_normalized_gamma_f32()
    }
}

/// Saves `bytes` as a file through a temporary object URL.
fn save_file(name: &str, mime: &str, bytes: &[u8]) -> Result<(), JsValue> {
    let parts = js_sys::Array::of1(&js_sys::Uint8Array::from(bytes));
    let opts = web_sys::BlobPropertyBag::new();
    opts.set_type(mime);
    let blob = web_sys::Blob::new_with_u8_array_sequence_and_options(&parts, &opts)?;
    let url = web_sys::Url::create_object_url_with_blob(&blob)?;
    let doc = web_sys::window().and_then(|w| w.document()).ok_or("no document")?;
    let a: web_sys::HtmlAnchorElement = doc.create_element("a")?.dyn_into()?;
    a.set_href(&url);
    a.set_download(name);
    a.click();
    // Release the object URL once the download has started.
    let release = Closure::once_into_js(move || {
        let _ = web_sys::Url::revoke_object_url(&url);
    });
    let window = web_sys::window().ok_or("no window")?;
    window.set_timeout_with_callback_and_timeout_and_arguments_0(release.unchecked_ref(), 10_000)?;
    Ok(())
}

/// Overlaid bar histograms (Fig. 14) over their common range.
fn histogram(ui: &mut egui::Ui, series: &[(&Histogram, Color32)], unit: &str) {
    let (rect, _) = ui.allocate_exact_size(Vec2::new(ui.available_width().min(260.0), 70.0), Sense::hover());
    let p = ui.painter();
    p.rect_filled(rect, 2.0, Color32::from_gray(30));
    let lo = series.iter().map(|(h, _)| h.lo).fold(f64::INFINITY, f64::min);
    let hi = series.iter().map(|(h, _)| h.hi).fold(f64::NEG_INFINITY, f64::max);
    if !(hi > lo) {
        return;
    }
    let peak = series.iter().flat_map(|(h, _)| h.counts.iter().copied()).max().unwrap_or(1).max(1) as f32;
    for (h, color) in series {
        let n = h.counts.len().max(1) as f64;
        let w = (h.hi - h.lo) / n;
        for (i, &c) in h.counts.iter().enumerate() {
            let x0 = (h.lo + w * i as f64 - lo) / (hi - lo);
            let x1 = (h.lo + w * (i + 1) as f64 - lo) / (hi - lo);
            let top = rect.bottom() - (c as f32 / peak) * (rect.height() - 14.0);
            let bar = Rect::from_min_max(
                Pos2::new(rect.left() + x0 as f32 * rect.width(), top),
                Pos2::new(rect.left() + (x1 as f32 * rect.width()).max(x0 as f32 * rect.width() + 1.0), rect.bottom()),
            );
            p.rect_filled(bar, 0.0, color.gamma_multiply(0.75));
        }
    }
    let font = egui::FontId::proportional(10.0);
    p.text(rect.left_top() + Vec2::new(2.0, 1.0), egui::Align2::LEFT_TOP, format!("{lo:.3}{unit}"), font.clone(), Color32::LIGHT_GRAY);
    p.text(rect.right_top() + Vec2::new(-2.0, 1.0), egui::Align2::RIGHT_TOP, format!("{hi:.3}{unit}"), font, Color32::LIGHT_GRAY);
}

/// Remeshing controls: kind, ε (log slider) and the face count.
fn sizing_controls(ui: &mut egui::Ui, id: &str, sizing: &mut crate::design_link::SizingDesign, kinds: &[SizingKind]) {
    egui::ComboBox::from_id_salt(id).selected_text(sizing.kind.label()).show_ui(ui, |ui| {
        for &k in kinds {
            ui.selectable_value(&mut sizing.kind, k, k.label());
        }
    });
    match sizing.kind {
        SizingKind::Adaptive => {
            ui.add(egui::Slider::new(&mut sizing.epsilon, 2e-5..=1e-2).logarithmic(true).text("ε").custom_formatter(|x, _| format!("{x:.2e}")))
                .on_hover_text("Distance tolerance of the influence zones, relative to the bbox diagonal (Sec. 3): smaller ε, smaller faces");
        }
        SizingKind::Faces => {
            ui.add(egui::Slider::new(&mut sizing.faces, 50..=8000).logarithmic(true).text("faces"));
        }
        SizingKind::None => {}
    }
}

/// Total energy against iteration on a log scale, one colour per optimizer stage.
fn energy_plot(ui: &mut egui::Ui, series: &[(u32, String, f64)]) {
    let (rect, _) = ui.allocate_exact_size(Vec2::new(ui.available_width().min(260.0), 110.0), Sense::hover());
    let p = ui.painter();
    p.rect_filled(rect, 2.0, Color32::from_gray(30));
    let logs: Vec<f64> = series.iter().map(|(_, _, e)| e.max(1e-300).log10()).collect();
    let (lo, hi) = logs.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| (lo.min(x), hi.max(x)));
    let (lo, hi) = if hi - lo < 1e-9 { (lo - 0.5, hi + 0.5) } else { (lo, hi) };
    let last = series.last().map_or(1, |s| s.0).max(1) as f32;
    let inner = rect.shrink2(Vec2::new(4.0, 14.0));
    let at = |it: u32, y: f64| Pos2::new(inner.left() + inner.width() * it as f32 / last, inner.bottom() - inner.height() * ((y - lo) / (hi - lo)) as f32);
    let palette = [Color32::from_rgb(110, 150, 230), Color32::from_rgb(90, 190, 90), Color32::from_rgb(230, 170, 60), Color32::from_rgb(220, 80, 70)];
    let mut stage_index = 0;
    for k in 1..series.len() {
        if series[k].1 != series[k - 1].1 {
            stage_index += 1;
            let x = at(series[k].0, lo).x;
            p.line_segment([Pos2::new(x, rect.top()), Pos2::new(x, rect.bottom())], egui::Stroke::new(1.0, Color32::from_gray(60)));
            continue;
        }
        let color = palette[stage_index % palette.len()];
        p.line_segment([at(series[k - 1].0, logs[k - 1]), at(series[k].0, logs[k])], egui::Stroke::new(1.5, color));
    }
    let font = egui::FontId::proportional(10.0);
    let (it, stage, e) = series.last().map(|(i, s, e)| (*i, s.as_str(), *e)).unwrap_or((0, "", 0.0));
    p.text(rect.left_top() + Vec2::new(2.0, 1.0), egui::Align2::LEFT_TOP, format!("1e{hi:.1}"), font.clone(), Color32::LIGHT_GRAY);
    p.text(rect.left_bottom() + Vec2::new(2.0, -1.0), egui::Align2::LEFT_BOTTOM, format!("1e{lo:.1}"), font.clone(), Color32::LIGHT_GRAY);
    p.text(rect.right_top() + Vec2::new(-2.0, 1.0), egui::Align2::RIGHT_TOP, format!("{stage} · it {it} · E {e:.3e}"), font, Color32::LIGHT_GRAY);
}

/// A two-column table of labels and values.
fn key_values(ui: &mut egui::Ui, id: &str, rows: &[(&str, String)]) {
    egui::Grid::new(id).num_columns(2).show(ui, |ui| {
        for (k, v) in rows {
            ui.label(*k);
            ui.label(v);
            ui.end_row();
        }
    });
}

fn empty_mesh() -> MeshData {
    MeshData { generation: 0, positions: Vec::new(), normals: Vec::new(), triangles: Vec::new(), edges: Vec::new() }
}

fn central_sphere(fields: &[Field], v: usize) -> Option<[f32; 5]> {
    let s = find(fields, field::CENTRAL_SPHERES)?.as_f32()?;
    s.get(5 * v..5 * v + 5)?.try_into().ok()
}

/// Centre and signed radius of a normalized generalized sphere (a, b, c); `None` for a plane.
fn sphere_center_radius(s: &[f32; 5]) -> Option<(Vec3, f32)> {
    let a = s[0];
    if a.abs() < 1e-9 {
        return None;
    }
    Some((Vec3::new(s[1], s[2], s[3]) / (2.0 * a), 1.0 / (2.0 * a)))
}

/// Möller–Trumbore: ray parameter of the hit, if any.
fn ray_triangle(o: Vec3, d: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Option<f32> {
    let (e1, e2) = (b - a, c - a);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-12 {
        return None;
    }
    let inv = 1.0 / det;
    let t = o - a;
    let u = t.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = t.cross(e1);
    let v = d.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let s = e2.dot(q) * inv;
    (s > 0.0).then_some(s)
}

/// Counts `event`s dispatched on the window (automation and diagnostics hooks).
fn count_events(event: &str, ctx: &egui::Context) -> (Rc<RefCell<u32>>, Closure<dyn FnMut()>) {
    let count = Rc::new(RefCell::new(0));
    let (c2, ctx) = (count.clone(), ctx.clone());
    let c = Closure::<dyn FnMut()>::new(move || {
        *c2.borrow_mut() += 1;
        ctx.request_repaint();
    });
    if let Some(w) = web_sys::window() {
        let _ = w.add_event_listener_with_callback(event, c.as_ref().unchecked_ref());
    }
    (count, c)
}

fn location_hash() -> String {
    web_sys::window().and_then(|w| w.location().hash().ok()).unwrap_or_default()
}

/// A hidden `<input type=file>` whose chosen files land in `sink`.
fn make_file_input(
    sink: Rc<RefCell<Vec<web_sys::File>>>,
    ctx: egui::Context,
) -> (Option<web_sys::HtmlInputElement>, Option<Closure<dyn FnMut()>>) {
    let doc = web_sys::window().and_then(|w| w.document());
    let Some(doc) = doc else { return (None, None) };
    let Ok(el) = doc.create_element("input") else { return (None, None) };
    let Ok(input) = el.dyn_into::<web_sys::HtmlInputElement>() else { return (None, None) };
    input.set_type("file");
    input.set_accept(".obj,.gltf,.glb");
    input.set_id("sf-file-input");
    let _ = input.style().set_property("display", "none");
    if let Some(body) = doc.body() {
        let _ = body.append_child(&input);
    }
    let inp = input.clone();
    let closure = Closure::<dyn FnMut()>::new(move || {
        if let Some(files) = inp.files() {
            if let Some(f) = files.get(0) {
                sink.borrow_mut().push(f);
                ctx.request_repaint();
            }
        }
    });
    input.set_onchange(Some(closure.as_ref().unchecked_ref()));
    (Some(input), Some(closure))
}
