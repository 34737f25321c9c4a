//! The benchmarks of `spherical_faces::bench_workloads` in the browser, in release wasm: the same
//! workloads `cargo bench` (benches/pipeline.rs) times natively. Not part of the CI wasm tests
//! (`--test web`); run it with
//!
//!     WASM_BINDGEN_TEST_TIMEOUT=1800 wasm-pack test --release --headless --chrome \
//!         --chromedriver /usr/bin/chromedriver . --test wasm_bench -- --nocapture
//!
//! or `bash www/dev.sh bench` (the runner's default timeout, 20 s, is too short for the suite). It prints one line per benchmark,
//! `bench <name>: <ms> ms/iter (n=<samples>)` (the median; `performance.now()` timing).
#![cfg(target_arch = "wasm32")]

use spherical_faces::bench_workloads::{run_suite, Scale};
use spherical_faces::progress::Clock;
use wasm_bindgen::{JsCast, JsValue};
use wasm_bindgen_test::*;

wasm_bindgen_test_configure!(run_in_browser);

/// `performance.now()` of the global scope (window or worker).
fn now_ms() -> f64 {
    let global = js_sys::global();
    let perf = js_sys::Reflect::get(&global, &"performance".into()).expect("performance");
    perf.unchecked_into::<web_sys::Performance>().now()
}

/// Resolves on the next macrotask (`setTimeout(0)`): lets the page and the runner's polling run.
async fn yield_to_event_loop() {
    let promise = js_sys::Promise::new(&mut |resolve, _| {
        let set_timeout = js_sys::Reflect::get(&js_sys::global(), &"setTimeout".into()).expect("setTimeout");
        set_timeout.unchecked_into::<js_sys::Function>().call2(&JsValue::NULL, &resolve, &0.into()).expect("setTimeout");
    });
    wasm_bindgen_futures::JsFuture::from(promise).await.expect("setTimeout promise");
}

#[wasm_bindgen_test]
async fn bench_pipeline() {
    console_log!("wasm bench: release build, performance.now() timing");
    run_suite(Clock(Some(now_ms)), Scale::Full, &mut |line| console_log!("{line}"), yield_to_event_loop).await;
}
