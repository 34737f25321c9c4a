//! The automation contract of the end-to-end tests: the app's state as JSON in
//! `<pre id="sf-state">`, rewritten when it changes.

use super::{App, CLEAR_COLOR};
use crate::stats::percentile;

/// Whether the page is cross-origin isolated (shared memory, so Cancel reaches the worker).
fn cross_origin_isolated() -> bool {
    js_sys::Reflect::get(&js_sys::global(), &"crossOriginIsolated".into())
        .ok()
        .and_then(|v| v.as_bool())
        .unwrap_or(false)
}

impl App {
    pub(super) fn publish_state(&mut self) {
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
        let curvature_ready = self
            .loaded
            .as_ref()
            .and_then(|l| l.curvature.as_ref())
            .is_some_and(|c| c.summary.is_some());
        let vp = self.viewport;
        let mut state = serde_json::json!({
            "ready": self.drawn,
            "backend": self.backend,
            "frames": self.frames,
            "source": source,
            "vertices": v, "faces": f, "boundary_loops": bl, "non_manifold_edges": nm,
            "busy": self.busy.is_some(),
            // From the request of the last finished run to its result, in the page (ms).
            "last_run": self.last_run.as_ref().map(|(stage, ms)| serde_json::json!({ "stage": stage, "ms": ms })),
            "stage": self.busy.as_ref().map(|b| b.stage.clone()).unwrap_or_default(),
            // The progress the app shows for the running stage: its step, done and total.
            "progress": self.busy.as_ref().and_then(|b| b.progress.as_ref()).map(|p| serde_json::json!([p.detail, p.iteration, p.total])),
            "curvature_ready": curvature_ready,
            "color_by": self.design.color.key(),
            "shading": self.design.shading.key(),
            "edges": self.design.edges,
            "jet_degree": self.design.jet.degree,
            "error": self.error,
            // The status bar's line when the last result misses its method's guarantees.
            "missed_guarantees": self.missed_guarantees,
            "notices": self.notices,
            "design_link": self.last_fragment,
            "clear_color": [CLEAR_COLOR.r(), CLEAR_COLOR.g(), CLEAR_COLOR.b()],
            "viewport": [vp.min.x, vp.min.y, vp.width(), vp.height()],
            "worker_restarts": self.worker.as_ref().map_or(0, |w| w.restarts),
            "ui_ms_median": percentile(self.ui_ms.iter().copied(), 0.5),
            "ui_ms_p95": percentile(self.ui_ms.iter().copied(), 0.95),
            "ui_ms_max": self.ui_ms.iter().copied().fold(0.0, f64::max),
            "selected_vertex": self.selected,
            "method": self.design.method.key(),
            "downloads": self.downloads.iter().map(|d| d.name.clone()).collect::<Vec<_>>(),
            "file_objects": self.loaded.as_ref().map_or(Vec::new(), |l| l.info.objects.iter().map(|o| o.name.clone()).collect::<Vec<_>>()),
            "file_object": self.loaded.as_ref().and_then(|l| l.info.object),
            "is_bspline": self.loaded.as_ref().is_some_and(|l| l.info.bspline.is_some()),
        });
        state["cancels"] = serde_json::json!({
            "requested": self.cancels,
            "in_worker": self.cancels_in_worker,
            "st_adapted_iterations_at_request": self.iterations_at_cancel,
            "cross_origin_isolated": cross_origin_isolated(),
        });
        state["side_panel"] = self.side_panel_state();
        let st_support = self.loaded.as_ref().and_then(|l| l.st_support.as_ref());
        state["st_support"] = serde_json::json!({
            "ready": st_support.is_some_and(|s| s.summary.is_some()),
            "panels": st_support.and_then(|s| s.summary.as_ref()).map_or(0, |s| s.report.output.panels),
        });
        state["st_adapted"] = serde_json::json!(self
            .loaded
            .as_ref()
            .and_then(|l| l.st_adapted.as_ref())
            .map(|a| serde_json::json!({
                "sizing": a.sizing.as_ref().map_or(0, Vec::len),
                "remeshed_faces": a.remeshed.as_ref().map_or(0, |m| m.triangles.len() / 3),
                "panel_iteration": a.panel_iteration,
                "panel_snapshots": a.panel_snapshots,
                "panel_triangles": a.panels.as_ref().map_or(0, |m| m.triangles.len() / 3),
                "energies": a.energy.len(),
                "ready": a.summary.is_some(),
                "panels": a.summary.as_ref().map_or(0, |s| s.report.output.panels),
                "timings_ms": a.summary.as_ref().map(|s| &s.report.timings_ms),
            })));
        state["sq"] = serde_json::json!(self.loaded.as_ref().and_then(|l| l.sq.as_ref()).map(|v| serde_json::json!({
            "line_snapshots": v.line_snapshots,
            "line_iteration": v.line_iteration,
            "lines": v.lines.as_ref().map_or(0, |m| m.edges.len() / 2),
            "initial_lines": v.initial_lines.as_ref().map_or(0, |m| m.edges.len() / 2),
            "cross_field_arms": v.cross_field_arms,
            "energies": v.energy.len(),
            "terms": v.energy.last().map(|(_, _, e)| e.iter().map(|e| e.name.clone()).collect::<Vec<_>>()).unwrap_or_default(),
            // The progress steps that sent energies, in order of first appearance.
            "energy_steps": v.energy.iter().fold(Vec::<String>::new(), |mut acc, (_, step, _)| {
                if !acc.contains(step) {
                    acc.push(step.clone());
                }
                acc
            }),
            "quad_mesh_edges": v.quad_mesh.as_ref().map_or(0, |m| m.edges.len() / 2),
            "panel_triangles": v.panels.as_ref().map_or(0, |m| m.triangles.len() / 3),
            "support_triangles": v.support.as_ref().map_or(0, |m| m.triangles.len() / 3),
            "axes": v.axes.as_ref().map_or(0, |m| m.edges.len() / 2),
            "mesh": v.summary.as_ref().and_then(|s| s.section.sq_mesh.as_ref().map(|m| m.figures)),
            "refused": v.refused_h.is_some(),
            "ready": v.summary.is_some(),
            "report": v.summary.as_ref().map(|s| &s.report),
        })));
        let state = state.to_string();
        if state != self.last_state {
            if let Some(el) = web_sys::window()
                .and_then(|w| w.document())
                .and_then(|d| d.get_element_by_id("sf-state"))
            {
                el.set_text_content(Some(&state));
            }
            self.last_state = state;
        }
    }
}
