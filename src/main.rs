//! `spherical-faces`: the native command line (`info`, `st`, `st-support`, `sq`). Not built for wasm32,
//! where the same pipeline runs in the browser's worker instead.

#[cfg(not(target_arch = "wasm32"))]
mod cli;

#[cfg(not(target_arch = "wasm32"))]
fn main() -> std::process::ExitCode {
    cli::main()
}

#[cfg(target_arch = "wasm32")]
fn main() {}
