//! The page around the app: the clock, the URL fragment, file download and the file dialog,
//! and the window events the automation and diagnostics hooks listen to.

use std::cell::RefCell;
use std::rc::Rc;

use wasm_bindgen::prelude::*;

/// Milliseconds from the page's time origin.
pub fn now_ms() -> f64 {
    web_sys::window().and_then(|w| w.performance()).map_or(0.0, |p| p.now())
}

/// Saves `bytes` as a file through a temporary object URL.
pub fn save_file(name: &str, mime: &str, bytes: &[u8]) -> Result<(), JsValue> {
    let parts = js_sys::Array::of1(&js_sys::Uint8Array::from(bytes));
    let opts = web_sys::BlobPropertyBag::new();
    opts.set_type(mime);
    let blob = web_sys::Blob::new_with_u8_array_sequence_and_options(&parts, &opts)?;
    let url = web_sys::Url::create_object_url_with_blob(&blob)?;
    let doc = web_sys::window().and_then(|w| w.document()).ok_or("no document")?;
    let a: web_sys::HtmlAnchorElement = doc.create_element("a")?.dyn_into()?;
    a.set_href(&url);
    a.set_download(name);
    a.click();
    // Release the object URL once the download has started.
    let release = Closure::once_into_js(move || {
        let _ = web_sys::Url::revoke_object_url(&url);
    });
    let window = web_sys::window().ok_or("no window")?;
    window.set_timeout_with_callback_and_timeout_and_arguments_0(release.unchecked_ref(), 10_000)?;
    Ok(())
}

/// Counts `event`s dispatched on the window (automation and diagnostics hooks).
pub fn count_events(event: &str, ctx: &egui::Context) -> (Rc<RefCell<u32>>, Closure<dyn FnMut()>) {
    let count = Rc::new(RefCell::new(0));
    let (c2, ctx) = (count.clone(), ctx.clone());
    let c = Closure::<dyn FnMut()>::new(move || {
        *c2.borrow_mut() += 1;
        ctx.request_repaint();
    });
    if let Some(w) = web_sys::window() {
        let _ = w.add_event_listener_with_callback(event, c.as_ref().unchecked_ref());
    }
    (count, c)
}

/// Strings queued by an event listener, and the listener (kept alive while it listens).
pub type EventQueue = (Rc<RefCell<Vec<String>>>, Closure<dyn FnMut(web_sys::CustomEvent)>);

/// Listens for the `CustomEvent` `event` on the window; its string details queue up for the app.
pub fn queue_events(event: &str, ctx: &egui::Context) -> EventQueue {
    let queue = Rc::new(RefCell::new(Vec::new()));
    let (q2, ctx) = (queue.clone(), ctx.clone());
    let c = Closure::<dyn FnMut(web_sys::CustomEvent)>::new(move |ev: web_sys::CustomEvent| {
        if let Some(name) = ev.detail().as_string() {
            q2.borrow_mut().push(name);
            ctx.request_repaint();
        }
    });
    if let Some(w) = web_sys::window() {
        let _ = w.add_event_listener_with_callback(event, c.as_ref().unchecked_ref());
    }
    (queue, c)
}

pub fn location_hash() -> String {
    web_sys::window().and_then(|w| w.location().hash().ok()).unwrap_or_default()
}

/// A file input and its change listener (kept alive while it listens).
pub type FileInput = (Option<web_sys::HtmlInputElement>, Option<Closure<dyn FnMut()>>);

/// A hidden `<input type=file>` whose chosen files land in `sink`.
pub fn make_file_input(sink: Rc<RefCell<Vec<web_sys::File>>>, ctx: egui::Context) -> FileInput {
    let doc = web_sys::window().and_then(|w| w.document());
    let Some(doc) = doc else { return (None, None) };
    let Ok(el) = doc.create_element("input") else { return (None, None) };
    let Ok(input) = el.dyn_into::<web_sys::HtmlInputElement>() else { return (None, None) };
    input.set_type("file");
    input.set_accept(".obj,.gltf,.glb,.json,.3dm");
    input.set_id("sf-file-input");
    let _ = input.style().set_property("display", "none");
    if let Some(body) = doc.body() {
        let _ = body.append_child(&input);
    }
    let inp = input.clone();
    let closure = Closure::<dyn FnMut()>::new(move || {
        if let Some(files) = inp.files() {
            if let Some(f) = files.get(0) {
                sink.borrow_mut().push(f);
                ctx.request_repaint();
            }
        }
    });
    input.set_onchange(Some(closure.as_ref().unchecked_ref()));
    (Some(input), Some(closure))
}
