//! The main-thread app: an immediate-mode egui UI over the wgpu viewport. It never computes
//! geometry; it sends the design to the worker and draws the snapshots that come back.
//!
//! - [`state`]: what the app holds of the worker's results;
//! - [`messages`]: the reducer of worker messages;
//! - [`views`]: one view per method behind one trait: controls, results, layers, what its
//!   snapshots update;
//! - [`panels`]: the side panel's shared sections and widgets;
//! - [`view`]: the viewport (camera, the reference and the method's layers, picking);
//! - [`link`]: the design link in the URL;
//! - [`automation`]: the state JSON the end-to-end tests read;
//! - [`plots`], [`dom`]: painted plots and the page around the app.

mod automation;
mod dom;
mod link;
mod messages;
pub mod panels;
mod plots;
mod state;
mod view;
mod views;

use std::cell::RefCell;
use std::collections::VecDeque;
use std::rc::Rc;

use egui::{Color32, Rect, RichText};
use glam::Vec3;
use wasm_bindgen::prelude::*;

use crate::congruence::central_spheres::{JET_DEGREE_RANGE, JET_RINGS_RANGE};
use crate::design_link::{CameraState, ColorBy, Design, DesignSurface, Method, Shading};
use crate::pipeline::protocol::{StageId, StageRequest, ToWorker};
use crate::samples::Sample;
use crate::web::viewer::camera::OrbitCamera;
use crate::web::viewer::ViewerResources;
use crate::web::worker_client::{Wake, WorkerClient, LIVE_REPAINT_MS};
use dom::{count_events, make_file_input, now_ms, save_file};
use state::{Busy, Download, Notice, Origin, ScalarView, Scene, ShownError, UI_NOTICE_MS};
use views::MethodView;

/// How many frames' `ui` times are kept for the state's percentiles.
const UI_TIMES: usize = 120;

/// The side panel's width (points).
const SIDE_PANEL_WIDTH: f32 = 380.0;

/// Viewport background, also reported to tests.
pub const CLEAR_COLOR: Color32 = Color32::from_rgb(28, 30, 36);

pub struct App {
    design: Design,
    notices: Vec<Notice>,
    error: Option<ShownError>,
    /// The design link names a file the app does not have: the view asks for it by name.
    awaiting_file: Option<String>,
    /// The verdict of the last result: its method's guarantees, each measured on the result.
    verdict: Option<panels::ShownVerdict>,
    /// The moulds of the last panel result, and whether the panels show them.
    moulds: Option<crate::export::MouldReport>,
    mould_colours: bool,
    /// What `panels.step` and `panels.3dm` of the last panel result hold as exact surfaces.
    exact_surfaces: Option<crate::export::report::ExactSurfacesReport>,
    worker: Option<WorkerClient>,
    loaded: Option<Scene>,
    /// The file behind the loaded design, kept to restore it in a fresh worker.
    file: Option<web_sys::File>,
    /// A file sent to the worker but not yet confirmed as loaded.
    file_in_flight: Option<web_sys::File>,
    busy: Option<Busy>,
    /// The last stage that finished and how long it took from the request to its result (ms,
    /// in the page, for the automation state).
    last_run: Option<(StageId, f64)>,
    downloads: Vec<Download>,
    /// Method parameters changed while a slider is held: rerun on release.
    params_dirty: bool,
    /// Only the moulds (δ, K, units) changed: the worker exports its result again.
    moulds_dirty: bool,
    /// The method's request of the last run, to tell a change of moulds from a new run.
    last_request: Option<StageRequest>,
    /// One view per method ([`views::views`]).
    views: Vec<Box<dyn MethodView>>,
    /// A fresh worker is being given the current design back: keep the view and the message.
    restoring: bool,
    camera: OrbitCamera,
    camera_from_link: Option<CameraState>,
    selected: Option<usize>,
    scalars: Option<ScalarView>,
    /// What the camera fits of the layers drawn.
    extent: Option<state::Extent>,
    /// A double click asked to frame what is drawn.
    frame_requested: bool,
    generation: u64,
    backend: String,
    frames: u64,
    /// Main-thread time of the last frames' `ui` (ms), newest last.
    ui_ms: VecDeque<f64>,
    drawn: bool,
    viewport: Rect,
    last_fragment: String,
    last_state: String,
    picked_files: Rc<RefCell<Vec<web_sys::File>>>,
    crash_requests: Rc<RefCell<u32>>,
    _crash_listener: Closure<dyn FnMut()>,
    cancel_requests: Rc<RefCell<u32>>,
    _cancel_listener: Closure<dyn FnMut()>,
    /// Whether the bottom of the method's results shows in the side panel (the panel scrolls), and
    /// the panel's content and visible heights.
    results_visible: bool,
    side_panel_heights: (f32, f32),
    /// Where the Copy link button, the verdict and the downloads are (for the tests).
    copy_link_rect: Rect,
    verdict_rect: Rect,
    downloads_rect: Rect,
    side_panel_width: f32,
    /// Cancels asked for (Cancel button or automation), and how each was carried out.
    cancels: u32,
    cancels_in_worker: u32,
    /// The last cancel carried by shared memory: the worker's posted-message count at the
    /// request, until the app has handled those messages; then the ST iterations received by
    /// then, i.e. done before the request.
    cancel_posted: Option<u32>,
    iterations_at_cancel: Option<usize>,
    download_requests: Rc<RefCell<Vec<String>>>,
    _download_listener: Option<Closure<dyn FnMut(web_sys::CustomEvent)>>,
    file_input: Option<web_sys::HtmlInputElement>,
    _file_input_closure: Option<Closure<dyn FnMut()>>,
}

/// Installs the viewer's GPU resources; the backend's name ("WebGPU", "WebGL2"; empty without one).
fn install_viewer(cc: &eframe::CreationContext<'_>) -> String {
    let Some(rs) = cc.wgpu_render_state.as_ref() else { return String::new() };
    rs.renderer.write().callback_resources.insert(ViewerResources::new(&rs.device, rs.target_format));
    match rs.adapter.get_info().backend {
        egui_wgpu::wgpu::Backend::BrowserWebGpu => "WebGPU".into(),
        egui_wgpu::wgpu::Backend::Gl => "WebGL2".into(),
        other => format!("{other:?}"),
    }
}

impl App {
    pub fn new(cc: &eframe::CreationContext<'_>) -> Self {
        let backend = install_viewer(cc);
        cc.egui_ctx.set_theme(egui::Theme::Dark);
        let fragment = dom::location_hash();
        let (design, notices) = Design::from_fragment(&fragment);
        let ctx = cc.egui_ctx.clone();
        let repaint: Rc<dyn Fn(Wake)> = Rc::new(move |wake| match wake {
            Wake::Now => ctx.request_repaint(),
            Wake::Soon => ctx.request_repaint_after(std::time::Duration::from_millis(LIVE_REPAINT_MS)),
        });
        let (worker, error) = match WorkerClient::spawn(repaint) {
            Ok(w) => (Some(w), None),
            Err(e) => (None, Some(e.to_string())),
        };
        let picked_files = Rc::new(RefCell::new(Vec::new()));
        let (file_input, closure) = make_file_input(picked_files.clone(), cc.egui_ctx.clone());
        // Diagnostics: `window.dispatchEvent(new Event('sf-crash-worker'))` makes the worker panic.
        let (crash_requests, crash_listener) = count_events("sf-crash-worker", &cc.egui_ctx);
        // Automation: `new Event('sf-cancel')` presses Cancel.
        let (cancel_requests, cancel_listener) = count_events("sf-cancel", &cc.egui_ctx);
        // Automation: `new CustomEvent('sf-download', {detail: 'panels.glb'})` saves that file.
        let (download_requests, download_listener) = dom::queue_events("sf-download", &cc.egui_ctx);
        let mut app = Self {
            camera_from_link: design.camera,
            views: views::views(&design),
            design,
            notices: notices.into_iter().map(|n| Notice::new(n, Origin::Link)).collect(),
            error: error.map(|e| ShownError::new(e, Origin::Worker)),
            awaiting_file: None,
            verdict: None,
            moulds: None,
            exact_surfaces: None,
            mould_colours: true,
            worker,
            loaded: None,
            file: None,
            file_in_flight: None,
            busy: None,
            last_run: None,
            downloads: Vec::new(),
            params_dirty: false,
            moulds_dirty: false,
            last_request: None,
            restoring: false,
            camera: OrbitCamera::framing(Vec3::ZERO, 1.0),
            selected: None,
            scalars: None,
            extent: None,
            frame_requested: false,
            generation: 0,
            backend,
            frames: 0,
            ui_ms: VecDeque::with_capacity(UI_TIMES),
            drawn: false,
            viewport: Rect::NOTHING,
            last_fragment: fragment,
            last_state: String::new(),
            picked_files,
            crash_requests,
            _crash_listener: crash_listener,
            cancel_requests,
            _cancel_listener: cancel_listener,
            cancels: 0,
            cancels_in_worker: 0,
            cancel_posted: None,
            iterations_at_cancel: None,
            results_visible: false,
            side_panel_heights: (0.0, 0.0),
            copy_link_rect: Rect::NOTHING,
            verdict_rect: Rect::NOTHING,
            downloads_rect: Rect::NOTHING,
            side_panel_width: 0.0,
            download_requests,
            _download_listener: Some(download_listener),
            file_input,
            _file_input_closure: closure,
        };
        app.load_design_reference();
        app
    }

    /// Sends the design's reference surface to the worker (own files need the file itself).
    fn load_design_reference(&mut self) {
        let sample = match &self.design.reference {
            DesignSurface::Sample(s) => *s,
            DesignSurface::OwnFile(name) => match self.file.clone() {
                Some(f) => return self.load_file(f),
                // The link names a file the app does not have: the view asks for it, and the
                // link stays as it is until it comes.
                None => return self.await_file(name.clone()),
            },
        };
        self.send(&ToWorker::LoadSample(sample), None);
    }

    /// Nothing is shown but the request for the design's file `name`: what was loaded belongs
    /// to another design.
    fn await_file(&mut self, name: String) {
        self.awaiting_file = Some(name);
        self.loaded = None;
        for v in &mut self.views {
            v.clear();
        }
        self.clear_result();
        self.error = None;
        self.notices.retain(|n| n.origin == Origin::Link);
        self.busy = None;
        self.selected = None;
        self.scalars = None;
    }

    /// Forgets the last result's verdict, moulds, surfaces and files.
    fn clear_result(&mut self) {
        self.verdict = None;
        self.moulds = None;
        self.exact_surfaces = None;
        self.downloads.clear();
    }

    fn load_file(&mut self, file: web_sys::File) {
        // Refused before a byte is read: the worker would hold the whole file.
        if file.size() > crate::import::MAX_BYTES as f64 {
            let name = crate::text::clip(&file.name(), 120);
            self.error = Some(ShownError::new(
                format!("{name}: {:.0} bytes exceed the limit of {} ({} MiB)", file.size(), crate::import::MAX_BYTES, crate::import::MAX_BYTES >> 20),
                Origin::Reference,
            ));
            return;
        }
        self.send(&ToWorker::LoadFile { name: file.name() }, Some(&file));
        self.file_in_flight = Some(file);
        self.busy = Some(Busy::new(StageId::Import));
    }

    fn send(&mut self, msg: &ToWorker, file: Option<&web_sys::File>) {
        match &self.worker {
            Some(w) => w.send(msg, file),
            None => self.error = Some(ShownError::new("The pipeline worker is not running; reload the page.", Origin::Worker)),
        }
    }

    fn notice(&mut self, text: impl Into<String>, origin: Origin) {
        self.notices.push(Notice::new(text, origin));
    }

    /// Runs the design's stages in the worker (the curvature first; the method reuses it).
    fn run_method(&mut self) {
        // A new run replaces what the last one said, and the error of the last run or file.
        self.clear_result();
        self.error = None;
        self.notices.retain(|n| n.origin != Origin::Run);
        if self.loaded.is_none() {
            return;
        }
        if self.busy.as_ref().is_some_and(|b| b.stage != StageId::Import) {
            self.cancel();
        }
        let stages = self.design.stage_requests();
        for v in &mut self.views {
            if v.method() == self.design.method {
                v.start();
            } else {
                v.clear();
            }
        }
        if self.design.color == ColorBy::Sizing {
            self.scalars = None;
        }
        let last = stages.last().map_or(StageId::Curvature, |s| s.name());
        self.busy = Some(Busy::new(last));
        self.last_request = stages.last().cloned();
        for stage in stages {
            self.send(&ToWorker::Run(Box::new(stage)), None);
        }
    }

    /// New moulds (δ, K or units) for the finished result: the worker exports it again and the
    /// view keeps everything else. Anything more (no result yet, a run under way, a method that
    /// optimizes for its moulds) runs the method again.
    fn regroup(&mut self) {
        let Some(request) = self.design.stage_requests().pop() else { return };
        let finished = self.moulds.is_some() && self.busy.is_none();
        if !finished || !self.last_request.as_ref().is_some_and(|l| request.same_result_as(l)) {
            self.run_method();
            return;
        }
        self.busy = Some(Busy::new(request.name()));
        self.last_request = Some(request.clone());
        self.send(&ToWorker::Run(Box::new(request)), None);
    }

    fn cancel(&mut self) {
        self.cancels += 1;
        if let Some(w) = self.worker.as_mut() {
            if let Some(posted) = w.cancel() {
                self.cancels_in_worker += 1;
                self.cancel_posted = Some(posted);
                self.iterations_at_cancel = None;
                self.note_cancel_point();
            } else {
                // Without shared memory the worker was replaced; its Ready reloads the design.
                self.notice("Cancelled (the worker was restarted).", Origin::Run);
            }
        }
        self.busy = None;
    }

    // --- UI --------------------------------------------------------------------------------

    fn top_bar(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            ui.heading("Spherical Faces");
            ui.separator();
            let current = match &self.design.reference {
                DesignSurface::Sample(s) => s.title().to_string(),
                DesignSurface::OwnFile(name) => name.clone(),
            };
            egui::ComboBox::from_id_salt("sample").selected_text(current).show_ui(ui, |ui| {
                for s in Sample::ALL {
                    let selected = self.design.reference == DesignSurface::Sample(s);
                    if ui.selectable_label(selected, s.title()).on_hover_text(s.description()).clicked() && !selected {
                        self.send(&ToWorker::LoadSample(s), None);
                        self.busy = Some(Busy::new(StageId::Import));
                    }
                }
            });
            if ui
                .button("Open…")
                .on_hover_text("OBJ, glTF (.gltf with embedded data), GLB, or a B-spline surface (.json); or drop a file on the view")
                .clicked()
            {
                if let Some(input) = &self.file_input {
                    input.set_value("");
                    input.click();
                }
            }
            let copy = ui.button("Copy link").on_hover_text("Copy a link that restores this design");
            self.copy_link_rect = copy.rect;
            if copy.clicked() {
                let url = self.share_url();
                ui.ctx().copy_text(url);
                self.notice("Design link copied.", Origin::Ui);
            }
            ui.with_layout(egui::Layout::right_to_left(egui::Align::Center), |ui| {
                let label = if self.backend.is_empty() { "no GPU backend".to_string() } else { self.backend.clone() };
                ui.label(RichText::new(label).monospace()).on_hover_text("Graphics backend in use");
            });
        });
    }

    /// The view of the design's method.
    fn view(&self) -> &dyn MethodView {
        let m = self.design.method;
        self.views.iter().find(|v| v.method() == m).expect("a view per method").as_ref()
    }

    fn side_panel(&mut self, ui: &mut egui::Ui) {
        let out = egui::ScrollArea::vertical().auto_shrink([false, false]).show(ui, |ui| {
            if self.error.is_some() {
                self.error_box(ui);
                ui.add_space(6.0);
            }
            if let Some(name) = &self.awaiting_file {
                ui.colored_label(Color32::from_rgb(240, 180, 80), RichText::new(state::drop_prompt(name)).strong());
                ui.add_space(6.0);
            }
            // The verdict first: whether the result can be built is what a designer reads first.
            if let (Some(v), None) = (&self.verdict, &self.busy) {
                let r = panels::verdict(ui, v).rect;
                self.verdict_rect = r;
                ui.add_space(4.0);
            } else {
                self.verdict_rect = Rect::NOTHING;
            }
            self.method_section(ui);
            ui.separator();
            self.display_section(ui);
            ui.separator();
            let picked = match self.awaiting_file {
                None => panels::info::show(ui, self.loaded.as_ref(), self.selected, self.design.fabrication.units),
                Some(_) => None,
            };
            if let Some(k) = picked {
                self.send(&ToWorker::PickObject(k), None);
                self.busy = Some(Busy::new(StageId::Import));
            }
            if self.loaded.is_some() {
                let results = ui.scope(|ui| {
                    self.view().results(ui, &self.design);
                    if let Some(m) = self.moulds.as_ref().filter(|_| self.design.method != Method::Curvature) {
                        ui.separator();
                        panels::moulds::results(ui, m);
                    }
                });
                let bottom = results.response.rect.left_bottom() + egui::vec2(1.0, -1.0);
                self.results_visible = ui.clip_rect().contains(bottom);
            }
            self.downloads_section(ui);
            self.notices_section(ui);
        });
        self.side_panel_heights = (out.content_size.y, out.inner_rect.height());
    }

    /// The error, with what it offers: the remesh a method's size refusal asks for, and the
    /// menu's other methods when a method refused its input.
    fn error_box(&mut self, ui: &mut egui::Ui) {
        let Some(err) = self.error.as_ref() else { return };
        let (text, remesh_to, offers) = (err.text.clone(), err.remesh_to, self.offered_methods());
        egui::Frame::new().fill(Color32::from_rgb(90, 24, 24)).inner_margin(6.0).corner_radius(4.0).show(ui, |ui| {
            ui.label(RichText::new(text).color(Color32::WHITE));
            if !offers.is_empty() {
                ui.label(RichText::new("Or choose another method:").color(Color32::WHITE).small());
                for m in offers {
                    if ui.small_button(m.title()).on_hover_text("switch to this method and run it").clicked() {
                        self.switch_method(m);
                    }
                }
            }
            ui.horizontal(|ui| {
                if let Some(n) = remesh_to {
                    if ui.small_button(format!("Remesh to about {n} faces and run")).clicked() {
                        let m = self.design.method;
                        if let Some(v) = self.views.iter().find(|v| v.method() == m) {
                            v.remesh_to(&mut self.design, n);
                        }
                        self.run_method();
                    }
                }
                if ui.small_button("Dismiss").clicked() {
                    self.error = None;
                }
            });
        });
    }

    /// The menu's other methods, offered when a method refused its input.
    fn offered_methods(&self) -> Vec<Method> {
        let Some(refused) = self.error.as_ref().and_then(|e| e.refused_by) else { return Vec::new() };
        Method::all().filter(|m| matches!(m, Method::Of(o) if *o != refused)).collect()
    }

    /// The design's method becomes `method`, and runs.
    fn switch_method(&mut self, method: Method) {
        // The colours follow the method where they were the old method's own.
        let before = self.view().colors();
        self.design.method = method;
        if self.design.color == before {
            self.design.color = self.view().colors();
        }
        self.run_method();
    }

    /// The method, the jet fit, and the method's own controls (a change reruns it).
    fn method_section(&mut self, ui: &mut egui::Ui) {
        ui.strong("Method");
        let mut method = self.design.method;
        egui::ComboBox::from_id_salt("method").selected_text(method.title()).show_ui(ui, |ui| {
            for m in Method::all() {
                ui.selectable_value(&mut method, m, m.title());
            }
        });
        if method != self.design.method {
            self.switch_method(method);
        }
        ui.label(RichText::new("Curvature by jet fitting (Sec. 2.6)").small());
        let mut jet = self.design.jet.clone();
        let mut degree = jet.degree as usize;
        ui.add(egui::Slider::new(&mut degree, JET_DEGREE_RANGE.range()).text("jet degree"));
        jet.degree = degree as u8;
        ui.add(egui::Slider::new(&mut jet.max_rings, JET_RINGS_RANGE.range()).text("max rings"));
        if jet != self.design.jet {
            self.design.jet = jet;
            self.run_method();
        }
        let m = self.design.method;
        let view = self.views.iter_mut().find(|v| v.method() == m).expect("a view per method");
        self.params_dirty |= view.controls(ui, &mut self.design);
        if m != Method::Curvature {
            ui.separator();
            self.moulds_dirty |= panels::moulds::controls(ui, &mut self.design.fabrication, self.moulds.as_ref());
        }
        if (self.params_dirty || self.moulds_dirty) && !ui.input(|i| i.pointer.any_down()) {
            if self.params_dirty {
                self.run_method();
            } else {
                self.regroup();
            }
            (self.params_dirty, self.moulds_dirty) = (false, false);
        }
    }

    fn display_section(&mut self, ui: &mut egui::Ui) {
        ui.strong("Display");
        ui.horizontal(|ui| {
            for s in Shading::ALL {
                ui.radio_value(&mut self.design.shading, s, s.key());
            }
        });
        ui.checkbox(&mut self.design.edges, "edges");
        if self.design.method != Method::Curvature {
            ui.checkbox(&mut self.mould_colours, "panels in their moulds' colours");
        }
        egui::ComboBox::from_label("colour by").selected_text(self.design.color.label()).show_ui(ui, |ui| {
            for c in ColorBy::ALL {
                ui.selectable_value(&mut self.design.color, c, c.label());
            }
        });
    }

    /// The result's files; a result that misses its guarantees says so above them, and each
    /// file is marked as coming from it.
    fn downloads_section(&mut self, ui: &mut egui::Ui) {
        if self.downloads.is_empty() {
            self.downloads_rect = Rect::NOTHING;
            return;
        }
        ui.separator();
        let failed = self.verdict.as_ref().filter(|v| !v.holds);
        let top = ui.strong("Downloads").rect;
        if let Some(v) = failed {
            panels::missed_above_downloads(ui, v);
        }
        let mut saved = None;
        ui.horizontal_wrapped(|ui| {
            for d in &self.downloads {
                let (label, hover) = match failed {
                    Some(_) => (
                        RichText::new(format!("⚠ {}", d.name)).color(panels::MISSED_COLOR),
                        format!("{} bytes, from a result that misses its guarantees", d.bytes.len()),
                    ),
                    None => (RichText::new(&d.name), format!("{} bytes", d.bytes.len())),
                };
                if ui.button(label).on_hover_text(hover).clicked() {
                    saved = Some(d.name.clone());
                }
            }
        });
        self.downloads_rect = top;
        if let Some(name) = saved {
            self.save_download(&name);
        }
        if let Some(e) = &self.exact_surfaces {
            let text = RichText::new(format!("panels.step, panels.3dm: {}", e.describe())).small();
            if e.refused.is_empty() {
                ui.label(text);
            } else {
                ui.colored_label(Color32::from_rgb(240, 180, 80), text);
            }
        }
    }

    fn notices_section(&mut self, ui: &mut egui::Ui) {
        if self.notices.is_empty() {
            return;
        }
        ui.separator();
        ui.horizontal(|ui| {
            ui.strong("Notices");
            if ui.small_button("clear").clicked() {
                self.notices.clear();
            }
        });
        for n in self.notices.iter().rev().take(8) {
            ui.label(RichText::new(&n.text).small());
        }
    }

    /// What the tests read of the side panel and the buttons they click.
    fn side_panel_state(&self) -> serde_json::Value {
        let rect = |r: Rect| (r != Rect::NOTHING).then(|| [r.min.x, r.min.y, r.width(), r.height()]);
        serde_json::json!({
            "results_visible": self.results_visible,
            "content_height": self.side_panel_heights.0,
            "visible_height": self.side_panel_heights.1,
            "width": self.side_panel_width,
            "copy_link_button": rect(self.copy_link_rect),
            "verdict": rect(self.verdict_rect),
            "downloads": rect(self.downloads_rect),
        })
    }
}

impl App {
    /// Downloads, crashes and cancels asked for by automation events, and dropped or picked files.
    fn take_requests(&mut self, ui: &egui::Ui) {
        let requested: Vec<String> = self.download_requests.borrow_mut().drain(..).collect();
        for name in requested {
            self.save_download(&name);
        }
        if std::mem::take(&mut *self.crash_requests.borrow_mut()) > 0 {
            self.send(&ToWorker::Crash, None);
        }
        if std::mem::take(&mut *self.cancel_requests.borrow_mut()) > 0 && self.busy.is_some() {
            self.cancel();
        }
        // Dropped files (eframe) and picked files (the Open… dialog).
        let dropped: Vec<web_sys::File> = ui.input(|i| i.raw.dropped_files.iter().filter_map(|f| f.web_file().cloned()).collect());
        let picked: Vec<web_sys::File> = self.picked_files.borrow_mut().drain(..).collect();
        if let Some(f) = dropped.into_iter().chain(picked).last() {
            self.load_file(f);
        }
    }

    /// Saves the download `name`.
    fn save_download(&mut self, name: &str) {
        let saved = match self.downloads.iter().find(|d| d.name == name) {
            Some(d) => save_file(&d.name, &d.mime, &d.bytes).map_err(|e| format!("could not save {name}: {e:?}")),
            None => Err(format!("no file named '{name}' to download yet")),
        };
        if let Err(e) = saved {
            self.notice(e, Origin::Ui);
        }
    }

    /// The running stage's progress bar with Cancel; the status bar of a missed guarantee.
    fn status_bars(&mut self, ui: &mut egui::Ui) {
        if self.busy.is_some() {
            egui::Panel::bottom("progress").show(ui, |ui| {
                ui.horizontal(|ui| {
                    let (frac, text) = match self.busy.as_ref().and_then(|b| b.progress.as_ref()) {
                        Some(p) if p.total > 0 => {
                            (p.iteration as f32 / p.total as f32, format!("{} {} {}/{}", p.stage, p.detail, p.iteration, p.total))
                        }
                        _ => (0.0, self.busy.as_ref().map(|b| b.stage.to_string()).unwrap_or_default()),
                    };
                    if ui.button("Cancel").clicked() {
                        self.cancel();
                    }
                    ui.add(egui::ProgressBar::new(frac).text(text).animate(true));
                });
            });
        }
        if let (None, Some(v)) = (&self.busy, self.verdict.as_ref().filter(|v| !v.holds)) {
            egui::Panel::bottom("verdict").show(ui, |ui| {
                ui.colored_label(panels::MISSED_COLOR, RichText::new(format!("✘ {}", v.line)).strong()).on_hover_text(&v.technical);
            });
        }
    }
}

impl eframe::App for App {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        let started = now_ms();
        self.frames += 1;
        self.notices.retain(|n| n.origin != Origin::Ui || started - n.since_ms < UI_NOTICE_MS);
        self.handle_messages();
        self.apply_link_if_changed();
        self.take_requests(ui);
        egui::Panel::top("top").show(ui, |ui| self.top_bar(ui));
        self.status_bars(ui);
        // One width whatever the results hold: the view does not jump when they arrive.
        let side = egui::Panel::left("side").exact_size(SIDE_PANEL_WIDTH).resizable(false).show(ui, |ui| self.side_panel(ui));
        self.side_panel_width = side.response.rect.width();
        let hovering = ui.input(|i| !i.raw.hovered_files.is_empty());
        egui::CentralPanel::no_frame().show(ui, |ui| {
            self.viewport(ui);
            if hovering {
                ui.painter().rect_filled(self.viewport, 0.0, Color32::from_black_alpha(140));
                ui.painter().text(
                    self.viewport.center(),
                    egui::Align2::CENTER_CENTER,
                    "Drop OBJ, glTF, GLB, a B-spline .json or a Rhino .3dm to load",
                    egui::FontId::proportional(22.0),
                    Color32::WHITE,
                );
            }
        });
        let dragging = ui.input(|i| i.pointer.any_down());
        self.write_link(dragging);
        self.publish_state();
        if self.ui_ms.len() == UI_TIMES {
            self.ui_ms.pop_front();
        }
        self.ui_ms.push_back(now_ms() - started);
        if !self.drawn {
            ui.ctx().request_repaint();
        } else if self.busy.is_some() {
            // The elapsed time ticks; worker messages wake the view sooner.
            ui.ctx().request_repaint_after(std::time::Duration::from_millis(LIVE_REPAINT_MS));
        }
    }

    fn clear_color(&self, _visuals: &egui::Visuals) -> [f32; 4] {
        CLEAR_COLOR.to_normalized_gamma_f32()
    }
}
