//! The pipeline: a loaded reference surface and the stages that run on it. It knows nothing of
//! the browser; the worker (wasm) and the CLI (native) drive a [`Session`] through an
//! [`Outbox`]; stages stream to a [`sink::Sink`].

pub mod fields;
pub mod method;
pub mod panel_output;
pub mod protocol;
pub mod session;
pub mod sink;
pub mod stages;

pub use session::{Loaded, Outbox, Session};
