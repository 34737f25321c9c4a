#![no_main]
//! Fuzz target `bspline`: the oracle is in ../oracles.rs (shared with tests/fuzz_replay.rs).

use libfuzzer_sys::fuzz_target;

#[path = "../oracles.rs"]
mod oracles;

fuzz_target!(|data: &[u8]| oracles::bspline(data));
