//! The main thread's handle on the pipeline worker: typed messages out, decoded messages in.
//! A crashed worker is replaced; the app re-sends its design so nothing is lost.

use std::cell::{Cell, RefCell};
use std::collections::VecDeque;
use std::rc::Rc;

use js_sys::{Atomics, Int32Array, Object, Reflect, SharedArrayBuffer};
use wasm_bindgen::prelude::*;
use web_sys::{MessageEvent, Worker, WorkerOptions, WorkerType};

use super::transport;
use crate::pipeline::fields::Field;
use crate::pipeline::protocol::{decode_from_worker, encode_to_worker, FromWorker, ToWorker};

pub enum Incoming {
    Message(FromWorker, Vec<Field>),
    /// The worker crashed (panic or failed start); it has been replaced by a fresh one.
    Crashed(String),
}

type Inbox = Rc<RefCell<VecDeque<Incoming>>>;

/// The pipeline worker could not be started (the browser's reason).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum WorkerStartError {
    /// `new Worker("./worker.js")` failed.
    Spawn(String),
    /// The init message could not be posted.
    Init(String),
}

impl std::fmt::Display for WorkerStartError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            WorkerStartError::Spawn(e) | WorkerStartError::Init(e) => write!(f, "cannot start the pipeline worker: {e}"),
        }
    }
}

impl std::error::Error for WorkerStartError {}

/// The shared memory between the page and the worker (cross-origin isolated pages only): the
/// cancel flag, and the number of messages the worker has posted.
pub const CANCEL_SLOT: u32 = 0;
pub const POSTED_SLOT: u32 = 1;

pub struct WorkerClient {
    worker: Worker,
    inbox: Inbox,
    cancel_flag: Option<Int32Array>,
    /// Worker messages handed to the app by [`Self::poll`].
    polled: Cell<u32>,
    repaint: Rc<dyn Fn(Wake)>,
    _on_message: Closure<dyn FnMut(MessageEvent)>,
    _on_error: Closure<dyn FnMut(web_sys::ErrorEvent)>,
    pub restarts: u32,
}

/// How soon a message from the worker needs the UI redrawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wake {
    /// A result, an error, a crash: now.
    Now,
    /// Progress and live snapshots, which stream while the worker computes: within
    /// [`LIVE_REPAINT_MS`], so that a software renderer redrawing the view does not take the
    /// worker's CPU at every iteration.
    Soon,
}

/// The longest a streamed message waits for its redraw (ms).
pub const LIVE_REPAINT_MS: u64 = 100;

impl WorkerClient {
    /// Spawns `worker.js` next to the page. `repaint` wakes the UI when a message arrives: at
    /// once for a result, an error or a crash, [`Wake::Soon`] for progress and live snapshots.
    pub fn spawn(repaint: Rc<dyn Fn(Wake)>) -> Result<Self, WorkerStartError> {
        let inbox: Inbox = Rc::new(RefCell::new(VecDeque::new()));
        let opts = WorkerOptions::new();
        opts.set_type(WorkerType::Module);
        let worker = Worker::new_with_options("./worker.js", &opts).map_err(|e| WorkerStartError::Spawn(format!("{e:?}")))?;
        let on_message = {
            let inbox = inbox.clone();
            let repaint = repaint.clone();
            Closure::<dyn FnMut(MessageEvent)>::new(move |ev: MessageEvent| {
                let data = ev.data();
                let item = if let Some(p) = Reflect::get(&data, &"panic".into()).ok().and_then(|p| p.as_string()) {
                    Incoming::Crashed(p)
                } else {
                    let decoded =
                        transport::from_js(&data).map_err(|e| e.to_string()).and_then(|env| decode_from_worker(&env).map_err(|e| e.to_string()));
                    match decoded {
                        Ok((msg, fields)) => Incoming::Message(msg, fields),
                        Err(message) => Incoming::Message(FromWorker::Error { message, remesh_to: None }, Vec::new()),
                    }
                };
                let wake = match &item {
                    Incoming::Message(FromWorker::Progress(_) | FromWorker::Snapshot { .. }, _) => Wake::Soon,
                    _ => Wake::Now,
                };
                inbox.borrow_mut().push_back(item);
                repaint(wake);
            })
        };
        let on_error = {
            let inbox = inbox.clone();
            let repaint = repaint.clone();
            Closure::<dyn FnMut(web_sys::ErrorEvent)>::new(move |ev: web_sys::ErrorEvent| {
                ev.prevent_default();
                inbox.borrow_mut().push_back(Incoming::Crashed(format!("The pipeline worker failed: {}", ev.message())));
                repaint(Wake::Now);
            })
        };
        worker.set_onmessage(Some(on_message.as_ref().unchecked_ref()));
        worker.set_onerror(Some(on_error.as_ref().unchecked_ref()));
        // Cancel within one iteration needs shared memory, which needs cross-origin isolation.
        let isolated = Reflect::get(&js_sys::global(), &"crossOriginIsolated".into()).ok().and_then(|v| v.as_bool()).unwrap_or(false);
        let cancel_flag = isolated.then(|| Int32Array::new(&SharedArrayBuffer::new(8)));
        let init = Object::new();
        let flag: JsValue = cancel_flag.as_ref().map_or(JsValue::UNDEFINED, |a| a.clone().into());
        let _ = Reflect::set(&init, &"init".into(), &flag);
        worker.post_message(&init).map_err(|e| WorkerStartError::Init(format!("{e:?}")))?;
        Ok(Self { worker, inbox, cancel_flag, polled: Cell::new(0), repaint, _on_message: on_message, _on_error: on_error, restarts: 0 })
    }

    /// Sends a message; a `LoadFile` carries the browser `File` (read inside the worker).
    pub fn send(&self, msg: &ToWorker, file: Option<&web_sys::File>) {
        if matches!(msg, ToWorker::Run(_)) {
            if let Some(a) = &self.cancel_flag {
                let _ = Atomics::store(a, CANCEL_SLOT, 0);
            }
        }
        let (obj, transfer) = transport::to_js(&encode_to_worker(msg, None));
        if let Some(f) = file {
            let _ = Reflect::set(&obj, &"file".into(), f);
        }
        if let Err(e) = self.worker.post_message_with_transfer(&obj, &transfer) {
            self.inbox.borrow_mut().push_back(Incoming::Message(
                FromWorker::Error { message: format!("could not send to the worker: {e:?}"), remesh_to: None },
                Vec::new(),
            ));
        }
    }

    /// Requests a cancel. With shared memory the running stage stops at its next iteration, and
    /// this returns how many messages the worker had posted at the request (compare with
    /// [`Self::polled`]); without it, the worker is replaced (the caller re-sends its design).
    pub fn cancel(&mut self) -> Option<u32> {
        match &self.cancel_flag {
            Some(a) => {
                let _ = Atomics::store(a, CANCEL_SLOT, 1);
                let posted = Atomics::load(a, POSTED_SLOT).unwrap_or(0) as u32;
                self.send(&ToWorker::Cancel, None);
                Some(posted)
            }
            None => {
                self.restart();
                None
            }
        }
    }

    /// Worker messages polled so far (crash notices excluded).
    pub fn polled(&self) -> u32 {
        self.polled.get()
    }

    /// Replaces the worker with a fresh one.
    pub fn restart(&mut self) {
        self.worker.terminate();
        self.inbox.borrow_mut().retain(|m| !matches!(m, Incoming::Message(..)));
        let restarts = self.restarts + 1;
        match Self::spawn(self.repaint.clone()) {
            Ok(w) => {
                *self = w;
                self.restarts = restarts;
            }
            Err(e) => self.inbox.borrow_mut().push_back(Incoming::Message(FromWorker::Error { message: e.to_string(), remesh_to: None }, Vec::new())),
        }
    }

    pub fn poll(&self) -> Option<Incoming> {
        let item = self.inbox.borrow_mut().pop_front();
        if let Some(Incoming::Message(..)) = item {
            self.polled.set(self.polled.get() + 1);
        }
        item
    }
}

impl Drop for WorkerClient {
    fn drop(&mut self) {
        self.worker.terminate();
    }
}
