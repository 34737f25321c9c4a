//! The curvature stage (Sec. 2.6): jet-fitted curvature and central spheres of the reference,
//! kept in it for the methods that follow.

use super::StageError;
use crate::congruence::central_spheres::{CurvatureSummary, JetParams};
use crate::pipeline::fields::Part;
use crate::pipeline::panel_output::curvature_fields;
use crate::pipeline::sink::{report, Sink};
use crate::reference::Reference;

/// Fits the jets (or takes the cached fit), sends the per-vertex fields, returns the summary.
pub fn run(reference: &Reference, params: &JetParams, sink: &mut dyn Sink) -> Result<CurvatureSummary, StageError> {
    let start = sink.now_ms();
    let field = reference.curvature(params, &mut |p| report(sink, p, Vec::new(), start))?;
    sink.snapshot(Part::Main, 1, curvature_fields(&field));
    Ok(field.summary.clone())
}
