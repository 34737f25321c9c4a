//! The automation contract of the end-to-end tests: the app's state as JSON in
//! `<pre id="sf-state">`, rewritten when it changes.

use std::collections::BTreeMap;

use serde::Serialize;

use super::{App, CLEAR_COLOR};
use crate::design_link::Method;
use crate::pipeline::protocol::StageId;
use crate::stats::percentile;

/// Whether the page is cross-origin isolated (shared memory, so Cancel reaches the worker).
fn cross_origin_isolated() -> bool {
    js_sys::Reflect::get(&js_sys::global(), &"crossOriginIsolated".into()).ok().and_then(|v| v.as_bool()).unwrap_or(false)
}

/// The state the tests read. Each method's view adds its own section under its name
/// ([`super::views::MethodView::automation`]).
#[derive(Serialize)]
struct AutomationState<'a> {
    ready: bool,
    backend: &'a str,
    frames: u64,
    source: String,
    vertices: usize,
    faces: usize,
    boundary_loops: usize,
    non_manifold_edges: usize,
    busy: bool,
    /// From the request of the last finished run to its result, in the page (ms).
    last_run: Option<LastRun>,
    stage: String,
    /// The progress the app shows for the running stage: its step, done and total.
    progress: Option<(&'a str, u32, u32)>,
    curvature_ready: bool,
    color_by: &'static str,
    shading: &'static str,
    edges: bool,
    jet_degree: u8,
    error: Option<&'a str>,
    /// The menu's methods the error offers (a method refused its input).
    error_offers: Vec<&'static str>,
    /// The missed guarantees of the last result as the report names them, None when it meets
    /// them (or there is none).
    missed_guarantees: Option<&'a str>,
    /// The same in a designer's words, as the side panel and the status bar show them.
    missed_in_words: Vec<&'a str>,
    /// The downloads are marked as coming from a result that misses its guarantees.
    downloads_marked_failed: bool,
    /// The design's file the view asks for (a link that names a file the app does not have).
    awaiting_file: Option<&'a str>,
    /// The moulds of the last panel result: how many, within what (model units), and how many
    /// panels have exactly their mould's radius.
    moulds: Option<(usize, f64, usize)>,
    /// The exact surfaces of the last panel result: panels, support elements, refused ones.
    exact_surfaces: Option<(usize, usize, usize)>,
    notices: Vec<&'a str>,
    design_link: &'a str,
    clear_color: [u8; 3],
    viewport: [f32; 4],
    worker_restarts: u32,
    ui_ms_median: f64,
    ui_ms_p95: f64,
    ui_ms_max: f64,
    selected_vertex: Option<usize>,
    method: &'static str,
    downloads: Vec<&'a str>,
    file_objects: Vec<&'a str>,
    file_object: Option<usize>,
    is_bspline: bool,
    cancels: Cancels,
    side_panel: serde_json::Value,
    #[serde(flatten)]
    views: BTreeMap<&'static str, serde_json::Value>,
}

#[derive(Serialize)]
struct LastRun {
    stage: StageId,
    ms: f64,
}

#[derive(Serialize)]
struct Cancels {
    requested: u32,
    in_worker: u32,
    st_adapted_iterations_at_request: Option<usize>,
    cross_origin_isolated: bool,
}

impl App {
    pub(super) fn publish_state(&mut self) {
        let info = self.loaded.as_ref().map(|l| &l.info);
        let stats = info.map(|i| i.stats).unwrap_or_default();
        let vp = self.viewport;
        let missed = self.verdict.as_ref().filter(|v| !v.holds);
        let state = AutomationState {
            ready: self.drawn,
            backend: &self.backend,
            frames: self.frames,
            source: info.map_or(String::new(), |i| i.source.label()),
            vertices: stats.vertices,
            faces: stats.faces,
            boundary_loops: stats.boundary_loops,
            non_manifold_edges: stats.non_manifold_edges,
            busy: self.busy.is_some(),
            last_run: self.last_run.map(|(stage, ms)| LastRun { stage, ms }),
            stage: self.busy.as_ref().map(|b| b.stage.to_string()).unwrap_or_default(),
            progress: self.busy.as_ref().and_then(|b| b.progress.as_ref()).map(|p| (p.detail.as_str(), p.iteration, p.total)),
            curvature_ready: self.loaded.as_ref().and_then(|l| l.curvature.as_ref()).is_some_and(|c| c.summary.is_some()),
            color_by: self.design.color.key(),
            shading: self.design.shading.key(),
            edges: self.design.edges,
            jet_degree: self.design.jet.degree,
            error: self.error.as_ref().map(|e| e.text.as_str()),
            error_offers: self.offered_methods().into_iter().map(|m| m.title()).collect(),
            missed_guarantees: missed.map(|v| v.technical.as_str()),
            missed_in_words: missed.map_or(Vec::new(), |v| v.misses.iter().map(|m| m.0.as_str()).collect()),
            downloads_marked_failed: missed.is_some() && !self.downloads.is_empty(),
            awaiting_file: self.awaiting_file.as_deref(),
            moulds: self.moulds.as_ref().map(|m| (m.count, m.tolerance, m.snap.snapped)),
            exact_surfaces: self.exact_surfaces.as_ref().map(|e| (e.panels, e.support_elements, e.refused.len())),
            notices: self.notices.iter().map(|n| n.text.as_str()).collect(),
            design_link: &self.last_fragment,
            clear_color: [CLEAR_COLOR.r(), CLEAR_COLOR.g(), CLEAR_COLOR.b()],
            viewport: [vp.min.x, vp.min.y, vp.width(), vp.height()],
            worker_restarts: self.worker.as_ref().map_or(0, |w| w.restarts),
            ui_ms_median: percentile(self.ui_ms.iter().copied(), 0.5),
            ui_ms_p95: percentile(self.ui_ms.iter().copied(), 0.95),
            ui_ms_max: self.ui_ms.iter().copied().fold(0.0, f64::max),
            selected_vertex: self.selected,
            method: self.design.method.key(),
            downloads: self.downloads.iter().map(|d| d.name.as_str()).collect(),
            file_objects: info.map_or(Vec::new(), |i| i.objects.iter().map(|o| o.name.as_str()).collect()),
            file_object: info.and_then(|i| i.object),
            is_bspline: info.is_some_and(|i| i.bspline.is_some()),
            cancels: Cancels {
                requested: self.cancels,
                in_worker: self.cancels_in_worker,
                st_adapted_iterations_at_request: self.iterations_at_cancel,
                cross_origin_isolated: cross_origin_isolated(),
            },
            side_panel: self.side_panel_state(),
            views: self.views.iter().filter(|v| v.method() != Method::Curvature).map(|v| (v.name(), v.automation())).collect(),
        };
        let state = serde_json::to_string(&state).expect("the automation state serializes");
        if state != self.last_state {
            if let Some(el) = web_sys::window().and_then(|w| w.document()).and_then(|d| d.get_element_by_id("sf-state")) {
                el.set_text_content(Some(&state));
            }
            self.last_state = state;
        }
    }
}
