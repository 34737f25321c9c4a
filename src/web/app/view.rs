//! The viewport: camera input, picking, and the layers drawn for the reference and each method.

use std::sync::Arc;

use egui::{Color32, Pos2, Rect, Sense, Vec2};
use glam::{Mat4, Vec3};

use super::panels::info::{center_radius, central_sphere};
use super::state::{ScalarView, SqView, StSupportView, CROSS_FIELD_BINS};
use super::{App, CLEAR_COLOR};
use crate::design_link::{ColorBy, Method, Shading};
use crate::geometry::absolute_sphere::AbsoluteSphere;
use crate::pipeline::fields::{field, find};
use crate::web::colormap;
use crate::web::viewer::camera::OrbitCamera;
use crate::web::viewer::picking::pick_vertex;
use crate::web::viewer::{ColorMap, Geometry, Layer, MeshData, ScalarData, Style, ViewerFrame};

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
            let values = if color == ColorBy::Sizing {
                l.st_adapted.as_ref()?.sizing.clone()?
            } else {
                find(&l.curvature.as_ref()?.fields, key)?.as_f32()?.to_vec()
            };
            let (range, diverging) = colormap::robust_range(&values);
            self.generation += 1;
            self.scalars = Some(ScalarView {
                color,
                data: Arc::new(ScalarData {
                    generation: self.generation,
                    values,
                }),
                range,
                diverging,
            });
        }
        self.scalars.as_ref()
    }

    pub(super) fn viewport(&mut self, ui: &mut egui::Ui) {
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
            let (scroll, zoom, touch) =
                ui.input(|i| (i.smooth_scroll_delta.y, i.zoom_delta(), i.multi_touch()));
            if scroll != 0.0 {
                self.camera.zoom((scroll * 0.002).exp());
            }
            if zoom != 1.0 {
                self.camera.zoom(zoom);
            }
            if let Some(t) = touch {
                self.camera
                    .pan(t.translation_delta.x, t.translation_delta.y, rect.height());
            }
        }
        if response.double_clicked() {
            if let Some(l) = &self.loaded {
                self.camera = OrbitCamera {
                    target: l.center,
                    ..OrbitCamera::framing(l.center, l.radius)
                };
            }
        } else if response.clicked() {
            if let Some(pos) = response.interact_pointer_pos() {
                self.selected = self.pick(pos, rect);
            }
        }

        let Some(l) = &self.loaded else {
            ui.painter().text(
                rect.center(),
                egui::Align2::CENTER_CENTER,
                "loading…",
                egui::FontId::proportional(18.0),
                Color32::GRAY,
            );
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
        let mut color_map = self.scalar_view().map(|s| ColorMap {
            scalars: s.data.clone(),
            range: s.range,
            diverging: s.diverging,
        });
        let st = self
            .loaded
            .as_ref()
            .and_then(|l| l.st_support.as_ref())
            .filter(|_| self.design.method == Method::StSupport);
        let angle = self
            .loaded
            .as_ref()
            .and_then(|l| l.st_adapted.as_ref())
            .filter(|_| self.design.method == Method::StAdapted);
        let angle_shown = angle.is_some_and(|a| a.panels.is_some() || a.remeshed.is_some());
        let sq = self
            .loaded
            .as_ref()
            .and_then(|l| l.sq.as_ref())
            .filter(|_| self.design.method == Method::Sq);
        // SQ refused for the sign of H (Sec. 6.3): the surface shows where H > 0 and H < 0.
        let refused_h = sq.and_then(|v| v.refused_h.clone()).map(|h| {
            let m = h
                .values
                .iter()
                .fold(0.0f32, |m, x| m.max(x.abs()))
                .max(1e-12);
            ColorMap {
                scalars: h,
                range: (-m, m),
                diverging: true,
            }
        });
        if sq.is_some() {
            // The cross field has the legend; the surface shows H only to explain a refusal.
            color_map = refused_h.clone();
        }
        let edge_color = [0.05, 0.06, 0.08, 1.0];
        let mut layers = Vec::new();
        let reference_shown = if sq.is_some() {
            self.sq_display.surface || refused_h.is_some()
        } else {
            (st.is_none() && !angle_shown) || self.show_reference
        };
        if reference_shown {
            layers.push(Layer {
                geometry: Geometry::Mesh(mesh.clone()),
                model: Mat4::IDENTITY,
                style: Style::Surface {
                    shading,
                    color: [0.72, 0.78, 0.86, 1.0],
                    color_map,
                },
            });
            if self.design.edges {
                layers.push(Layer {
                    geometry: Geometry::Mesh(mesh),
                    model: Mat4::IDENTITY,
                    style: Style::Lines { color: edge_color },
                });
            }
        }
        if let Some(st) = st {
            layers.extend(self.st_layers(st, shading, edge_color));
        }
        if let Some(a) = angle {
            let id = Mat4::IDENTITY;
            match (&a.panels, &a.remeshed) {
                (Some(p), _) => {
                    layers.push(Layer {
                        geometry: Geometry::Mesh(p.clone()),
                        model: id,
                        style: Style::Surface {
                            shading,
                            color: [0.70, 0.80, 0.88, 1.0],
                            color_map: None,
                        },
                    });
                    layers.push(Layer {
                        geometry: Geometry::Mesh(p.clone()),
                        model: id,
                        style: Style::Lines { color: edge_color },
                    });
                }
                (None, Some(r)) => {
                    layers.push(Layer {
                        geometry: Geometry::Mesh(r.clone()),
                        model: id,
                        style: Style::Surface {
                            shading,
                            color: [0.70, 0.80, 0.88, 1.0],
                            color_map: None,
                        },
                    });
                }
                (None, None) => {}
            }
            // The remeshed triangulation: alone until the first panels arrive, then on request.
            if let Some(r) = a
                .remeshed
                .as_ref()
                .filter(|_| self.show_remeshed || a.panels.is_none())
            {
                layers.push(Layer {
                    geometry: Geometry::Mesh(r.clone()),
                    model: id,
                    style: Style::Lines {
                        color: [0.95, 0.55, 0.20, 1.0],
                    },
                });
            }
        }
        if let Some(v) = sq {
            layers.extend(self.sq_layers(v, shading, edge_color));
        }
        layers.extend(self.selected.and_then(|v| self.central_sphere_layer(v)));
        let frame = ViewerFrame {
            view_proj: self.camera.proj(aspect) * self.camera.view(),
            eye: self.camera.eye(),
            line_bias: 2e-3 * self.camera.distance.min(4.0 * self.camera.scene_radius),
            layers,
        };
        ui.painter()
            .add(egui_wgpu::Callback::new_paint_callback(rect, frame));
        self.drawn = true;
        let cross_legend = sq
            .filter(|v| self.sq_display.cross_field && v.cross_field_arms > 0)
            .map(|v| v.cross_field_range);
        if let Some(cm) = &refused_h {
            colormap::legend(ui.painter(), rect, "H (SQ needs one sign)", cm.range, true);
        } else if let Some(range) = cross_legend {
            colormap::binned_legend(
                ui.painter(),
                rect,
                "torsal-plane angle (°)",
                range,
                CROSS_FIELD_BINS,
            );
        } else if let Some(s) = self.scalars.as_ref().filter(|_| reference_shown) {
            colormap::legend(
                ui.painter(),
                rect,
                self.design.color.label(),
                s.range,
                s.diverging,
            );
        }
        if let Some(b) = &self.busy {
            let text = match &b.progress {
                Some(p) if p.total > 0 => format!(
                    "{} {}: {}/{} · {:.0} ms",
                    b.stage, p.detail, p.iteration, p.total, p.elapsed_ms
                ),
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
    }

    /// Panels (with their arcs), support structure, node axes, Ω and m, and the second envelope.
    fn st_layers(&self, st: &StSupportView, shading: u32, edge_color: [f32; 4]) -> Vec<Layer> {
        let id = Mat4::IDENTITY;
        let radius = self.loaded.as_ref().map_or(1.0, |l| l.radius);
        let mut layers = vec![
            Layer {
                geometry: Geometry::Mesh(st.panels.clone()),
                model: id,
                style: Style::Surface {
                    shading,
                    color: [0.70, 0.80, 0.88, 1.0],
                    color_map: None,
                },
            },
            Layer {
                geometry: Geometry::Mesh(st.panels.clone()),
                model: id,
                style: Style::Lines { color: edge_color },
            },
            Layer {
                geometry: Geometry::Mesh(st.support.clone()),
                model: id,
                style: Style::Surface {
                    shading: 0,
                    color: [0.80, 0.55, 0.30, 1.0],
                    color_map: None,
                },
            },
            Layer {
                geometry: Geometry::Mesh(st.axes.clone()),
                model: id,
                style: Style::Lines {
                    color: [0.85, 0.15, 0.12, 1.0],
                },
            },
        ];
        if self.show_envelope {
            if let Some(env) = &st.envelope {
                layers.push(Layer {
                    geometry: Geometry::Mesh(env.clone()),
                    model: id,
                    style: Style::Surface {
                        shading: 0,
                        color: [0.55, 0.75, 0.55, 1.0],
                        color_map: None,
                    },
                });
            }
        }
        if let Some(AbsoluteSphere::Plane { axis, d }) = st.summary.as_ref().map(|s| s.omega) {
            // Ω at infinity: a disc of the plane ⟨x, a⟩ = d under the mesh centre.
            let (a, center) = (
                axis.as_vec3().normalize_or(Vec3::Z),
                self.loaded.as_ref().map_or(Vec3::ZERO, |l| l.center),
            );
            let foot = center + a * (d as f32 - center.dot(a));
            layers.push(Layer {
                geometry: Geometry::UnitDisc,
                model: Mat4::from_scale_rotation_translation(
                    Vec3::splat(radius * 1.2),
                    glam::Quat::from_rotation_arc(Vec3::Z, a),
                    foot,
                ),
                style: Style::Translucent {
                    color: [0.95, 0.75, 0.30, 0.15],
                },
            });
        }
        if let Some(AbsoluteSphere::Sphere { center, r2 }) = st.summary.as_ref().map(|s| s.omega) {
            let m = center.as_vec3();
            // m itself, and Ω when real and not too large to see.
            layers.push(Layer {
                geometry: Geometry::UnitSphere,
                model: Mat4::from_translation(m) * Mat4::from_scale(Vec3::splat(radius * 0.02)),
                style: Style::Surface {
                    shading: 1,
                    color: [0.85, 0.15, 0.12, 1.0],
                    color_map: None,
                },
            });
            if r2 > 0.0 && (r2.sqrt() as f32) < 20.0 * radius {
                layers.push(Layer {
                    geometry: Geometry::UnitSphere,
                    model: Mat4::from_translation(m)
                        * Mat4::from_scale(Vec3::splat(r2.sqrt() as f32)),
                    style: Style::Translucent {
                        color: [0.95, 0.75, 0.30, 0.15],
                    },
                });
            }
        }
        layers
    }

    /// The SQ run: lines (Fig. 21), the cross field by angle bins (Fig. 23) and the quads
    /// without real torsal directions in red; the quad mesh, the panels (reflective with the
    /// design's shading), the support structure and the node axes (Fig. 19, 25).
    fn sq_layers(&self, v: &SqView, shading: u32, edge_color: [f32; 4]) -> Vec<Layer> {
        let id = Mat4::IDENTITY;
        let lines = |m: &Arc<MeshData>, color| Layer {
            geometry: Geometry::Mesh(m.clone()),
            model: id,
            style: Style::Lines { color },
        };
        let d = self.sq_display;
        let mut layers = Vec::new();
        if d.initial_lines {
            layers.extend(
                v.initial_lines
                    .as_ref()
                    .map(|m| lines(m, [0.55, 0.55, 0.60, 1.0])),
            );
        }
        if d.lines {
            layers.extend(v.lines.as_ref().map(|m| lines(m, [0.15, 0.40, 0.95, 1.0])));
        }
        if d.cross_field {
            let bins = v.cross_field.len();
            layers.extend(
                v.cross_field
                    .iter()
                    .enumerate()
                    .filter(|(_, m)| !m.edges.is_empty())
                    .map(|(k, m)| lines(m, colormap::bin_color(k, bins))),
            );
        }
        layers.extend(
            v.no_real_quads
                .as_ref()
                .filter(|m| !m.edges.is_empty())
                .map(|m| lines(m, [0.95, 0.10, 0.10, 1.0])),
        );
        let surface = |m: &Arc<MeshData>, shading, color| Layer {
            geometry: Geometry::Mesh(m.clone()),
            model: id,
            style: Style::Surface {
                shading,
                color,
                color_map: None,
            },
        };
        if d.panels {
            if let Some(p) = &v.panels {
                layers.push(surface(p, shading, [0.70, 0.80, 0.88, 1.0]));
                layers.push(lines(p, edge_color));
            }
        }
        if d.quad_mesh && (v.panels.is_none() || !d.panels) {
            layers.extend(
                v.quad_mesh
                    .as_ref()
                    .map(|m| lines(m, [0.95, 0.55, 0.20, 1.0])),
            );
        }
        if d.support {
            layers.extend(
                v.support
                    .as_ref()
                    .map(|m| surface(m, 0, [0.80, 0.55, 0.30, 1.0])),
            );
        }
        if d.axes {
            layers.extend(v.axes.as_ref().map(|m| lines(m, [0.85, 0.15, 0.12, 1.0])));
        }
        layers
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
                model: Mat4::from_translation(c.as_vec3())
                    * Mat4::from_scale(Vec3::splat(r.abs() as f32)),
                style: Style::Translucent { color },
            }),
            _ => {
                // A plane (or a sphere too large to draw): a disc in the tangent plane at v.
                let n = sphere.b.as_vec3().normalize_or(Vec3::Z);
                let rot = glam::Quat::from_rotation_arc(Vec3::Z, n);
                Some(Layer {
                    geometry: Geometry::UnitDisc,
                    model: Mat4::from_scale_rotation_translation(
                        Vec3::splat(l.radius * 0.6),
                        rot,
                        p,
                    ),
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
        let (o, d) = self
            .camera
            .ray(ndc_x, ndc_y, rect.width() / rect.height().max(1.0));
        pick_vertex(&l.mesh.positions, &l.mesh.triangles, o, d)
    }
}
