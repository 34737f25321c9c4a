//! The browser app (wasm32 only): egui UI and wgpu viewer on the main thread, the pipeline in a
//! Web Worker running the same wasm.

mod app;
mod colormap;
pub mod transport;
mod viewer;
mod worker;
mod worker_client;

use wasm_bindgen::prelude::*;

/// Starts the app on `canvas`. `backend` is "webgpu", "webgl2" or "" (WebGPU, else WebGL2).
#[wasm_bindgen]
pub async fn start_app(canvas: web_sys::HtmlCanvasElement, backend: String) -> Result<(), JsValue> {
    console_error_panic_hook::set_once();
    let mut options = eframe::WebOptions { depth_buffer: 24, ..Default::default() };
    if let egui_wgpu::WgpuSetup::CreateNew(create) = &mut options.wgpu_options.wgpu_setup {
        create.instance_descriptor.backends = match backend.as_str() {
            "webgpu" => egui_wgpu::wgpu::Backends::BROWSER_WEBGPU,
            "webgl2" => egui_wgpu::wgpu::Backends::GL,
            _ => egui_wgpu::wgpu::Backends::BROWSER_WEBGPU | egui_wgpu::wgpu::Backends::GL,
        };
    }
    eframe::WebRunner::new().start(canvas, options, Box::new(|cc| Ok(Box::new(app::App::new(cc))))).await
}
