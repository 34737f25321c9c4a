//! The viewport: camera input, picking, the reference, and the layers the method's view draws
//! ([`super::views::MethodView::draw`]).

use std::sync::Arc;

use egui::{Color32, Pos2, Rect, Sense, Vec2};
use glam::{Mat4, Vec3};

use super::panels::info::{center_radius, central_sphere};
use super::state::{drop_prompt, framing, Extent, ScalarView};
use super::views::method_view::{Frame, Legend};
use super::{App, CLEAR_COLOR};
use crate::design_link::{ColorBy, Shading};
use crate::pipeline::fields::{field, find};
use crate::web::colormap;
use crate::web::viewer::camera::OrbitCamera;
use crate::web::viewer::picking::pick_vertex;
use crate::web::viewer::{ColorMap, Geometry, Layer, ScalarData, Style, ViewerFrame};

impl App {
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
            let values =
                if color == ColorBy::Sizing { self.view().sizing()?.to_vec() } else { find(&l.curvature.as_ref()?.fields, key)?.as_f32()?.to_vec() };
            let (range, diverging) = colormap::robust_range(&values);
            self.generation += 1;
            self.scalars = Some(ScalarView { color, data: Arc::new(ScalarData { generation: self.generation, values }), range, diverging });
        }
        self.scalars.as_ref()
    }

    pub(super) fn viewport(&mut self, ui: &mut egui::Ui) {
        let rect = ui.available_rect_before_wrap();
        self.viewport = rect;
        let response = ui.allocate_rect(rect, Sense::click_and_drag());
        ui.painter().rect_filled(rect, 0.0, CLEAR_COLOR);
        self.camera_input(ui, &response, rect);
        let Some(l) = &self.loaded else {
            let (text, size, color) = match &self.awaiting_file {
                Some(name) => (drop_prompt(name), 22.0, Color32::WHITE),
                None => ("loading…".to_string(), 18.0, Color32::GRAY),
            };
            ui.painter().text(rect.center(), egui::Align2::CENTER_CENTER, text, egui::FontId::proportional(size), color);
            // The prompt is what this design shows until its file comes.
            self.drawn |= self.awaiting_file.is_some();
            return;
        };
        if l.mesh.triangles.is_empty() {
            return;
        }
        let (mesh, center, radius) = (l.mesh.clone(), l.center, l.radius);
        let aspect = rect.width() / rect.height().max(1.0);
        let shading = match self.design.shading {
            Shading::Flat => 0,
            Shading::Smooth => 1,
            Shading::Reflective => 2,
        };
        let design_colors = self.scalar_view().map(|s| ColorMap { scalars: s.data.clone(), range: s.range, diverging: s.diverging });
        let edge_color = [0.05, 0.06, 0.08, 1.0];
        let drawn = self.view().draw(&Frame { shading, edge_color, center, radius, moulds: self.mould_colours });
        let mut layers = Vec::new();
        if drawn.reference {
            let color_map = drawn.reference_colors.clone().unwrap_or(design_colors);
            layers.push(Layer {
                geometry: Geometry::Mesh(mesh.clone()),
                model: Mat4::IDENTITY,
                style: Style::Surface { shading, color: [0.72, 0.78, 0.86, 1.0], color_map },
            });
            if self.design.edges {
                layers.push(Layer { geometry: Geometry::Mesh(mesh), model: Mat4::IDENTITY, style: Style::Lines { color: edge_color } });
            }
        }
        layers.extend(drawn.layers);
        // The clip planes hold everything drawn, however wild a failed result's parts are.
        self.camera.scene_radius = self.drawn_extent(&layers, center, radius).clip_radius;
        if std::mem::take(&mut self.frame_requested) {
            let (c, r) = framing(&layers, center, radius);
            self.camera = OrbitCamera { scene_radius: self.camera.scene_radius, ..OrbitCamera::framing(c, r) };
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
        match drawn.legend {
            Some(Legend::Scale { title, range, diverging }) => colormap::legend(ui.painter(), rect, title, range, diverging),
            Some(Legend::Bins { title, range, bins }) => colormap::binned_legend(ui.painter(), rect, title, range, bins),
            None => {
                if let Some(s) = self.scalars.as_ref().filter(|_| drawn.reference && drawn.reference_colors.is_none()) {
                    colormap::legend(ui.painter(), rect, self.design.color.label(), s.range, s.diverging);
                }
            }
        }
        self.busy_text(ui, rect);
    }

    /// Orbit (primary), pan (secondary, middle or shift), zoom (wheel, pinch); a double click
    /// frames the reference, a click picks a vertex.
    fn camera_input(&mut self, ui: &egui::Ui, response: &egui::Response, rect: Rect) {
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
            // Framed once this frame's layers are known.
            self.frame_requested = true;
        } else if response.clicked() {
            if let Some(pos) = response.interact_pointer_pos() {
                self.selected = self.pick(pos, rect);
            }
        }
    }

    /// The extent of the layers drawn, computed again when their meshes change.
    fn drawn_extent(&mut self, layers: &[Layer], center: Vec3, radius: f32) -> &Extent {
        let key: Vec<u64> = layers
            .iter()
            .filter_map(|l| match &l.geometry {
                Geometry::Mesh(m) => Some(m.generation),
                _ => None,
            })
            .collect();
        if self.extent.as_ref().is_none_or(|e| e.key != key) {
            self.extent = Some(Extent::of(key, layers, center, radius));
        }
        self.extent.as_ref().expect("just set")
    }

    /// The running stage and its progress, top left.
    fn busy_text(&self, ui: &egui::Ui, rect: Rect) {
        let Some(b) = &self.busy else { return };
        let text = match &b.progress {
            Some(p) if p.total > 0 => format!("{} {}: {}/{} · {:.0} ms", b.stage, p.detail, p.iteration, p.total, p.elapsed_ms),
            _ => format!("{}…", b.stage),
        };
        ui.painter().text(
            rect.left_top() + Vec2::new(10.0, 10.0),
            egui::Align2::LEFT_TOP,
            text,
            egui::FontId::proportional(13.0),
            Color32::LIGHT_GRAY,
        );
    }

    /// The translucent central sphere (or plane) at vertex `v`.
    fn central_sphere_layer(&self, v: usize) -> Option<Layer> {
        let l = self.loaded.as_ref()?;
        let sphere = central_sphere(l.curvature.as_ref()?, v)?;
        let p = Vec3::from_slice(l.mesh.positions.get(3 * v..3 * v + 3)?);
        let color = [0.35, 0.65, 1.0, 0.28];
        match center_radius(&sphere) {
            Some((c, r)) if (r.abs() as f32) < 50.0 * l.radius => Some(Layer {
                geometry: Geometry::UnitSphere,
                model: Mat4::from_translation(c.as_vec3()) * Mat4::from_scale(Vec3::splat(r.abs() as f32)),
                style: Style::Translucent { color },
            }),
            _ => {
                // A plane (or a sphere too large to draw): a disc in the tangent plane at v.
                let n = sphere.b.as_vec3().normalize_or(Vec3::Z);
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
        pick_vertex(&l.mesh.positions, &l.mesh.triangles, o, d)
    }
}
