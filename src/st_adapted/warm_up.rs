//! A small run of the ST method (Sec. 3) at worker start, while the user looks at the page.
//!
//! A browser runs new wasm code in a baseline tier first and compiles the hot functions optimized
//! in the background; a function's running call stays in the baseline code. Without a warm-up,
//! the first run spends its first iterations there: on the dome at 600 faces (headless Chromium,
//! 2 cores) the first seven angle iterations took 20–45 ms each against 5–6 ms later. The
//! warm-up runs the same code (jet fit, remeshing, the angle iterations with the sparse Cholesky
//! factorization, panels) on about [`WARM_UP_FACES`] faces, so the user's first run starts on
//! optimized code.

use super::params::StAdaptedParams;
use super::{compute, StAdaptedError};
use crate::panels::moulds::Fabrication;
use crate::progress::Clock;
use crate::reference::Reference;
use crate::remeshing::Sizing;

/// Faces of the warm-up's remeshed dome: a few hundred, so that the factorization takes the same
/// (supernodal) path as a real run.
pub const WARM_UP_FACES: usize = 250;
/// Rings of the warm-up's reference dome ([`crate::samples::dome`]).
pub const WARM_UP_RINGS: usize = 10;
/// Solver iterations per optimization stage.
pub const WARM_UP_STAGE_ITERATIONS: usize = 2;

/// What the warm-up did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WarmUp {
    pub faces: usize,
    pub iterations: usize,
    /// Whether the factorization was supernodal (as in a real run of some hundred faces).
    pub supernodal: bool,
}

/// Runs the ST method once on a small dome (no sink, no clock); the result is dropped.
pub fn warm_up() -> Result<WarmUp, StAdaptedError> {
    let reference = Reference::from_triangles(crate::samples::dome(WARM_UP_RINGS));
    let params = StAdaptedParams {
        sizing: Sizing::UniformFaces(WARM_UP_FACES),
        stages: StAdaptedParams::stages_with([WARM_UP_STAGE_ITERATIONS; 3]),
        ..Default::default()
    };
    let result = compute(&reference, &params, &Fabrication::default(), Clock(None), &mut |_| Ok(()))?;
    Ok(WarmUp { faces: result.panels.len(), iterations: result.iterations, supernodal: result.supernodal })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_warm_up_runs_every_stage_on_a_few_hundred_faces_supernodally() {
        let w = warm_up().unwrap();
        assert_eq!(w.iterations, 3 * WARM_UP_STAGE_ITERATIONS, "every stage's iterations: {w:?}");
        assert!((WARM_UP_FACES * 4 / 5..=WARM_UP_FACES * 6 / 5).contains(&w.faces), "{w:?}");
        assert!(w.supernodal, "the warm-up must take a real run's factorization path: {w:?}");
    }
}
