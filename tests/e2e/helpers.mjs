// Shared harness for the Spherical Faces browser tests (node:test + playwright-core + Debian Chromium).
//
// - startServer(): runs www/serve.py --port 0 and parses the URL it prints.
// - launchBrowser(project): /usr/bin/chromium (never a downloaded browser) with the flags each
//   project needs; WebGPU runs on SwiftShader, WebGL2 on ANGLE/SwiftShader.
// - openApp()/withApp(): one fresh browser context per test, console/page errors collected and
//   printed (with the last #sf-state) when the test fails.
// - readState()/waitForState(): the app's automation contract, JSON in <pre id="sf-state">.
// - dropFile(): dragenter/dragover/drop DragEvents on #sf-canvas with a DataTransfer holding a File.
// - measureViewport(): screenshot + count pixels inside state.viewport that differ from clear_color.

import { spawn } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';
import pngjs from 'pngjs';

const { PNG } = pngjs;

export const E2E_DIR = path.dirname(fileURLToPath(import.meta.url));
export const REPO_ROOT = path.resolve(E2E_DIR, '..', '..');
export const SERVE_PY = path.join(REPO_ROOT, 'www', 'serve.py');
export const ARTIFACTS_DIR = path.join(E2E_DIR, 'artifacts');
export const CHROMIUM = process.env.SF_CHROMIUM || '/usr/bin/chromium';

// SwiftShader is slow and a cold load of a ~10 MB wasm can take 10-30 s: be generous.
// SF_TIMEOUT_SCALE=2 doubles every wait on a slow machine.
const SCALE = Number(process.env.SF_TIMEOUT_SCALE) > 0 ? Number(process.env.SF_TIMEOUT_SCALE) : 1;
export const T = {
  launch: 60_000 * SCALE,
  load: 90_000 * SCALE, // page navigation + wasm start + first frame with the mesh + curvature
  step: 60_000 * SCALE, // one action (drop, recompute) until the state shows its effect
  test: 300_000 * SCALE, // node:test timeout of one test
  server: 15_000 * SCALE,
};

export const BASE_ARGS = [
  '--no-sandbox',
  '--no-first-run',
  '--disable-background-networking',
  '--disable-component-update',
  '--disable-sync',
  '--disable-quic',
];
export const WEBGPU_ARGS = [
  '--enable-unsafe-webgpu',
  '--enable-unsafe-swiftshader',
  '--use-webgpu-adapter=swiftshader',
  '--enable-gpu',
  '--ignore-gpu-blocklist',
  '--enable-features=Vulkan',
  '--use-vulkan=swiftshader',
  '--use-angle=swiftshader',
];

const ALL_PROJECTS = [
  { name: 'webgpu', query: 'webgpu', backend: 'WebGPU', args: [...BASE_ARGS, ...WEBGPU_ARGS] },
  { name: 'webgl2', query: 'webgl2', backend: 'WebGL2', args: [...BASE_ARGS] },
];

// SF_PROJECTS=webgl2 (comma-separated) runs a subset while debugging; default: both.
export const PROJECTS = (() => {
  const want = (process.env.SF_PROJECTS || '').split(',').map((s) => s.trim()).filter(Boolean);
  if (want.length === 0) return ALL_PROJECTS;
  const unknown = want.filter((w) => !ALL_PROJECTS.some((p) => p.name === w));
  if (unknown.length) throw new Error(`SF_PROJECTS: unknown project(s) ${unknown.join(', ')} (known: webgpu, webgl2)`);
  return ALL_PROJECTS.filter((p) => want.includes(p.name));
})();

// ---------------------------------------------------------------------------------------------
// The build under test

/** Absolute path of the web build, or throws a clear error (the browser tests must fail, not skip). */
export function requireDist() {
  const dist = process.env.SF_DIST;
  if (!dist) {
    throw new Error(
      'SF_DIST is not set. The browser tests need the web build: run `bash www/dev.sh test` from the repo root, ' +
        'or build with `bash www/dev.sh build` and run `cd tests/e2e && SF_DIST=$PWD/../../target/dist node --test --test-concurrency=1 *.test.mjs`.',
    );
  }
  const root = path.resolve(dist);
  const wasm = path.join(root, 'pkg', 'spherical_faces_bg.wasm');
  if (!fs.existsSync(wasm)) {
    throw new Error(`SF_DIST=${dist} has no pkg/spherical_faces_bg.wasm (looked for ${wasm}). Build it first: bash www/dev.sh build`);
  }
  return root;
}

// ---------------------------------------------------------------------------------------------
// Static server (www/serve.py)

/**
 * Starts `python3 www/serve.py --root ROOT --port 0` and resolves once it printed its URL.
 * Returns { url, host, port, proc, output(), stop({ signal, timeout }) }.
 */
export function startServer(root, { extraArgs = ['--quiet'], python = process.env.PYTHON || 'python3' } = {}) {
  return new Promise((resolve, reject) => {
    const proc = spawn(python, [SERVE_PY, '--root', root, '--port', '0', ...extraArgs], {
      stdio: ['ignore', 'pipe', 'pipe'],
    });
    let stdout = '';
    let stderr = '';
    let settled = false;
    const exited = new Promise((res) => proc.on('exit', (code, signal) => res({ code, signal })));
    const timer = setTimeout(() => {
      if (settled) return;
      settled = true;
      proc.kill('SIGKILL');
      reject(new Error(`serve.py printed no URL within ${T.server} ms.\nstdout: ${stdout}\nstderr: ${stderr}`));
    }, T.server);
    const output = () => `stdout:\n${stdout.slice(-4000)}\nstderr:\n${stderr.slice(-4000)}`;
    proc.stdout.setEncoding('utf8');
    proc.stderr.setEncoding('utf8');
    proc.stderr.on('data', (d) => {
      stderr = (stderr + d).slice(-20_000); // keep draining so the pipe never fills
    });
    proc.stdout.on('data', (d) => {
      stdout = (stdout + d).slice(-20_000);
      const m = stdout.match(/Spherical Faces is being served at (http:\/\/(\S+):(\d+)\/) \(Ctrl-C to stop\)/);
      if (m && !settled) {
        settled = true;
        clearTimeout(timer);
        const server = {
          url: m[1],
          host: m[2],
          port: Number(m[3]),
          proc,
          exited,
          output,
          /** Sends `signal` and resolves {code, signal, ms}; SIGKILLs after `timeout` (then killed: true). */
          async stop({ signal = 'SIGINT', timeout = 5000 } = {}) {
            if (proc.exitCode !== null || proc.signalCode !== null) {
              return { code: proc.exitCode, signal: proc.signalCode, ms: 0, killed: false };
            }
            const t0 = Date.now();
            proc.kill(signal);
            let t;
            const r = await Promise.race([
              exited,
              new Promise((res) => {
                t = setTimeout(() => res(null), timeout);
              }),
            ]);
            clearTimeout(t);
            if (r) return { ...r, ms: Date.now() - t0, killed: false };
            proc.kill('SIGKILL');
            const k = await exited;
            return { ...k, ms: Date.now() - t0, killed: true };
          },
        };
        resolve(server);
      }
    });
    proc.on('error', (e) => {
      if (settled) return;
      settled = true;
      clearTimeout(timer);
      reject(new Error(`cannot start ${python} ${SERVE_PY}: ${e.message}`));
    });
    exited.then(({ code, signal }) => {
      if (settled) return;
      settled = true;
      clearTimeout(timer);
      reject(new Error(`serve.py exited (code ${code}, signal ${signal}) before printing its URL.\n${output()}`));
    });
  });
}

// ---------------------------------------------------------------------------------------------
// Browser

export async function launchBrowser(project) {
  if (!fs.existsSync(CHROMIUM)) {
    throw new Error(`${CHROMIUM} not found: install Debian's Chromium (apt-get install -y chromium chromium-driver). ` +
      'Never let a tool download its own browser.');
  }
  const extra = (process.env.SF_CHROMIUM_ARGS || '').split(' ').filter(Boolean);
  return chromium.launch({ executablePath: CHROMIUM, headless: true, args: [...project.args, ...extra], timeout: T.launch });
}

/** The app's URL; `backend: false` leaves ?backend out (the app's own choice). */
export function appUrl(server, project, fragment = '', { backend = true } = {}) {
  const frag = fragment ? (fragment.startsWith('#') ? fragment : `#${fragment}`) : '';
  return `${server.url}${backend ? `?backend=${project.query}` : ''}${frag}`;
}

function slug(s) {
  return String(s).replace(/[^A-Za-z0-9._-]+/g, '_').replace(/^_+|_+$/g, '').slice(0, 80);
}

/** Opens the app in a fresh context. Returns the `app` handle used by the other helpers. */
export async function openApp(browser, server, project, { fragment = '', name = 'app', backend = true } = {}) {
  const context = await browser.newContext({ viewport: { width: 1280, height: 800 }, deviceScaleFactor: 1, acceptDownloads: true });
  const page = await context.newPage();
  const app = {
    project,
    server,
    context,
    page,
    name: `${project.name}-${slug(name)}`,
    url: appUrl(server, project, fragment, { backend }),
    consoleAll: [], // last 300 console lines of any type
    consoleErrors: [],
    pageErrors: [],
    requestFailures: [],
    notes: [],
    lastState: undefined,
    crashed: false,
  };
  page.on('console', (msg) => {
    const line = `[${msg.type()}] ${msg.text()}`;
    app.consoleAll.push(line);
    if (app.consoleAll.length > 300) app.consoleAll.shift();
    if (msg.type() === 'error') app.consoleErrors.push(msg.text());
  });
  page.on('pageerror', (err) => app.pageErrors.push(err.stack || String(err)));
  page.on('requestfailed', (req) => app.requestFailures.push(`${req.method()} ${req.url()}: ${req.failure()?.errorText}`));
  page.on('response', (res) => {
    if (res.status() >= 400) app.requestFailures.push(`${res.request().method()} ${res.url()}: HTTP ${res.status()}`);
  });
  page.on('crash', () => {
    app.crashed = true;
  });
  page.on('worker', (w) => app.notes.push(`worker started: ${w.url()}`));
  await page.goto(app.url, { waitUntil: 'load', timeout: T.load });
  return app;
}

export function formatDiagnostics(app) {
  const tail = (arr, n) => (arr.length > n ? [`... (${arr.length - n} earlier)`, ...arr.slice(-n)] : arr);
  const parts = [
    `--- diagnostics for ${app.name} (${app.url})`,
    `page crashed: ${app.crashed}`,
    `last #sf-state: ${JSON.stringify(app.lastState)}`,
    `page errors (${app.pageErrors.length}):`,
    ...tail(app.pageErrors, 10).map((s) => `  ${s}`),
    `console errors (${app.consoleErrors.length}):`,
    ...tail(app.consoleErrors, 20).map((s) => `  ${s}`),
    `failed requests (${app.requestFailures.length}):`,
    ...tail(app.requestFailures, 10).map((s) => `  ${s}`),
    `notes:`,
    ...tail(app.notes, 10).map((s) => `  ${s}`),
    `console (last 40 lines):`,
    ...tail(app.consoleAll, 40).map((s) => `  ${s}`),
    `server ${app.server.output().split('\n').slice(-10).join('\n  ')}`,
    `---`,
  ];
  return parts.join('\n');
}

/**
 * Runs fn(app) on a freshly opened app page; on failure saves a screenshot to artifacts/ and
 * rethrows with the console errors, page errors and last #sf-state appended to the message.
 */
export async function withApp(_t, browser, server, project, opts, fn) {
  let app;
  try {
    app = await openApp(browser, server, project, opts);
    await fn(app);
  } catch (err) {
    let diag = `--- (the page could not be opened: no diagnostics)`;
    if (app) {
      try {
        app.lastState = (await readState(app.page, 5000)) ?? app.lastState;
      } catch {
        /* page gone */
      }
      try {
        const file = path.join(ARTIFACTS_DIR, `${app.name}-FAILED.png`);
        fs.mkdirSync(ARTIFACTS_DIR, { recursive: true });
        await app.page.screenshot({ path: file, timeout: 15_000 });
        app.notes.push(`failure screenshot: ${file}`);
      } catch (e) {
        app.notes.push(`failure screenshot not taken: ${e.message.split('\n')[0]}`);
      }
      diag = formatDiagnostics(app);
    }
    const wrapped = new Error(`${err.message}\n${diag}`);
    wrapped.stack = `${wrapped.message}\n${(err.stack || '').split('\n').slice(1).join('\n')}`;
    throw wrapped;
  } finally {
    if (app) await app.context.close().catch(() => {});
  }
}

// ---------------------------------------------------------------------------------------------
// Automation contract: <pre id="sf-state">

/**
 * Parsed #sf-state JSON; {__missing:true} when the element is absent, {__unparsable:text} when not
 * JSON, {__fatal:text} when index.html shows its start-up failure box (#sf-fatal).
 */
export async function readState(page, timeout = 10_000) {
  let timer;
  const evaluation = page.evaluate(() => {
    // index.html shows start-up failures (no WebGPU/WebGL2, wasm failed to load) in #sf-fatal
    const fatal = document.getElementById('sf-fatal');
    if (fatal && !fatal.hidden && fatal.textContent.trim()) return { __fatal: fatal.textContent.trim().slice(0, 1000) };
    const el = document.getElementById('sf-state');
    if (!el) return { __missing: true };
    const text = el.textContent || '';
    try {
      return JSON.parse(text);
    } catch {
      return { __unparsable: text.slice(0, 500) };
    }
  });
  const limit = new Promise((_, reject) => {
    timer = setTimeout(() => reject(new Error(`no answer within ${timeout} ms (page hung?)`)), timeout);
  });
  try {
    return await Promise.race([evaluation, limit]);
  } catch (e) {
    throw new Error(`reading #sf-state failed: ${String(e.message).split('\n')[0]}`);
  } finally {
    clearTimeout(timer);
    evaluation.catch(() => {});
  }
}

const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

/**
 * Polls #sf-state until predicate(state) is true; returns that state. Fails early when the page
 * crashes or throws a new uncaught error (a wasm panic would otherwise just time out).
 */
export async function waitForState(app, description, predicate, { timeout = T.step, interval = 250, failOnPageError = true } = {}) {
  const t0 = Date.now();
  const errorsBefore = app.pageErrors.length;
  for (;;) {
    if (app.crashed) throw new Error(`page crashed while waiting for ${description}`);
    let state;
    try {
      state = await readState(app.page);
    } catch (e) {
      if (Date.now() - t0 > timeout) throw e;
      await sleep(interval);
      continue;
    }
    if (state?.__fatal) throw new Error(`the app failed to start while waiting for ${description}: ${state.__fatal}`);
    if (state && !state.__missing && !state.__unparsable) app.lastState = state;
    else if (state) app.lastState = app.lastState ?? state;
    if (state && !state.__missing && !state.__unparsable) {
      let ok = false;
      try {
        ok = predicate(state);
      } catch {
        ok = false;
      }
      if (ok) return state;
    }
    if (failOnPageError && app.pageErrors.length > errorsBefore) {
      throw new Error(`uncaught page error while waiting for ${description}: ${app.pageErrors[app.pageErrors.length - 1].split('\n')[0]}`);
    }
    const elapsed = Date.now() - t0;
    if (elapsed > timeout) {
      let why = '';
      if (state?.__missing) why = ' (#sf-state is not in the page)';
      else if (state?.__unparsable) why = ` (#sf-state is not JSON: ${JSON.stringify(state.__unparsable)})`;
      throw new Error(`timed out after ${elapsed} ms waiting for ${description}${why}; last state: ${JSON.stringify(app.lastState)}`);
    }
    await sleep(interval);
  }
}

/** ready && curvature_ready && !busy: the mesh is drawn and coloured, the worker idle. */
export function isSettled(s) {
  return s.ready === true && s.curvature_ready === true && s.busy === false;
}

// ---------------------------------------------------------------------------------------------
// Dropping files

/**
 * Drops one file on #sf-canvas: dispatches dragenter, dragover, drop (bubbling, cancelable, at
 * the canvas centre) whose dataTransfer is a DataTransfer built in the page holding a File with
 * the given bytes. eframe's drop listener (on the canvas) reads dataTransfer.files.
 * Returns { files, size, dragenter, dragover, drop } where each event is 'prevented' when a
 * listener called preventDefault() (eframe does on dragover and drop).
 */
export async function dropFile(app, name, bytes, mime = '') {
  const b64 = Buffer.from(bytes).toString('base64');
  const r = await app.page.evaluate(
    ({ name, b64, mime }) => {
      const bin = atob(b64);
      const u8 = new Uint8Array(bin.length);
      for (let i = 0; i < bin.length; i++) u8[i] = bin.charCodeAt(i);
      const file = new File([u8], name, { type: mime, lastModified: Date.now() });
      const canvas = document.getElementById('sf-canvas');
      if (!canvas) throw new Error('#sf-canvas not found');
      const rect = canvas.getBoundingClientRect();
      const clientX = rect.left + rect.width / 2;
      const clientY = rect.top + rect.height / 2;
      const dt = new DataTransfer();
      dt.items.add(file);
      dt.effectAllowed = 'all';
      dt.dropEffect = 'copy';
      const out = { files: dt.files.length, size: file.size };
      for (const type of ['dragenter', 'dragover', 'drop']) {
        const ev = new DragEvent(type, { bubbles: true, cancelable: true, composed: true, clientX, clientY, dataTransfer: dt });
        out[type] = canvas.dispatchEvent(ev) ? 'not prevented' : 'prevented';
      }
      return out;
    },
    { name, b64, mime },
  );
  app.notes.push(`dropped ${name} (${r.size} bytes): dragenter ${r.dragenter}, dragover ${r.dragover}, drop ${r.drop}`);
  return r;
}

// ---------------------------------------------------------------------------------------------
// Pixels

/**
 * Screenshots the page (saved as artifacts/<app>-<label>.png) and counts the pixels inside
 * state.viewport (CSS px relative to #sf-canvas, scaled by devicePixelRatio) that differ from
 * state.clear_color by more than `tolerance` in any channel.
 */
export async function measureViewport(app, state, label, { tolerance = 12 } = {}) {
  const { canvasRect, dpr } = await app.page.evaluate(() => {
    const c = document.getElementById('sf-canvas');
    const r = c ? c.getBoundingClientRect() : { left: 0, top: 0, width: innerWidth, height: innerHeight };
    return { canvasRect: [r.left, r.top, r.width, r.height], dpr: window.devicePixelRatio || 1 };
  });
  fs.mkdirSync(ARTIFACTS_DIR, { recursive: true });
  const file = path.join(ARTIFACTS_DIR, `${app.name}-${slug(label)}.png`);
  const buf = await app.page.screenshot({ path: file, timeout: T.step });
  const png = PNG.sync.read(buf);
  const vp = state.viewport;
  const clear = state.clear_color;
  if (!Array.isArray(vp) || vp.length !== 4 || !vp.every(Number.isFinite)) {
    throw new Error(`state.viewport must be [x, y, w, h] in CSS px, got ${JSON.stringify(vp)}`);
  }
  if (!Array.isArray(clear) || clear.length < 3 || !clear.slice(0, 3).every(Number.isFinite)) {
    throw new Error(`state.clear_color must be [r, g, b] (0-255 sRGB), got ${JSON.stringify(clear)}`);
  }
  // Screenshot pixels per CSS px (Playwright's default scale 'device' makes this dpr).
  const sx = png.width / (await app.page.evaluate(() => window.innerWidth));
  const scale = Number.isFinite(sx) && sx > 0 ? sx : dpr;
  const clamp = (v, hi) => Math.max(0, Math.min(hi, v));
  const x0 = clamp(Math.round((canvasRect[0] + vp[0]) * scale), png.width);
  const y0 = clamp(Math.round((canvasRect[1] + vp[1]) * scale), png.height);
  const x1 = clamp(Math.round((canvasRect[0] + vp[0] + vp[2]) * scale), png.width);
  const y1 = clamp(Math.round((canvasRect[1] + vp[1] + vp[3]) * scale), png.height);
  const area = Math.max(0, x1 - x0) * Math.max(0, y1 - y0);
  let drawn = 0;
  let background = 0;
  for (let y = y0; y < y1; y++) {
    for (let x = x0; x < x1; x++) {
      const i = (y * png.width + x) * 4;
      const dr = Math.abs(png.data[i] - clear[0]);
      const dg = Math.abs(png.data[i + 1] - clear[1]);
      const db = Math.abs(png.data[i + 2] - clear[2]);
      if (dr > tolerance || dg > tolerance || db > tolerance) drawn++;
      else background++;
    }
  }
  const result = {
    file,
    png,
    rect: [x0, y0, x1 - x0, y1 - y0],
    image: [png.width, png.height],
    scale,
    dpr,
    area,
    drawn,
    background,
    drawnFraction: area ? drawn / area : 0,
    backgroundFraction: area ? background / area : 0,
  };
  const { png: _png, ...summary } = result;
  app.notes.push(`${label}: ${JSON.stringify(summary)}`);
  return result;
}

/**
 * The share of the viewport's pixels that changed between two measureViewport() results of the
 * same viewport (any channel by more than `tolerance`).
 */
export function changedFraction(a, b, { tolerance = 12 } = {}) {
  const [x0, y0, w, h] = a.rect;
  if (w * h === 0 || b.png.width !== a.png.width || b.png.height !== a.png.height) return 0;
  let changed = 0;
  for (let y = y0; y < y0 + h; y++) {
    for (let x = x0; x < x0 + w; x++) {
      const i = (y * a.png.width + x) * 4;
      if ([0, 1, 2].some((c) => Math.abs(a.png.data[i + c] - b.png.data[i + c]) > tolerance)) changed++;
    }
  }
  return changed / (w * h);
}

// ---------------------------------------------------------------------------------------------
// Test files

export const TRI_DOME = path.resolve(REPO_ROOT, '../shared/data/meshes/tri_dome.obj');
export const SADDLE = path.resolve(REPO_ROOT, '../shared/data/bsplines/saddle_sign_change.json');
export const MIXED_3DM = path.resolve(REPO_ROOT, 'tests/data/3dm/mixed.3dm');

/** A GLB that claims 1000 bytes and a JSON chunk but stops in the middle of it. */
export function truncatedGlb() {
  const head = Buffer.alloc(20);
  head.write('glTF', 0, 'latin1');
  head.writeUInt32LE(2, 4); // version
  head.writeUInt32LE(1000, 8); // total length (a lie)
  head.writeUInt32LE(400, 12); // JSON chunk length (a lie)
  head.write('JSON', 16, 'latin1');
  return Buffer.concat([head, Buffer.from('{"asset":{"version":"2.0"},"meshes":[{"primitives":[{"attri', 'latin1')]);
}

/**
 * Counts the pixels of a measureViewport() screenshot inside `rect` ([x, y, w, h] in CSS px of
 * the page; the whole viewport when omitted) for which `pick([r, g, b])` holds.
 */
export function countPixels(m, pick, rect = null) {
  const { png } = m;
  const scale = m.scale;
  const [x0, y0, w, h] = rect ? rect.map((v) => Math.round(v * scale)) : m.rect;
  let n = 0;
  for (let y = Math.max(0, y0); y < Math.min(png.height, y0 + h); y++) {
    for (let x = Math.max(0, x0); x < Math.min(png.width, x0 + w); x++) {
      const i = (y * png.width + x) * 4;
      if (pick([png.data[i], png.data[i + 1], png.data[i + 2]])) n++;
    }
  }
  return n;
}

/** Sets the page's design link (the URL fragment), as a user editing the address would. */
export async function editLink(app, fragment) {
  await app.page.evaluate((f) => {
    location.hash = f;
  }, fragment.startsWith('#') ? fragment.slice(1) : fragment);
}
