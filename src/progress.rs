//! The one progress event every long computation reports, the typed [`Cancelled`] that stops
//! it, and the caller's clock.
//!
//! A computation takes `&mut OnProgress` and calls it at step boundaries (a remeshing round, 1024
//! vertices of a jet fit, a solver iteration). The callback answers `Err(Cancelled)` to stop it;
//! the computation then returns that error at once, with nothing half-written.
//!
//! No clock is read here: `std::time::Instant` panics on wasm32. The caller passes a [`Clock`]
//! (`performance.now()` in the worker, [`native_clock_ms`] natively); without one, timings are 0.

use std::fmt;

/// How far a step of a computation is: `done` of `total` units (0 of 0 when unknown).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Progress<'a> {
    /// The step, e.g. "jet_fit", "remesh", "optimize".
    pub step: &'a str,
    pub done: usize,
    pub total: usize,
}

impl<'a> Progress<'a> {
    pub fn new(step: &'a str, done: usize, total: usize) -> Self {
        Self { step, done, total }
    }
}

/// The caller asked to stop.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Cancelled;

impl fmt::Display for Cancelled {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("cancelled")
    }
}

impl std::error::Error for Cancelled {}

/// The progress callback every long computation takes.
pub type OnProgress<'a> = dyn FnMut(Progress) -> Result<(), Cancelled> + 'a;

/// A callback that never cancels.
pub fn ignore(_: Progress) -> Result<(), Cancelled> {
    Ok(())
}

/// A millisecond clock supplied by the caller. It never affects results: all clocks compare
/// equal, and none is serialized.
#[derive(Clone, Copy, Default)]
pub struct Clock(pub Option<fn() -> f64>);

impl Clock {
    /// The time in ms, 0 without a clock.
    pub fn now(&self) -> f64 {
        self.0.map_or(0.0, |f| f())
    }

    /// [`native_clock_ms`].
    #[cfg(not(target_arch = "wasm32"))]
    pub fn native() -> Self {
        Self(Some(native_clock_ms))
    }
}

impl fmt::Debug for Clock {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(if self.0.is_some() { "Clock(Some)" } else { "Clock(None)" })
    }
}

impl PartialEq for Clock {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

/// Milliseconds since the first call, from `std::time::Instant` (native only).
#[cfg(not(target_arch = "wasm32"))]
pub fn native_clock_ms() -> f64 {
    use std::sync::OnceLock;
    use std::time::Instant;
    static START: OnceLock<Instant> = OnceLock::new();
    START.get_or_init(Instant::now).elapsed().as_secs_f64() * 1e3
}

/// Step times in execution order: each [`Timings::lap`] records the time since the previous one.
#[derive(Clone, Debug)]
pub struct Timings {
    clock: Clock,
    last: f64,
    /// (step, milliseconds).
    pub laps: Vec<(String, f64)>,
}

impl Timings {
    pub fn start(clock: Clock) -> Self {
        Self { clock, last: clock.now(), laps: Vec::new() }
    }

    /// Records `step` as lasting from the previous lap (or the start) until now.
    pub fn lap(&mut self, step: &str) {
        let now = self.clock.now();
        self.laps.push((step.to_string(), now - self.last));
        self.last = now;
    }

    /// Restarts the running lap without recording it.
    pub fn skip(&mut self) {
        self.last = self.clock.now();
    }
}
