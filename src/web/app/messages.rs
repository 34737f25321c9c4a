//! The reducer: what each worker message does to the app's state.

use std::sync::Arc;

use glam::Vec3;

use super::state::{
    mesh_from_fields, CurvatureView, Download, Scene, StSupportView, MESH_FIELDS, PANEL_FIELDS,
};
use super::App;
use crate::design_link::DesignSurface;
use crate::pipeline::fields::{field, find, Field, FieldData};
use crate::pipeline::protocol::{FromWorker, Source, StageResult, ToWorker};
use crate::pipeline::stages::{sq, st_adapted, st_support};
use crate::web::viewer::camera::OrbitCamera;
use crate::web::viewer::MeshData;
use crate::web::worker_client::Incoming;

impl App {
    pub(super) fn handle_messages(&mut self) {
        loop {
            let Some(item) = self.worker.as_ref().and_then(|w| w.poll()) else {
                break;
            };
            match item {
                Incoming::Crashed(message) => {
                    self.error = Some(format!(
                        "{message}. The worker was restarted; your design is kept."
                    ));
                    self.busy = None;
                    if let Some(w) = self.worker.as_mut() {
                        w.restart();
                    }
                }
                Incoming::Message(msg, fields) => {
                    self.handle_message(msg, fields);
                    self.note_cancel_point();
                }
            }
        }
    }

    /// Once every message the worker had posted before the last cancel request is handled: the
    /// ST iterations received by then (what "stops within one iteration" is measured from).
    pub(super) fn note_cancel_point(&mut self) {
        let polled = self.worker.as_ref().map_or(0, |w| w.polled());
        if self.cancel_posted.is_some_and(|posted| polled >= posted) {
            self.cancel_posted = None;
            let energies = self
                .loaded
                .as_ref()
                .and_then(|l| l.st_adapted.as_ref())
                .map_or(0, |a| a.energy.len());
            self.iterations_at_cancel = Some(energies);
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
                        self.design.reference = DesignSurface::Sample(*s);
                        self.file = None;
                    }
                    Source::File(name) => {
                        self.design.reference = DesignSurface::OwnFile(name.clone());
                        if let Some(f) = self.file_in_flight.take() {
                            self.file = Some(f);
                        }
                    }
                }
                for n in &info.notes {
                    self.notices.push(n.clone());
                }
                self.loaded = Some(Scene::new(info));
            }
            FromWorker::Snapshot { stage, .. } if stage == "reference" => {
                self.install_geometry(&fields)
            }
            FromWorker::Files { mime, .. } => {
                self.downloads = fields
                    .into_iter()
                    .zip(mime)
                    .filter_map(|(f, m)| match f.data {
                        FieldData::Bytes(b) => Some(Download {
                            name: f.name,
                            mime: m,
                            bytes: b,
                        }),
                        _ => None,
                    })
                    .collect();
            }
            FromWorker::Snapshot { stage, .. } if stage == st_support::STAGE => {
                if let Some(l) = self.loaded.as_mut() {
                    l.st_support = Some(StSupportView::from_fields(&fields, &mut self.generation));
                }
            }
            FromWorker::Snapshot {
                stage, iteration, ..
            } if [
                st_adapted::STAGE,
                st_adapted::SIZING_STAGE,
                st_adapted::REMESHED_STAGE,
            ]
            .contains(&stage.as_str()) =>
            {
                let Some(a) = self.loaded.as_mut().and_then(|l| l.st_adapted.as_mut()) else {
                    return;
                };
                if stage == st_adapted::SIZING_STAGE {
                    a.sizing = find(&fields, field::SIZING)
                        .and_then(Field::as_f32)
                        .map(<[f32]>::to_vec);
                    self.scalars = None;
                } else if stage == st_adapted::REMESHED_STAGE {
                    a.remeshed = Some(mesh_from_fields(&fields, &mut self.generation, MESH_FIELDS));
                } else {
                    a.panels = Some(mesh_from_fields(
                        &fields,
                        &mut self.generation,
                        PANEL_FIELDS,
                    ));
                    a.panel_iteration = iteration;
                    a.panel_snapshots += 1;
                }
            }
            FromWorker::Snapshot {
                stage, iteration, ..
            } if stage == sq::STAGE => {
                if let Some(v) = self.loaded.as_mut().and_then(|l| l.sq.as_mut()) {
                    v.install(&fields, iteration, &mut self.generation);
                }
            }
            FromWorker::Snapshot { stage, .. } if stage == sq::REFUSED_STAGE => {
                if let Some(v) = self.loaded.as_mut().and_then(|l| l.sq.as_mut()) {
                    let values = find(&fields, field::MEAN_CURVATURE)
                        .and_then(Field::as_f32)
                        .map(<[f32]>::to_vec)
                        .unwrap_or_default();
                    self.generation += 1;
                    v.refused_h = Some(Arc::new(crate::web::viewer::ScalarData {
                        generation: self.generation,
                        values,
                    }));
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
                if let (Some(a), Some(total)) = (
                    self.loaded.as_mut().and_then(|l| l.st_adapted.as_mut()),
                    p.energies.first(),
                ) {
                    if p.stage == st_adapted::STAGE {
                        a.energy.push((p.iteration, p.detail.clone(), total.value));
                    }
                }
                if let Some(v) = self
                    .loaded
                    .as_mut()
                    .and_then(|l| l.sq.as_mut())
                    .filter(|_| p.stage == sq::STAGE && !p.energies.is_empty())
                {
                    v.energy
                        .push((p.iteration, p.detail.clone(), p.energies.clone()));
                }
                if let Some(b) = self.busy.as_mut() {
                    b.progress = Some(p);
                }
            }
            FromWorker::Finished { stage, result, .. } => {
                if let Some(b) = self.busy.as_ref().filter(|b| b.stage == stage) {
                    self.last_run = Some((stage.clone(), super::dom::now_ms() - b.since_ms));
                    self.busy = None;
                }
                match result {
                    StageResult::Curvature(summary) => {
                        if let Some(c) = self.loaded.as_mut().and_then(|l| l.curvature.as_mut()) {
                            c.summary = Some(summary);
                        }
                    }
                    StageResult::StSupport(summary) => {
                        if let Some(st) = self.loaded.as_mut().and_then(|l| l.st_support.as_mut()) {
                            st.summary = Some(*summary);
                        }
                    }
                    StageResult::Sq(summary) => {
                        // With the SQ mesh done, the panels take the stage: the congruence and
                        // the reference step back (each can be switched on again).
                        if summary.section.sq_mesh.is_some() {
                            let d = &mut self.sq_display;
                            (d.lines, d.cross_field, d.surface) = (false, false, false);
                        }
                        self.missed_guarantees = super::panels::missed_guarantees(&summary.report);
                        if let Some(v) = self.loaded.as_mut().and_then(|l| l.sq.as_mut()) {
                            v.summary = Some(*summary);
                        }
                    }
                    StageResult::StAdapted(summary) => {
                        self.missed_guarantees = super::panels::missed_guarantees(&summary.report);
                        if let Some(a) = self.loaded.as_mut().and_then(|l| l.st_adapted.as_mut()) {
                            a.summary = Some(*summary);
                        }
                    }
                }
            }
            FromWorker::Cancelled { stage } => {
                self.busy = None;
                self.notices.push(format!("Stage '{stage}' cancelled."));
            }
            FromWorker::Error { message, remesh_to } => {
                // A failed stage also ends the stages queued after it.
                self.busy = None;
                self.file_in_flight = None;
                self.error = Some(message);
                self.remesh_to = remesh_to;
            }
        }
    }

    fn install_geometry(&mut self, fields: &[Field]) {
        let Some(l) = self.loaded.as_mut() else {
            return;
        };
        let get_f = |n| {
            find(fields, n)
                .and_then(Field::as_f32)
                .map(<[f32]>::to_vec)
                .unwrap_or_default()
        };
        let get_u = |n| {
            find(fields, n)
                .and_then(Field::as_u32)
                .map(<[u32]>::to_vec)
                .unwrap_or_default()
        };
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
        l.st_support = None;
        l.st_adapted = None;
        l.sq = None;
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
            self.camera.target =
                Vec3::new(c.target[0] as f32, c.target[1] as f32, c.target[2] as f32);
        }
        self.busy = None;
        self.run_method();
    }
}
