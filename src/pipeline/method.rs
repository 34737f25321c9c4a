//! The one seam between the pipeline and a method, as egui's demo apps have one trait per view:
//! each method's stage file implements [`Method`] once, and the session, the worker protocol and
//! the command line run every method through it. `protocol.rs` lists the methods.
//!
//! A run is [`Method::compute`] (the method, streaming its progress and live snapshots), then
//! [`Method::export`] (the report with the run's verdict, the files and the final display
//! fields) for the request's fabrication settings. A new δ, K or unit exports the kept result
//! again ([`reexport`]); nothing is computed again unless the method optimizes for its moulds.

use std::fmt::Debug;

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use super::fields::{Field, Part};
use super::sink::Sink;
use super::stages::StageError;
use crate::congruence::central_spheres::JetParams;
use crate::export::{ExportFile, Report};
use crate::panels::moulds::{Fabrication, MouldAssignment};
use crate::params::LinkFields;
use crate::progress::Clock;
use crate::reference::Reference;

/// What a method is asked for: its own parameters, the fabrication settings (the model unit and
/// the moulds) and the jet fit, held once for every method.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Request<P> {
    pub params: P,
    pub fabrication: Fabrication,
    pub jet: JetParams,
}

impl<P: Default> Default for Request<P> {
    fn default() -> Self {
        Self { params: P::default(), fabrication: Fabrication::default(), jet: JetParams::default() }
    }
}

impl<P> Request<P> {
    /// `params` with the default fabrication settings and jet fit.
    pub fn new(params: P) -> Self {
        Self { params, fabrication: Fabrication::default(), jet: JetParams::default() }
    }
}

/// A method's result, with the iteration its final snapshot is sent at.
pub struct Computed<R> {
    pub result: R,
    pub iteration: u32,
}

/// What an export delivers: the report (with the run's verdict), the files, and the moulds it
/// assigned the panels (the final snapshot shows the panels in their colours).
pub struct Exported {
    pub report: Report,
    pub files: Vec<ExportFile>,
    pub moulds: Option<MouldAssignment>,
}

/// A method as the pipeline runs it.
pub trait Method: 'static {
    /// The method's key: its stage on the wire, `method=` in the design link, the command
    /// line's subcommand and the report's `method`.
    const KEY: &'static str;
    /// Its name in the app's menu.
    const LABEL: &'static str;
    /// Its own parameters: their ranges, defaults, `check()` and link fields live in its
    /// `params.rs`.
    type Params: Clone + Debug + PartialEq + Default + Serialize + DeserializeOwned + LinkFields + 'static;
    type Result: 'static;
    /// What the app shows after a run; it holds the report.
    type Summary: Clone + Debug + PartialEq + Serialize + DeserializeOwned + 'static;

    /// Whether the result depends on the moulds asked for (the method optimizes for them): then a
    /// new δ or K runs it again instead of exporting the kept result.
    fn optimizes_moulds(params: &Self::Params) -> bool;

    /// Runs the method on `reference`, streaming progress and live snapshots to `sink`.
    fn compute(
        reference: &Reference,
        request: &Request<Self::Params>,
        clock: Clock,
        sink: &mut dyn Sink,
    ) -> Result<Computed<Self::Result>, StageError>;

    /// The report, the files and the moulds of `result` for `request`'s fabrication settings.
    /// The verdict in the report is measured here, on the delivered output.
    fn export(reference: &Reference, result: &Self::Result, request: &Request<Self::Params>, clock: Clock) -> Exported;

    /// The fields of the final snapshot of `result`, its panels in the colours of `moulds`: built
    /// only for a sink that shows snapshots.
    fn display(result: &Self::Result, moulds: Option<&MouldAssignment>) -> Vec<Field>;

    /// The summary of a run whose export made `report`.
    fn summary(result: &Self::Result, report: Report) -> Self::Summary;

    /// The summary's report.
    fn report(summary: &Self::Summary) -> &Report;
    fn report_mut(summary: &mut Self::Summary) -> &mut Report;

    /// Runs the method's hot code once at worker start, so that a browser's first real run starts
    /// on optimized wasm code (nothing by default).
    fn warm_up() -> Result<(), String> {
        Ok(())
    }

    /// What the command line says of a run that wrote its files to `out`.
    fn describe(result: &Self::Result, report: &Report, request: &Request<Self::Params>, out: &str) -> String;
}

/// Runs `M` on `reference`, then sends its final snapshot and files; returns the summary and the
/// result.
pub fn run<M: Method>(
    reference: &Reference,
    request: &Request<M::Params>,
    clock: Clock,
    sink: &mut dyn Sink,
) -> Result<(M::Summary, Computed<M::Result>), StageError> {
    let computed = M::compute(reference, request, clock, sink)?;
    let report = reexport::<M>(reference, &computed, request, clock, sink);
    Ok((M::summary(&computed.result, report), computed))
}

/// Sends a result's final snapshot and files for `request`; returns the report. A new δ, K or
/// unit needs only this, not the method again.
pub fn reexport<M: Method>(
    reference: &Reference,
    computed: &Computed<M::Result>,
    request: &Request<M::Params>,
    clock: Clock,
    sink: &mut dyn Sink,
) -> Report {
    let Exported { report, files, moulds } = M::export(reference, &computed.result, request, clock);
    if sink.wants_snapshots() {
        sink.snapshot(Part::Main, computed.iteration, M::display(&computed.result, moulds.as_ref()));
    }
    sink.files(files);
    report
}

/// The report and the files of `result` for `params` and `fabrication`, for code that runs a
/// method's `compute` itself (tests, benchmarks, examples).
pub fn export<M: Method>(
    reference: &Reference,
    result: &M::Result,
    params: &M::Params,
    fabrication: &Fabrication,
    clock: Clock,
) -> (Report, Vec<ExportFile>) {
    let request = Request { params: params.clone(), fabrication: *fabrication, jet: JetParams::default() };
    let Exported { report, files, .. } = M::export(reference, result, &request, clock);
    (report, files)
}

/// Whether `request` asks for the very result `earlier` made, with other moulds at most (a new δ,
/// K or unit): then that result is exported again, not computed again.
pub fn same_result<M: Method>(request: &Request<M::Params>, earlier: &Request<M::Params>) -> bool {
    !M::optimizes_moulds(&request.params) && request.params == earlier.params && request.jet == earlier.jet
}
