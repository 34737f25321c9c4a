//! The reducer: what each worker message does to the app's state.

use std::sync::Arc;

use glam::Vec3;

use super::state::{CurvatureView, Download, Origin, Scene, ShownError};
use super::App;
use crate::design_link::DesignSurface;
use crate::pipeline::fields::{field, find, Field, FieldData};
use crate::pipeline::protocol::{FromWorker, ReferenceInfo, Source, StageId, StageProgress, StageResult, ToWorker};
use crate::web::viewer::camera::OrbitCamera;
use crate::web::viewer::MeshData;
use crate::web::worker_client::Incoming;

impl App {
    pub(super) fn handle_messages(&mut self) {
        while let Some(item) = self.worker.as_ref().and_then(|w| w.poll()) {
            match item {
                Incoming::Crashed(message) => {
                    self.error = Some(ShownError::new(format!("{message}. The worker was restarted; your design is kept."), Origin::Worker));
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
            self.iterations_at_cancel = Some(self.view().iterations());
        }
    }

    fn handle_message(&mut self, msg: FromWorker, fields: Vec<Field>) {
        match msg {
            FromWorker::Ready => self.restore_design(),
            FromWorker::Loaded(info) => self.loaded(info),
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
            FromWorker::Snapshot { stage, iteration, .. } => self.snapshot(stage, iteration, fields),
            FromWorker::Progress(p) => self.progress(p),
            FromWorker::Finished { stage, result, .. } => self.finished(stage, result),
            FromWorker::Cancelled { stage } => {
                self.busy = None;
                self.notice(format!("Stage '{stage}' cancelled."), Origin::Run);
            }
            FromWorker::Error { message, remesh_to } => {
                // A failed stage also ends the stages queued after it. The error belongs to the
                // file being loaded, or to the run of the method that refused.
                let stage = self.busy.take().map(|b| b.stage);
                self.file_in_flight = None;
                let refused_by = stage.and_then(StageId::method);
                let origin = if stage == Some(StageId::Import) { Origin::Reference } else { Origin::Run };
                self.error = Some(ShownError { remesh_to, refused_by, ..ShownError::new(message, origin) });
            }
        }
    }

    /// A fresh worker (first start or after a crash): the design goes back into it.
    fn restore_design(&mut self) {
        let Some(l) = &self.loaded else { return };
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

    fn loaded(&mut self, info: ReferenceInfo) {
        // A new reference replaces everything said of the old one (a restored one keeps it).
        if !self.restoring {
            self.error = None;
            self.notices.retain(|n| n.origin == Origin::Link || n.origin == Origin::Ui);
        }
        self.awaiting_file = None;
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
        for note in &info.notes {
            self.notice(note.clone(), Origin::Reference);
        }
        // A file that names its model unit sets the design's (the moulds' tolerance reads in it).
        if let Some(u) = info.units.filter(|&u| u != self.design.fabrication.units) {
            self.design.fabrication.units = u;
            self.notice(format!("model unit from the file: {u}"), Origin::Reference);
        }
        self.loaded = Some(Scene::new(info));
    }

    /// The reference's geometry, the curvature, or a snapshot of the stage of a method's view.
    fn snapshot(&mut self, stage: StageId, iteration: u32, fields: Vec<Field>) {
        match stage {
            StageId::Reference => self.install_geometry(&fields),
            StageId::Curvature => {
                if let Some(l) = self.loaded.as_mut() {
                    let summary = l.curvature.take().and_then(|c| c.summary);
                    l.curvature = Some(CurvatureView { fields, summary });
                    self.scalars = None;
                }
            }
            _ => {
                let generation = &mut self.generation;
                if let Some(v) = self.views.iter_mut().find(|v| v.owns(stage)) {
                    if v.snapshot(stage, iteration, &fields, generation) {
                        self.scalars = None;
                    }
                }
            }
        }
    }

    fn progress(&mut self, p: StageProgress) {
        if let Some(v) = self.views.iter_mut().find(|v| v.owns(p.stage)) {
            v.progress(&p);
        }
        if let Some(b) = self.busy.as_mut() {
            b.progress = Some(p);
        }
    }

    fn finished(&mut self, stage: StageId, result: StageResult) {
        if let Some(b) = self.busy.as_ref().filter(|b| b.stage == stage) {
            self.last_run = Some((stage, super::dom::now_ms() - b.since_ms));
            self.busy = None;
        }
        if let StageResult::Curvature(summary) = result {
            if let Some(c) = self.loaded.as_mut().and_then(|l| l.curvature.as_mut()) {
                c.summary = Some(summary);
            }
        } else if let Some(v) = self.views.iter_mut().find(|v| v.owns(stage)) {
            if let Some(report) = v.finished(result) {
                self.verdict = report.meets_guarantees.is_some().then(|| super::panels::ShownVerdict::of(&report.guarantees));
                self.moulds = report.moulds;
                self.exact_surfaces = report.exact_surfaces;
            }
        }
    }

    fn install_geometry(&mut self, fields: &[Field]) {
        let Some(l) = self.loaded.as_mut() else {
            return;
        };
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
        let (lo, hi) = mesh.positions.chunks_exact(3).fold((Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)), |(lo, hi), p| {
            (lo.min(Vec3::from_slice(p)), hi.max(Vec3::from_slice(p)))
        });
        l.center = (lo + hi) * 0.5;
        l.radius = ((hi - lo).length() * 0.5).max(1e-6);
        l.mesh = Arc::new(mesh);
        l.curvature = None;
        for v in &mut self.views {
            v.clear();
        }
        self.scalars = None;
        if !self.restoring {
            self.selected = None;
        }
        let restored = std::mem::take(&mut self.restoring);
        if restored {
            self.camera.scene_radius = l.radius;
        } else {
            self.camera = OrbitCamera::framing(l.center, l.radius);
        }
        self.apply_link_camera();
        self.busy = None;
        // The run that restores a crashed worker's design keeps its message.
        let kept = if restored { self.error.take().filter(|e| e.origin == Origin::Worker) } else { None };
        self.run_method();
        if kept.is_some() {
            self.error = kept;
        }
    }
}
