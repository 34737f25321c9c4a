// Dedicated worker: runs the Spherical Faces pipeline (the same wasm as the page).
// Messages in: {init: Int32Array|undefined} once, then {json, bodies} or {json, file: File}.
// Messages out: {json, bodies} from the wasm, or {panic: string} when the computation crashed.
// A Rhino .3dm file is converted here first, with rhino3dm.js (OpenNURBS in wasm, loaded on the
// first .3dm only), and its NURBS surfaces and meshes handed to the pipeline to pick from.
import init, { worker_start, worker_handle, worker_load_objects, worker_load_failed } from './pkg/spherical_faces.js';

const pending = [];
let ready = false;
let crashed = false;
// Messages are handled one after another; a .3dm conversion is asynchronous.
let queue = Promise.resolve();
let rhino = null;

// The pipeline's CAD model of panels.3dm (src/export/rhino.rs) is written as a .3dm here, with
// rhino3dm.js, before its Files message goes out; every message passes through `sfPost`, in order.
const RHINO_MODEL = 'panels.3dm.json';
// The pipeline runs synchronously, so only a message holding the model, and those after it while
// it is written, wait: progress and snapshots go out at once, and Cancel reaches a running method.
let outbox = Promise.resolve();
let waiting = 0;
self.sfPost = (obj, transfer) => {
  if (waiting === 0 && !obj.json.includes(RHINO_MODEL)) {
    self.postMessage(obj, transfer);
    return;
  }
  waiting++;
  outbox = outbox.then(() => postOut(obj, transfer)).finally(() => waiting--);
};

async function rhinoModule() {
  const { loadRhino } = await import('./rhino3dm/convert.mjs');
  rhino ??= await loadRhino(new URL('./rhino3dm/', import.meta.url).href);
  return rhino;
}

async function postOut(obj, transfer) {
  let notice = null;
  try {
    const msg = JSON.parse(obj.json);
    const files = msg.Files;
    const k = files ? files.fields.findIndex((f) => f.name === RHINO_MODEL) : -1;
    if (k >= 0) {
      try {
        const model = JSON.parse(new TextDecoder().decode(new Uint8Array(obj.bodies[k])));
        const { write3dm } = await import('./rhino3dm/write.mjs');
        const bytes = write3dm(model, await rhinoModule());
        files.fields[k] = { ...files.fields[k], name: 'panels.3dm', len: bytes.length };
        files.mime[k] = 'application/x-3dm';
        obj.bodies[k] = bytes.buffer;
      } catch (err) {
        files.fields.splice(k, 1);
        files.mime.splice(k, 1);
        obj.bodies.splice(k, 1);
        notice = `panels.3dm could not be written: ${err && err.message ? err.message : err}`;
      }
      obj.json = JSON.stringify(msg);
      transfer = obj.bodies.slice();
    }
  } catch (err) {
    notice = `a message could not be read: ${err && err.message ? err.message : err}`;
  }
  self.postMessage(obj, transfer);
  if (notice) self.postMessage({ json: JSON.stringify({ Error: { message: notice } }), bodies: [] });
}

async function convert3dm(file) {
  const { read3dm } = await import('./rhino3dm/convert.mjs');
  const bytes = new Uint8Array(new FileReaderSync().readAsArrayBuffer(file));
  return read3dm(bytes, await rhinoModule());
}

async function handle(data) {
  if (crashed) return;
  try {
    if (data.file instanceof File && /\.3dm$/i.test(data.file.name)) {
      let result;
      try {
        result = await convert3dm(data.file);
      } catch (err) {
        worker_load_failed(data.file.name, String(err && err.message ? err.message : err));
        return;
      }
      worker_load_objects(data.file.name, result.objects, result.notes, result.units ?? undefined);
      return;
    }
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

function enqueue(data) {
  queue = queue.then(() => handle(data));
}

self.onmessage = (event) => {
  const data = event.data;
  if (data && 'init' in data) {
    init().then(() => {
      worker_start(data.init);
      ready = true;
      for (const m of pending.splice(0)) enqueue(m);
    }).catch((err) => {
      self.postMessage({ panic: `The worker could not start: ${err && err.message ? err.message : err}` });
    });
    return;
  }
  if (!ready) pending.push(data);
  else enqueue(data);
};
