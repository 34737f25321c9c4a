//! Where a stage streams what it makes: progress, snapshots of fields and files. The session
//! turns these into worker messages, naming the stage; tests and the CLI can record them directly.

use super::fields::{Energy, Field, Part, StepProgress};
use crate::export::ExportFile;
use crate::progress::{Cancelled, Progress};

/// A stage's outlet.
pub trait Sink {
    /// Reports progress.
    fn progress(&mut self, progress: StepProgress);
    /// A snapshot of a part of the stage's geometry and per-element data.
    fn snapshot(&mut self, part: Part, iteration: u32, fields: Vec<Field>);
    /// Files for download.
    fn files(&mut self, files: Vec<ExportFile>);
    /// Polled at every step boundary; true stops the stage there.
    fn cancel_requested(&mut self) -> bool;
    /// Milliseconds from an arbitrary origin.
    fn now_ms(&self) -> f64;
    /// Whether snapshots are wanted, live while the stage runs and the final one (the CLI shows
    /// none: the stages then skip building them). The files are always sent.
    fn wants_snapshots(&self) -> bool {
        true
    }
}

/// Reports `p` (with `energies` of an iteration) as progress of a stage started at `start` ms,
/// then answers whether the stage goes on.
pub fn report(sink: &mut dyn Sink, p: Progress, energies: Vec<Energy>, start: f64) -> Result<(), Cancelled> {
    let elapsed_ms = sink.now_ms() - start;
    sink.progress(StepProgress { detail: p.step.into(), iteration: p.done as u32, total: p.total as u32, energies, elapsed_ms });
    if sink.cancel_requested() {
        Err(Cancelled)
    } else {
        Ok(())
    }
}
