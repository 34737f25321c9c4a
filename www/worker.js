// Dedicated worker: runs the Spherical Faces pipeline (the same wasm as the page).
// Messages in: {init: Int32Array|undefined} once, then {json, bodies} or {json, file: File}.
// Messages out: {json, bodies} from the wasm, or {panic: string} when the computation crashed.
import init, { worker_start, worker_handle } from './pkg/spherical_faces.js';

const pending = [];
let ready = false;
let crashed = false;

function handle(data) {
  if (crashed) return;
  try {
    if (data.file instanceof File) {
      // Read the dropped file here, off the main thread.
      const bytes = new FileReaderSync().readAsArrayBuffer(data.file);
      data = { json: data.json, bodies: [bytes] };
    }
    worker_handle(data);
  } catch (err) {
    crashed = true;
    // The wasm panic hook has already posted the panic message when it could.
    self.postMessage({ panic: `The computation crashed: ${err && err.message ? err.message : err}` });
    self.close();
  }
}

self.onmessage = (event) => {
  const data = event.data;
  if (data && 'init' in data) {
    init().then(() => {
      worker_start(data.init);
      ready = true;
      for (const m of pending.splice(0)) handle(m);
    }).catch((err) => {
      self.postMessage({ panic: `The worker could not start: ${err && err.message ? err.message : err}` });
    });
    return;
  }
  if (!ready) pending.push(data);
  else handle(data);
};
