//! The design link: the URL fragment follows the design, and a fragment the user edits or
//! navigates to is applied.

use glam::Vec3;
use wasm_bindgen::prelude::*;

use super::dom::location_hash;
use super::state::{Notice, Origin};
use super::App;
use crate::design_link::{CameraState, Design};

impl App {
    pub(super) fn apply_link_if_changed(&mut self) {
        let hash = location_hash();
        if hash == self.last_fragment {
            return;
        }
        // The user edited or navigated the link: apply it, as the sliders would. A new link
        // replaces the last one's notices.
        self.last_fragment = hash.clone();
        let (design, notices) = Design::from_fragment(&hash);
        self.notices.retain(|n| n.origin != Origin::Link);
        self.notices.extend(notices.into_iter().map(|n| Notice::new(n, Origin::Link)));
        let reference_changed = design.reference != self.design.reference || self.awaiting_file.is_some();
        // Everything that defines the result reruns it; the moulds alone (δ, K, unit) group it
        // again.
        let rerun = design.jet != self.design.jet || design.method != self.design.method || design.methods != self.design.methods;
        let regroup = design.fabrication != self.design.fabrication;
        self.camera_from_link = design.camera;
        for v in &mut self.views {
            v.link_applied(&design);
        }
        self.design = design;
        if reference_changed {
            self.load_design_reference();
        } else {
            self.apply_link_camera();
            if rerun {
                self.run_method();
            } else if regroup {
                self.regroup();
            }
        }
    }

    /// The camera the link holds, once.
    pub(super) fn apply_link_camera(&mut self) {
        if let Some(c) = self.camera_from_link.take() {
            self.camera.yaw = c.yaw as f32;
            self.camera.pitch = c.pitch as f32;
            self.camera.distance = c.distance as f32;
            self.camera.target = Vec3::new(c.target[0] as f32, c.target[1] as f32, c.target[2] as f32);
        }
    }

    pub(super) fn write_link(&mut self, dragging: bool) {
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

    pub(super) fn share_url(&self) -> String {
        let w = web_sys::window();
        let base = w
            .and_then(|w| {
                let l = w.location();
                Some(format!("{}{}{}", l.origin().ok()?, l.pathname().ok()?, l.search().ok()?))
            })
            .unwrap_or_default();
        format!("{base}{}", self.last_fragment)
    }
}
