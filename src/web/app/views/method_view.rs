//! The trait every method's view implements, and what a view draws.

use glam::Vec3;

use crate::design_link::{ColorBy, Design, Method};
use crate::export::Report;
use crate::pipeline::fields::Field;
use crate::pipeline::protocol::{StageId, StageProgress, StageResult};
use crate::web::viewer::{ColorMap, Layer};

/// What a view needs to draw: the design's shading, the edge colour, the reference's centre
/// and radius, and whether panels show their moulds.
pub struct Frame {
    pub shading: u32,
    pub edge_color: [f32; 4],
    pub center: Vec3,
    pub radius: f32,
    /// Panels in their moulds' colours ([`crate::web::app::panels::moulds::MouldMeshes`]).
    pub moulds: bool,
}

/// A colour legend in the viewport's corner.
pub enum Legend {
    Scale { title: &'static str, range: (f32, f32), diverging: bool },
    Bins { title: &'static str, range: (f32, f32), bins: usize },
}

/// What a view draws: its layers, whether the reference surface shows beneath them (and with
/// which colours instead of the design's, if any), and its legend.
pub struct Drawn {
    pub layers: Vec<Layer>,
    pub reference: bool,
    /// Some: the reference's colours instead of the design's colour choice (None: plain).
    pub reference_colors: Option<Option<ColorMap>>,
    pub legend: Option<Legend>,
}

impl Drawn {
    /// The reference alone, in the design's colours.
    pub fn reference_only() -> Self {
        Self { layers: Vec::new(), reference: true, reference_colors: None, legend: None }
    }
}

/// A method's view.
pub trait MethodView {
    fn method(&self) -> Method;
    /// Its key in the automation state ("st_adapted").
    fn name(&self) -> &'static str;
    /// Whether snapshots and progress of `stage` are this view's.
    fn owns(&self, stage: StageId) -> bool;
    /// A run of this method starts: its results so far are dropped.
    fn start(&mut self);
    /// Another method runs, or the reference changed: everything is dropped.
    fn clear(&mut self);
    /// The side panel's controls: the method's parameters in `design` and what the view shows;
    /// true when a parameter changed (the method runs again).
    fn controls(&mut self, ui: &mut egui::Ui, design: &mut Design) -> bool;
    /// The results: live plots while it runs, the verdict and figures when done.
    fn results(&self, ui: &mut egui::Ui, design: &Design);
    /// A snapshot of one of its stages; true when the reference's colours changed.
    fn snapshot(&mut self, stage: StageId, iteration: u32, fields: &[Field], generation: &mut u64) -> bool;
    /// Progress of one of its stages.
    fn progress(&mut self, _progress: &StageProgress) {}
    /// Its stage's summary; the report, for the status bar's verdict.
    fn finished(&mut self, result: StageResult) -> Option<Report>;
    fn draw(&self, frame: &Frame) -> Drawn;
    /// What the end-to-end tests read of it (a typed struct, serialized).
    fn automation(&self) -> serde_json::Value;
    /// The method refused its input's size: remesh to about `faces` first, if it can.
    fn remesh_to(&self, _design: &mut Design, _faces: usize) {}
    /// Optimizer iterations received so far (where a cancel is measured from).
    fn iterations(&self) -> usize {
        0
    }
    /// The reference's colours this method shows first.
    fn colors(&self) -> ColorBy {
        ColorBy::MeanCurvature
    }
    /// Values at the reference vertices for the colour choice "sizing", when it has them.
    fn sizing(&self) -> Option<&[f32]> {
        None
    }
    /// A design link was applied.
    fn link_applied(&mut self, _design: &Design) {}
}
