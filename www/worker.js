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

async function convert3dm(file) {
  const { loadRhino, read3dm } = await import('./rhino3dm/convert.mjs');
  rhino ??= await loadRhino(new URL('./rhino3dm/', import.meta.url).href);
  const bytes = new Uint8Array(new FileReaderSync().readAsArrayBuffer(file));
  return read3dm(bytes, rhino);
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
