//! The stage of ST meshes with support structure (Sec. 4): runs [`crate::st_support::compute`]
//! and sends its panels, support structure, node axes and second envelope, the files and the
//! report (method "st-support").

use serde::{Deserialize, Serialize};

use super::StageError;
use crate::export::{report_file, Report};
use crate::geometry::absolute_sphere::AbsoluteSphere;
use crate::panels::moulds::{MouldAssignment, MouldOutcome};
use crate::pipeline::fields::{field, Field};
use crate::pipeline::method::{Computed, Exported, Method, Request};
use crate::pipeline::panel_output::{export_panels, f32s, result_panel_fields, support_fields, with_moulds, PanelExport, Snapping};
use crate::pipeline::sink::{report, Sink};
use crate::progress::Clock;
use crate::reference::Reference;
use crate::st_support::guarantees::{measure, Delivered, Measured};
use crate::st_support::report::StSupportSection;
use crate::st_support::{compute, StSupportParams, StSupportResult};
use crate::stats::Histogram;

/// The method in the pipeline.
pub struct StSupportStage;

/// Data for the histograms of Fig. 14 and the Ω display.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StSupportSummary {
    pub report: Report,
    pub omega: AbsoluteSphere,
    pub m0: [f64; 3],
    pub m: [f64; 3],
    pub flipped: bool,
    /// angle(v − m, n) in degrees, for m0 and for the optimized m.
    pub angles_m0: Histogram,
    pub angles_m: Histogram,
    /// The R_i² of the central spheres (or the distances d_i when Ω is a plane).
    pub r2: Histogram,
    pub distinct_radii: usize,
}

impl StSupportSummary {
    /// The report's section, typed.
    pub fn section(&self) -> Option<StSupportSection> {
        self.report.section()
    }
}

impl Method for StSupportStage {
    const KEY: &'static str = "st-support";
    const LABEL: &'static str = "ST with support structure (Sec. 4)";
    type Params = StSupportParams;
    type Result = StSupportResult;
    type Summary = StSupportSummary;

    fn optimizes_moulds(params: &StSupportParams) -> bool {
        params.optimize_moulds
    }

    fn compute(
        reference: &Reference,
        request: &Request<StSupportParams>,
        clock: Clock,
        sink: &mut dyn Sink,
    ) -> Result<Computed<StSupportResult>, StageError> {
        let start = sink.now_ms();
        let result = compute(reference, &core_params(request), &request.fabrication, clock, &mut |p| report(sink, p, Vec::new(), start))?;
        Ok(Computed { result, iteration: 1 })
    }

    /// The report (method "st-support") and the export files of a result; distances are
    /// measured to the reference as loaded, also when the method remeshed it.
    fn export(reference: &Reference, result: &StSupportResult, request: &Request<StSupportParams>, clock: Clock) -> Exported {
        let params = &core_params(request);
        let section = StSupportSection::of(result, params.remesh);
        let delivered = Delivered { panels: &result.panels, support: &result.support, metrics: &result.metrics, omega: &result.omega };
        let Measured { verdict, exact, deviations } = measure(delivered, reference, params, request.fabrication.units);
        let export = PanelExport::new(
            Self::KEY,
            &result.sphere_mesh,
            &result.panels,
            result.diag,
            params.radius_tolerance,
            request.fabrication,
            &section,
            &result.timings_ms,
        )
        .with_absolute_sphere(&result.omega)
        .with_support(&result.support)
        .with_warnings(&result.warnings)
        .with_verdict(&verdict)
        .with_exact_surfaces(&exact)
        .with_deviations(&deviations)
        .with_moulds_before(result.moulds.as_ref().map(|m| &m.fits_before))
        .with_snapping(Snapping::of(result.moulds.as_ref().map(|m| &m.snap)));
        let (report, mut files, moulds) = export_panels(reference, export, clock);
        files.push(report_file(&report));
        Exported { report, files, moulds: Some(moulds) }
    }

    fn display(result: &StSupportResult, moulds: Option<&MouldAssignment>) -> Vec<Field> {
        moulds.map_or_else(Vec::new, |m| display_fields(result, m))
    }

    fn summary(result: &StSupportResult, report: Report) -> StSupportSummary {
        let a = &result.absolute;
        let r2_values = if a.at_infinity { &a.d_samples } else { &a.r2_samples };
        StSupportSummary {
            distinct_radii: report.metrics.as_ref().map_or(0, |m| m.distinct_radii),
            report,
            omega: result.omega,
            m0: a.m0.to_array(),
            m: a.m.to_array(),
            flipped: a.flipped,
            angles_m0: Histogram::new(&a.angles_m0_deg, 36),
            angles_m: Histogram::new(&a.angles_m_deg, 36),
            r2: Histogram::new(r2_values, 36),
        }
    }

    fn report(summary: &StSupportSummary) -> &Report {
        &summary.report
    }

    fn report_mut(summary: &mut StSupportSummary) -> &mut Report {
        &mut summary.report
    }

    fn describe(result: &StSupportResult, report: &Report, _request: &Request<StSupportParams>, out: &str) -> String {
        let summary = format!(
            "wrote {} panels to {out} (max kink {:.3}°, max distance to reference {})",
            result.panels.len(),
            result.metrics.max_kink_angle_deg,
            report.metrics.as_ref().map_or("–".into(), |m| m.max_distance_text())
        );
        match MouldOutcome::section(result.moulds.as_ref()).refused() {
            Some(why) => format!("{}; {why}", with_moulds(summary, report)),
            None => with_moulds(summary, report),
        }
    }
}

/// The method's own parameters with the request's jet fit.
fn core_params(request: &Request<StSupportParams>) -> StSupportParams {
    StSupportParams { jet: request.jet.clone(), ..request.params.clone() }
}

/// Display fields: panels, support, node axes, second envelope.
pub(crate) fn display_fields(result: &StSupportResult, moulds: &MouldAssignment) -> Vec<Field> {
    let mut fields = result_panel_fields(&result.panels, moulds);
    fields.extend(support_fields(&result.support.geometry, &result.support.axis_segments()));
    if let Some(env) = &result.second_envelope {
        fields.push(Field::f32(field::ENVELOPE_POSITIONS, 3, f32s(env.positions.iter().copied())));
        fields.push(Field::u32(field::ENVELOPE_TRIANGLES, 3, env.triangles.iter().flatten().copied().collect()));
    }
    fields
}

impl From<crate::st_support::StSupportError> for StageError {
    fn from(e: crate::st_support::StSupportError) -> Self {
        use crate::st_support::StSupportError;
        match e {
            StSupportError::Cancelled => StageError::Cancelled,
            StSupportError::TooManyFaces(t) => StageError::refused(&t, Some(t.suggested())),
            e => StageError::refused(&e, None),
        }
    }
}
