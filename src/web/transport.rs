//! Moves protocol [`Envelope`]s across `postMessage`: `{json: string, bodies: [ArrayBuffer]}`,
//! with the bodies transferred, not copied.

use js_sys::{Array, ArrayBuffer, Object, Reflect, Uint8Array};
use wasm_bindgen::{JsCast, JsValue};

use crate::pipeline::protocol::Envelope;

/// The message object and its transfer list.
pub fn to_js(env: &Envelope) -> (Object, Array) {
    let obj = Object::new();
    let bodies = Array::new();
    let transfer = Array::new();
    for b in &env.bodies {
        let buf = Uint8Array::from(b.as_slice()).buffer();
        bodies.push(&buf);
        transfer.push(&buf);
    }
    let _ = Reflect::set(&obj, &"json".into(), &JsValue::from_str(&env.json));
    let _ = Reflect::set(&obj, &"bodies".into(), &bodies);
    (obj, transfer)
}

/// A `postMessage` payload that is not `{json, bodies}`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TransportError {
    NoJsonHeader,
    BodyNotArrayBuffer,
}

impl std::fmt::Display for TransportError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            TransportError::NoJsonHeader => "message without a json header",
            TransportError::BodyNotArrayBuffer => "a message body is not an ArrayBuffer",
        })
    }
}

impl std::error::Error for TransportError {}

/// Reads `{json, bodies}` back.
pub fn from_js(value: &JsValue) -> Result<Envelope, TransportError> {
    let json = Reflect::get(value, &"json".into()).ok().and_then(|j| j.as_string()).ok_or(TransportError::NoJsonHeader)?;
    let mut bodies = Vec::new();
    if let Ok(list) = Reflect::get(value, &"bodies".into()) {
        if let Some(list) = list.dyn_ref::<Array>() {
            for b in list.iter() {
                let buf = b.dyn_into::<ArrayBuffer>().map_err(|_| TransportError::BodyNotArrayBuffer)?;
                bodies.push(Uint8Array::new(&buf).to_vec());
            }
        }
    }
    Ok(Envelope { json, bodies })
}
