//! The worker side: the same wasm, instantiated by www/worker.js in a dedicated Web Worker, runs
//! the pipeline [`Session`] and streams messages back.

use std::cell::RefCell;

use js_sys::{Atomics, Int32Array, Reflect};
use wasm_bindgen::prelude::*;
use web_sys::DedicatedWorkerGlobalScope;

use super::transport;
use super::worker_client::{CANCEL_SLOT, POSTED_SLOT};
use crate::pipeline::fields::Field;
use crate::pipeline::protocol::{decode_to_worker, encode_from_worker, FileObject, FromWorker, ObjectKind};
use crate::pipeline::{Outbox, Session};
use crate::progress::Clock;

thread_local! {
    static SESSION: RefCell<Session> = RefCell::new(Session::new());
    static CANCEL: RefCell<Option<Int32Array>> = const { RefCell::new(None) };
}

fn scope() -> DedicatedWorkerGlobalScope {
    js_sys::global().unchecked_into()
}

fn post_panic(message: &str) {
    let obj = js_sys::Object::new();
    let _ = Reflect::set(&obj, &"panic".into(), &JsValue::from_str(message));
    let _ = scope().post_message(&obj);
}

/// Called once by worker.js. `cancel` is an `Int32Array` over a `SharedArrayBuffer` when the
/// page is cross-origin isolated (cancel within one iteration), otherwise `undefined`.
#[wasm_bindgen]
pub fn worker_start(cancel: JsValue) {
    std::panic::set_hook(Box::new(|info| {
        console_error_panic_hook::hook(info);
        post_panic(&format!("The computation crashed: {info}"));
    }));
    CANCEL.with(|c| *c.borrow_mut() = cancel.dyn_into::<Int32Array>().ok());
    SESSION.with(|s| s.borrow_mut().clock = Clock(Some(js_sys::Date::now)));
    WorkerOutbox.send(FromWorker::Ready, Vec::new());
    // Messages that arrive meanwhile wait (a few hundred ms in baseline code).
    if let Err(e) = crate::pipeline::protocol::warm_up() {
        web_sys::console::warn_1(&format!("the solver warm-up failed: {e}").into());
    }
}

/// Handles one message `{json, bodies}` from the main thread.
#[wasm_bindgen]
pub fn worker_handle(data: JsValue) {
    let env = match transport::from_js(&data) {
        Ok(e) => e,
        Err(e) => return WorkerOutbox.send(FromWorker::Error { message: e.to_string(), remesh_to: None }, Vec::new()),
    };
    match decode_to_worker(&env) {
        Ok((msg, bytes)) => SESSION.with(|s| s.borrow_mut().handle(msg, bytes, &mut WorkerOutbox)),
        Err(e) => WorkerOutbox.send(FromWorker::Error { message: e.to_string(), remesh_to: None }, Vec::new()),
    }
}

/// Called by worker.js with the objects rhino3dm.js read from a .3dm file: an array of
/// `{name, kind, summary, text}`, the reader's notes and the file's model unit system by its
/// Rhino name.
#[wasm_bindgen]
pub fn worker_load_objects(file: String, objects: JsValue, notes: JsValue, units: Option<String>) {
    let text = |o: &JsValue, key: &str| Reflect::get(o, &key.into()).ok().and_then(|v| v.as_string()).unwrap_or_default();
    let (mut list, mut texts) = (Vec::new(), Vec::new());
    for o in js_sys::Array::from(&objects).iter() {
        list.push(FileObject {
            name: text(&o, "name"),
            kind: if text(&o, "kind") == "surface" { ObjectKind::Surface } else { ObjectKind::Mesh },
            summary: text(&o, "summary"),
        });
        texts.push(text(&o, "text"));
    }
    let notes: Vec<String> = js_sys::Array::from(&notes).iter().filter_map(|n| n.as_string()).collect();
    let units = units.as_deref().and_then(crate::units::Units::from_name);
    SESSION.with(|s| s.borrow_mut().load_objects(&file, list, texts, notes, units, &mut WorkerOutbox));
}

/// Called by worker.js when rhino3dm.js could not read a .3dm file.
#[wasm_bindgen]
pub fn worker_load_failed(file: String, message: String) {
    let message = format!("{}: {}", crate::text::clip(&file, 120), crate::text::printable(&message));
    WorkerOutbox.send(FromWorker::Error { message, remesh_to: None }, Vec::new());
}

struct WorkerOutbox;

impl Outbox for WorkerOutbox {
    fn send(&mut self, msg: FromWorker, fields: Vec<Field>) {
        let (obj, transfer) = transport::to_js(&encode_from_worker(&msg, &fields));
        CANCEL.with(|c| {
            if let Some(a) = c.borrow().as_ref() {
                let _ = Atomics::add(a, POSTED_SLOT, 1);
            }
        });
        // worker.js's `sfPost` keeps the order of messages while it writes panels.3dm from its
        // model (www/rhino3dm/write.mjs); without it, post directly.
        let hook = Reflect::get(&scope(), &"sfPost".into()).ok().and_then(|f| f.dyn_into::<js_sys::Function>().ok());
        let posted = match hook {
            Some(f) => f.call2(&JsValue::UNDEFINED, &obj, &transfer).map(drop),
            None => scope().post_message_with_transfer(&obj, &transfer),
        };
        if let Err(e) = posted {
            web_sys::console::error_2(&"postMessage failed".into(), &e);
        }
    }

    fn cancel_requested(&mut self) -> bool {
        CANCEL.with(|c| c.borrow().as_ref().is_some_and(|a| Atomics::load(a, CANCEL_SLOT).unwrap_or(0) != 0))
    }

    fn now_ms(&self) -> f64 {
        js_sys::Date::now()
    }
}
