//! Where a stage streams what it makes: progress, snapshots of fields and files. The session
//! turns these into worker messages; tests and the CLI can record them directly.

use super::fields::{Energy, Field, StageId, StageProgress};
use crate::export::ExportFile;
use crate::progress::{Cancelled, Progress};

/// A stage's outlet.
pub trait Sink {
    /// Reports progress.
    fn progress(&mut self, progress: StageProgress);
    /// A snapshot of the stage's geometry and per-element data.
    fn snapshot(&mut self, stage: StageId, iteration: u32, fields: Vec<Field>);
    /// Files for download.
    fn files(&mut self, stage: StageId, files: Vec<ExportFile>);
    /// Polled at every step boundary; true stops the stage there.
    fn cancel_requested(&mut self) -> bool;
    /// Milliseconds from an arbitrary origin.
    fn now_ms(&self) -> f64;
}

/// Reports `p` as progress of `stage` (started at `start` ms, with `energies` of an iteration),
/// then answers whether the stage goes on.
pub fn report(sink: &mut dyn Sink, stage: StageId, p: Progress, energies: Vec<Energy>, start: f64) -> Result<(), Cancelled> {
    let elapsed_ms = sink.now_ms() - start;
    sink.progress(StageProgress { stage, detail: p.step.into(), iteration: p.done as u32, total: p.total as u32, energies, elapsed_ms });
    if sink.cancel_requested() {
        Err(Cancelled)
    } else {
        Ok(())
    }
}
