//! The curvature of the reference (Sec. 2.6): the surface coloured by the design's choice; its
//! summary and the picked vertex's central sphere are in the info section.

use super::method_view::{Drawn, Frame, MethodView};
use crate::design_link::{Design, Method};
use crate::export::Report;
use crate::pipeline::fields::Field;
use crate::pipeline::protocol::{StageId, StageResult};

pub struct CurvatureMethod;

impl MethodView for CurvatureMethod {
    fn method(&self) -> Method {
        Method::Curvature
    }
    fn name(&self) -> &'static str {
        "curvature"
    }
    fn owns(&self, _stage: StageId) -> bool {
        false
    }
    fn start(&mut self) {}
    fn clear(&mut self) {}
    fn controls(&mut self, _ui: &mut egui::Ui, _design: &mut Design) -> bool {
        false
    }
    fn results(&self, _ui: &mut egui::Ui, _design: &Design) {}
    fn snapshot(&mut self, _: StageId, _: u32, _: &[Field], _: &mut u64) -> bool {
        false
    }
    fn finished(&mut self, _result: StageResult) -> Option<Report> {
        None
    }
    fn draw(&self, _frame: &Frame) -> Drawn {
        Drawn::reference_only()
    }
    fn automation(&self) -> serde_json::Value {
        serde_json::Value::Null
    }
}
