// Browser timings of the release build (not a test: `bash www/dev.sh timings`, after a build).
// Prints one line per measurement, `timing <name>: <ms> ms (<details>)`:
// - st_adapted_600: ST with adapted face size on the dome sample (3,456 triangles) remeshed to
//   about 600 faces, 45 iterations, from the run's request to its final panels (the page's own
//   clock, `last_run` in #sf-state: it includes the curvature stage the run starts with);
// - sq_sample: SQ on the vault sample at the default settings, the same way;
// - sq_<surface>: SQ at the default settings on hard surfaces of ../shared/data/bsplines/hard
//   (SF_SQ_HARD, default roof_rough,tunnel_bulged), each dropped on a page that has run SQ on the
//   vault, the same way (the dropped file's run);
// - import_curvature_1m: a generated 1,000,000-triangle OBJ dropped on the canvas, from the drop
//   to the coloured curvature (wall clock, polled every 50 ms), with the progress steps seen.
// Each page is fresh (the wasm compiles and warms up in it); the median of SF_RUNS (3) is printed.
// The two runs also print the wall clock from opening the page to the final panels, which includes
// the wasm start and the worker's warm-up (src/pipeline/warm_up.rs).
// SF_TIMINGS=st,sq,import picks the measurements (default all); SF_CHROMIUM_ARGS adds browser
// flags (e.g. "--js-flags=--no-liftoff" to compare the wasm tiers).
import fs from 'node:fs';
import path from 'node:path';
import { startServer, launchBrowser, openApp, waitForState, dropFile, requireDist, PROJECTS, REPO_ROOT, T } from './helpers.mjs';

const runs = Number(process.env.SF_RUNS || 3);
const project = PROJECTS.find((p) => p.name === (process.env.SF_PROJECT || 'webgpu')) || PROJECTS[0];
const median = (v) => [...v].sort((a, b) => a - b)[Math.floor(v.length / 2)];

function gridObj(n) {
  // An n × n grid on a paraboloid dome, 2n² triangles.
  const lines = [];
  for (let j = 0; j <= n; j++) {
    for (let i = 0; i <= n; i++) {
      const x = (i / n) * 20 - 10, y = (j / n) * 20 - 10;
      lines.push(`v ${x.toFixed(5)} ${y.toFixed(5)} ${(6 - 0.04 * (x * x + y * y)).toFixed(5)}`);
    }
  }
  const id = (i, j) => j * (n + 1) + i + 1;
  for (let j = 0; j < n; j++) {
    for (let i = 0; i < n; i++) {
      lines.push(`f ${id(i, j)} ${id(i + 1, j)} ${id(i + 1, j + 1)}`, `f ${id(i, j)} ${id(i + 1, j + 1)} ${id(i, j + 1)}`);
    }
  }
  return Buffer.from(lines.join('\n') + '\n');
}

async function timeStage(browser, server, name, fragment, ready) {
  const ms = [];
  const wall = [];
  let detail = '';
  for (let k = 0; k < runs; k++) {
    const opened = Date.now();
    const app = await openApp(browser, server, project, { fragment, name });
    try {
      const s = await waitForState(app, `${name} finished`, (s) => ready(s) && !s.busy && s.last_run, { timeout: T.load, interval: 50 });
      ms.push(s.last_run.ms);
      wall.push(Date.now() - opened);
      // The worker's own steps (the report's timings, ms), to tell compute from the page's share.
      const steps = (s.st_adapted ? s.st_adapted.timings_ms : s.sq && s.sq.report && s.sq.report.timings_ms) || {};
      const worker = Object.entries(steps).map(([k, v]) => `${k} ${Math.round(v)}`).join(', ');
      detail = `stage ${s.last_run.stage}, ${JSON.stringify(s.st_adapted ? { panels: s.st_adapted.panels, iterations: s.st_adapted.energies } : { mesh: s.sq && s.sq.mesh })}; worker steps (ms): ${worker}`;
    } finally {
      await app.context.close();
    }
  }
  console.log(`timing ${name}: ${median(ms).toFixed(0)} ms (median of ${ms.map((m) => m.toFixed(0)).join(', ')}; page open to panels ${median(wall)} ms; ${detail}; ${project.name})`);
}

async function timeDroppedSq(browser, server, surface) {
  const file = `${surface}.json`;
  const bytes = fs.readFileSync(path.resolve(REPO_ROOT, '../shared/data/bsplines/hard', file));
  const ms = [];
  let detail = '';
  for (let k = 0; k < runs; k++) {
    const app = await openApp(browser, server, project, { fragment: 'v=1&sample=vault&method=sq', name: `sq-${surface}` });
    try {
      const vault = await waitForState(app, 'SQ on the vault', (s) => s.sq && s.sq.ready && !s.busy && s.last_run, { timeout: T.load });
      await dropFile(app, file, bytes, 'application/json');
      const s = await waitForState(
        app,
        `SQ on ${file}`,
        (s) => s.source === `file:${file}` && s.sq && s.sq.ready && !s.busy && s.last_run && s.last_run.stage === 'sq' && s.last_run.ms !== vault.last_run.ms,
        { timeout: T.load, interval: 50 },
      );
      ms.push(s.last_run.ms);
      const steps = (s.sq.report && s.sq.report.timings_ms) || {};
      const worker = Object.entries(steps).map(([key, v]) => `${key} ${Math.round(v)}`).join(', ');
      detail = `${JSON.stringify({ mesh: s.sq.mesh })}; worker steps (ms): ${worker}`;
    } finally {
      await app.context.close();
    }
  }
  console.log(`timing sq_${surface}: ${median(ms).toFixed(0)} ms (median of ${ms.map((m) => m.toFixed(0)).join(', ')}; ${detail}; ${project.name})`);
}

async function timeImport(browser, server) {
  const bytes = gridObj(707);
  const ms = [];
  let steps = new Set();
  for (let k = 0; k < runs; k++) {
    const app = await openApp(browser, server, project, { name: 'import-1m' });
    try {
      await waitForState(app, 'the app is ready', (s) => s.ready === true && !s.busy, { timeout: T.load });
      await dropFile(app, 'grid_1m.obj', bytes, 'model/obj');
      const t0 = Date.now();
      await waitForState(
        app,
        'the dropped mesh coloured by curvature',
        (s) => {
          if (s.progress) steps.add(s.progress[0] || s.stage);
          return s.faces === 2 * 707 * 707 && s.curvature_ready && !s.busy;
        },
        { timeout: T.load * 4, interval: 50 },
      );
      ms.push(Date.now() - t0);
    } finally {
      await app.context.close();
    }
  }
  console.log(`timing import_curvature_1m: ${median(ms).toFixed(0)} ms (median of ${ms.join(', ')}; ${bytes.length} bytes, ${2 * 707 * 707} triangles; progress steps seen: ${[...steps].join(', ')}; ${project.name})`);
}

const dist = requireDist();
const server = await startServer(dist);
const browser = await launchBrowser(project);
try {
  const only = (process.env.SF_TIMINGS || 'st,sq,import').split(',');
  if (only.includes('st')) {
    await timeStage(browser, server, 'st_adapted_600', 'v=1&sample=dome&method=st&sizing=faces&faces=600&variant=a', (s) => s.st_adapted && s.st_adapted.ready);
  }
  if (only.includes('sq')) await timeStage(browser, server, 'sq_sample', 'v=1&sample=vault&method=sq', (s) => s.sq && s.sq.ready);
  if (only.includes('sq')) {
    for (const surface of (process.env.SF_SQ_HARD || 'roof_rough,tunnel_bulged').split(',')) await timeDroppedSq(browser, server, surface);
  }
  if (only.includes('import')) await timeImport(browser, server);
} finally {
  await browser.close();
  server.stop && server.stop();
}
