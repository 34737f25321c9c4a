// Browser end-to-end tests of the web build in $SF_DIST, each run as two projects:
// "webgpu" (?backend=webgpu, WebGPU on SwiftShader) and "webgl2" (?backend=webgl2).
// They talk to the app only through its automation contract: #sf-canvas, the JSON in
// <pre id="sf-state">, the design-link fragment and files dropped on the canvas.
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import { spawnSync } from 'node:child_process';
import { after, describe, test } from 'node:test';
import {
  PROJECTS,
  T,
  TRI_DOME,
  MIXED_3DM, SADDLE,
  changedFraction,
  countPixels,
  dropFile,
  editLink,
  isSettled,
  launchBrowser,
  measureViewport,
  readState,
  requireDist,
  startServer,
  truncatedGlb,
  waitForState,
  withApp,
  ARTIFACTS_DIR,
  E2E_DIR,
} from './helpers.mjs';

const MIN_DRAWN = 0.02; // share of the viewport that must differ from the clear colour
const MIN_BACKGROUND = 0.01; // ... and that must show the clear colour (else clear_color is wrong)
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

function assertDrawn(m, what) {
  assert.ok(m.area > 0, `${what}: the viewport ${JSON.stringify(m.rect)} is empty inside the ${m.image.join('x')} screenshot`);
  assert.ok(
    m.drawnFraction > MIN_DRAWN,
    `${what}: only ${(100 * m.drawnFraction).toFixed(2)}% of the viewport differs from clear_color ` +
      `(need > ${100 * MIN_DRAWN}%); screenshot ${m.file}`,
  );
  assert.ok(
    m.backgroundFraction > MIN_BACKGROUND,
    `${what}: clear_color is almost nowhere in the viewport (${(100 * m.backgroundFraction).toFixed(2)}%): ` +
      `is state.clear_color the sRGB 0-255 background and state.viewport right? screenshot ${m.file}`,
  );
}

/**
 * Scrolls the side panel (wheel over it) until the bottom of the method's results shows, as a
 * user would at 1280×800; returns the last state.
 */
async function scrollResultsIntoView(app, s) {
  for (let k = 0; k < 25 && !(s.side_panel && s.side_panel.results_visible); k++) {
    await app.page.mouse.move(120, 450);
    await app.page.mouse.wheel(0, 300);
    await sleep(250);
    s = await readState(app.page);
  }
  return s;
}

const settledDefault = (app) =>
  waitForState(app, 'the default sample drawn (ready && curvature_ready && !busy)', isSettled, { timeout: T.load });

for (const project of PROJECTS) {
  describe(`${project.name}`, () => {
    // Started by the first test that needs them (not in a before() hook: node:test would report
    // a failing hook as "cancelled" tests; this way a missing build fails every test loudly).
    let setup;
    let server;
    let browser;
    const env = () => {
      setup ??= (async () => {
        const dist = requireDist(); // throws a clear error when SF_DIST is unset or not built
        server = await startServer(dist);
        browser = await launchBrowser(project);
        return { server, browser };
      })();
      return setup;
    };

    after(async () => {
      if (browser) await browser.close().catch(() => {});
      if (server) await server.stop({ signal: 'SIGINT', timeout: 3000 }).catch(() => {});
    });

    test(`[${project.name}] a. page loads and draws the default sample`, { timeout: T.test }, async (t) => {
      const { server, browser } = await env();
      await withApp(t, browser, server, project, { name: 'a-default' }, async (app) => {
        const s = await settledDefault(app);
        assert.equal(s.backend, project.backend, `backend (asked for ?backend=${project.query})`);
        assert.match(String(s.source), /^sample:/, 'source of the default mesh');
        assert.ok(s.vertices > 0 && s.faces > 0, `vertices ${s.vertices}, faces ${s.faces}`);
        assert.ok(s.frames > 0, `frames ${s.frames}`);
        assert.ok(!s.error, `an error is shown right after loading: ${JSON.stringify(s.error)}`);
        const m = await measureViewport(app, s, 'default-sample');
        t.diagnostic(`drawn ${(100 * m.drawnFraction).toFixed(1)}% of viewport ${JSON.stringify(m.rect)}; screenshot ${m.file}`);
        assertDrawn(m, 'default sample');
        const icon = await app.page.evaluate(async () => {
          const link = document.querySelector('link[rel="icon"]');
          return link ? { href: link.href, status: (await fetch(link.href)).status } : null;
        });
        assert.ok(icon && icon.status === 200, `the favicon is linked and served: ${JSON.stringify(icon)}`);
        assert.deepEqual(app.requestFailures, [], 'no request fails on load (the favicon included)');
        assert.deepEqual(app.consoleErrors, [], 'no console error on load');
        assert.deepEqual(app.pageErrors, [], 'uncaught page errors');
      });
    });

    test(`[${project.name}] b. dropping tri_dome.obj shows it`, { timeout: T.test }, async (t) => {
      const { server, browser } = await env();
      const bytes = fs.readFileSync(TRI_DOME);
      await withApp(t, browser, server, project, { name: 'b-drop-obj' }, async (app) => {
        await settledDefault(app);
        const d = await dropFile(app, 'tri_dome.obj', bytes, 'model/obj');
        assert.equal(d.files, 1);
        const s = await waitForState(
          app,
          'source == "file:tri_dome.obj" with curvature_ready',
          (s) => s.source === 'file:tri_dome.obj' && isSettled(s),
        );
        assert.equal(s.vertices, 91, 'vertices of tri_dome.obj');
        assert.ok(s.faces > 0, `faces ${s.faces}`);
        assert.ok(!s.error, `error after a valid drop: ${JSON.stringify(s.error)}`);
        const m = await measureViewport(app, s, 'tri_dome');
        t.diagnostic(`drawn ${(100 * m.drawnFraction).toFixed(1)}% of the viewport; screenshot ${m.file}`);
        assertDrawn(m, 'tri_dome.obj');
        assert.deepEqual(app.pageErrors, [], 'uncaught page errors');
      });
    });

    const corrupt = [
      { name: 'broken.obj', mime: 'model/obj', bytes: () => Buffer.from('v 1 2\nf 1 2 9\n') },
      { name: 'truncated.glb', mime: 'model/gltf-binary', bytes: truncatedGlb },
    ];
    for (const file of corrupt) {
      test(`[${project.name}] c. a corrupt ${file.name} shows an error and keeps the mesh`, { timeout: T.test }, async (t) => {
        const { server, browser } = await env();
        await withApp(t, browser, server, project, { name: `c-${file.name}` }, async (app) => {
          const before = await settledDefault(app);
          assert.ok(!before.error, `an error is already shown before the drop: ${JSON.stringify(before.error)}`);
          await dropFile(app, file.name, file.bytes(), file.mime);
          const s = await waitForState(
            app,
            `state.error after dropping ${file.name}`,
            (s) => typeof s.error === 'string' && s.error.trim().length > 0 && s.busy === false,
          );
          t.diagnostic(`error shown: ${s.error}`);
          assert.equal(s.source, before.source, 'the previous mesh is kept (source)');
          assert.equal(s.vertices, before.vertices, 'the previous mesh is kept (vertices)');
          assert.equal(s.faces, before.faces, 'the previous mesh is kept (faces)');
          // nothing replaces it a moment later either, and it is still drawn
          await sleep(1000);
          const later = await readState(app.page);
          assert.equal(later.source, before.source, 'source a second later');
          assert.equal(later.vertices, before.vertices, 'vertices a second later');
          assert.equal(later.ready, true, 'still ready');
          assertDrawn(await measureViewport(app, later, `after-${file.name}`), `mesh kept after ${file.name}`);
          assert.deepEqual(app.pageErrors, [], 'uncaught page errors');
        });
      });
    }

    test(`[${project.name}] d. a design link restores its parameters`, { timeout: T.test }, async (t) => {
      const { server, browser } = await env();
      const fragment = 'v=1&sample=torus&color=k1&shading=flat&jet_degree=2&cam=0.5,0.3,6,0,0,0&bogus=7';
      await withApp(t, browser, server, project, { name: 'd-design-link', fragment }, async (app) => {
        await waitForState(
          app,
          'sample:torus drawn (ready && source == "sample:torus")',
          (s) => s.ready === true && s.source === 'sample:torus',
          { timeout: T.load },
        );
        // give the rest of the link a moment to show up, then assert field by field
        const restored = (s) =>
          s.color_by === 'k1' && s.shading === 'flat' && String(s.design_link).includes('jet_degree=2') &&
          Array.isArray(s.notices) && s.notices.some((n) => String(n).includes('bogus'));
        const s = await waitForState(app, 'every design-link field restored', restored, { timeout: 15_000 }).catch(
          () => app.lastState,
        );
        assert.equal(s.backend, project.backend, 'backend');
        assert.equal(s.color_by, 'k1', 'color_by');
        assert.equal(s.shading, 'flat', 'shading');
        assert.equal(typeof s.design_link, 'string', 'design_link');
        assert.ok(s.design_link.includes('sample=torus'), `design_link ${s.design_link} has sample=torus`);
        assert.ok(s.design_link.includes('jet_degree=2'), `design_link ${s.design_link} has jet_degree=2`);
        assert.ok(s.design_link.includes('v=1'), `design_link ${s.design_link} has v=1`);
        assert.ok(Array.isArray(s.notices), `notices is an array: ${JSON.stringify(s.notices)}`);
        assert.ok(
          s.notices.some((n) => String(n).includes('bogus')),
          `a notice mentions the ignored field "bogus": ${JSON.stringify(s.notices)}`,
        );
        assert.deepEqual(app.pageErrors, [], 'uncaught page errors');
      });
    });

    test(`[${project.name}] e. a worker crash is shown, the worker restarts and the design survives`, { timeout: T.test }, async (t) => {
      const { server, browser } = await env();
      await withApp(t, browser, server, project, { name: 'e-crash' }, async (app) => {
        const before = await settledDefault(app);
        assert.equal(before.worker_restarts, 0);
        await app.page.evaluate(() => window.dispatchEvent(new Event('sf-crash-worker')));
        const s = await waitForState(
          app,
          'worker restarted, error shown, curvature recomputed',
          (s) => s.worker_restarts >= 1 && /crash/i.test(String(s.error)) && isSettled(s),
          { failOnPageError: false },
        );
        t.diagnostic(`error shown: ${s.error}`);
        assert.equal(s.source, before.source, 'the design is kept (source)');
        assert.equal(s.vertices, before.vertices, 'the design is kept (vertices)');
        assert.equal(s.design_link, before.design_link, 'the design link is unchanged');
        assertDrawn(await measureViewport(app, s, 'after-crash'), 'mesh after the worker crash');
      });
    });

    test(`[${project.name}] f. reflective shading with edges draws, and a click shows a central sphere`, { timeout: T.test }, async (t) => {
      const { server, browser } = await env();
      const fragment = 'v=1&sample=sphere-cap&shading=reflective&edges=1&color=none';
      await withApp(t, browser, server, project, { name: 'f-reflective', fragment }, async (app) => {
        const s = await waitForState(app, 'sphere cap settled', (s) => s.source === 'sample:sphere-cap' && isSettled(s), { timeout: T.load });
        assert.equal(s.shading, 'reflective');
        assert.equal(s.edges, true);
        const m = await measureViewport(app, s, 'reflective-edges');
        assertDrawn(m, 'reflective sphere cap with edges');
        assert.equal(s.selected_vertex, null, 'no vertex selected before the click');
        const [x, y, w, h] = s.viewport;
        await app.page.mouse.click(x + w / 2, y + h / 2);
        const picked = await waitForState(app, 'a vertex is selected', (s) => Number.isInteger(s.selected_vertex));
        await sleep(500);
        const after = await measureViewport(app, picked, 'central-sphere');
        const changed = changedFraction(m, after);
        t.diagnostic(`selected vertex ${picked.selected_vertex}; ${(100 * changed).toFixed(2)}% of the viewport changed`);
        assertDrawn(after, 'central sphere overlay');
        // The translucent central sphere covers part of the view: the picture changed there.
        assert.ok(changed > 0.005, `the click changed only ${(100 * changed).toFixed(3)}% of the viewport`);
        assert.deepEqual(app.pageErrors, [], 'uncaught page errors');
      });
    });

    test(`[${project.name}] g. ST with support structure runs on the default sample and its GLB downloads`, { timeout: T.test }, async (t) => {
      const { server, browser } = await env();
      await withApp(t, browser, server, project, { name: 'g-st-support', fragment: 'v=1&sample=dome&method=st-support&shading=reflective' }, async (app) => {
        const s = await waitForState(
          app,
          'st-support finished (st_support.ready, downloads offered)',
          (s) => s.st_support && s.st_support.ready === true && !s.busy && Array.isArray(s.downloads) && s.downloads.includes('panels.glb'),
          { timeout: T.load },
        );
        assert.equal(s.method, 'st-support');
        assert.ok(!s.error, `error: ${s.error}`);
        assert.equal(s.st_support.panels, s.faces, 'one panel per face of the reference triangulation');
        const shown = await scrollResultsIntoView(app, s);
        t.diagnostic(`side panel: ${JSON.stringify(shown.side_panel)}`);
        assert.equal(shown.side_panel.results_visible, true, 'the metrics and histograms can be scrolled into view at 1280×800');
        for (const f of ['panels.glb', 'panels.obj', 'panels.csv', 'panels.json', 'moulds.csv', 'report.json']) {
          assert.ok(s.downloads.includes(f), `${f} offered (${s.downloads})`);
        }
        assertDrawn(await measureViewport(app, s, 'st-support'), 'panels and support structure');
        const [download] = await Promise.all([
          app.page.waitForEvent('download', { timeout: 30_000 }),
          app.page.evaluate(() => window.dispatchEvent(new CustomEvent('sf-download', { detail: 'panels.glb' }))),
        ]);
        assert.equal(download.suggestedFilename(), 'panels.glb');
        fs.mkdirSync(ARTIFACTS_DIR, { recursive: true });
        const file = path.join(ARTIFACTS_DIR, `${project.name}-panels.glb`);
        await download.saveAs(file);
        const bytes = fs.readFileSync(file);
        assert.equal(bytes.subarray(0, 4).toString('latin1'), 'glTF', 'GLB magic');
        const v = spawnSync(process.execPath, [path.join(E2E_DIR, 'validate-gltf.mjs'), file], { encoding: 'utf8' });
        t.diagnostic(`validator: ${v.stdout.slice(0, 300)}`);
        assert.equal(v.status, 0, `the Khronos validator accepts the downloaded GLB: ${v.stdout}${v.stderr}`);
        assert.deepEqual(app.pageErrors, [], 'uncaught page errors');
      });
    });

    test(`[${project.name}] h. ST with adapted face size streams sizing, remesh, panels and energies, and its GLB validates`, { timeout: T.test }, async (t) => {
      const { server, browser } = await env();
      const fragment = 'v=1&sample=dome&method=st&sizing=adaptive&eps=0.0004&variant=a&color=sizing';
      await withApp(t, browser, server, project, { name: 'h-st-adapted', fragment }, async (app) => {
        const running = await waitForState(
          app,
          'sizing field and remeshed triangulation arrived',
          (s) => s.st_adapted && s.st_adapted.sizing > 0 && s.st_adapted.remeshed_faces > 0,
          { timeout: T.load },
        );
        assert.equal(running.st_adapted.sizing, running.vertices, 'one sizing value per reference vertex');
        const s = await waitForState(
          app,
          'st finished (st_adapted.ready, downloads offered)',
          (s) => s.st_adapted && s.st_adapted.ready && !s.busy && s.downloads.includes('panels.glb'),
          { timeout: T.load },
        );
        t.diagnostic(`st: ${JSON.stringify(s.st_adapted)}`);
        assert.equal(s.method, 'st');
        assert.ok(!s.error, `error: ${s.error}`);
        assert.equal(s.st_adapted.energies, 45, 'one energy per optimizer iteration');
        assert.equal(s.st_adapted.panel_iteration, 45, 'the final panels are those of the last iteration');
        assert.ok(s.st_adapted.panel_snapshots >= 2, `panels arrived at the start and the end at least (${s.st_adapted.panel_snapshots})`);
        assert.equal(s.st_adapted.panels, s.st_adapted.remeshed_faces, 'one panel per remeshed face');
        assert.ok(s.st_adapted.remeshed_faces > 100 && s.st_adapted.remeshed_faces < 1000, `faces ${s.st_adapted.remeshed_faces}`);
        assert.ok(s.design_link.includes('method=st&') && s.design_link.includes('eps=4e-4'), s.design_link);
        const shown = await scrollResultsIntoView(app, s);
        t.diagnostic(`side panel: ${JSON.stringify(shown.side_panel)}`);
        assert.equal(shown.side_panel.results_visible, true, 'the energy plot and the run metrics can be scrolled into view at 1280×800');
        assertDrawn(await measureViewport(app, s, 'st-adapted'), 'ST panels');
        const [download] = await Promise.all([
          app.page.waitForEvent('download', { timeout: 30_000 }),
          app.page.evaluate(() => window.dispatchEvent(new CustomEvent('sf-download', { detail: 'panels.glb' }))),
        ]);
        fs.mkdirSync(ARTIFACTS_DIR, { recursive: true });
        const file = path.join(ARTIFACTS_DIR, `${project.name}-st-panels.glb`);
        await download.saveAs(file);
        const v = spawnSync(process.execPath, [path.join(E2E_DIR, 'validate-gltf.mjs'), file], { encoding: 'utf8' });
        assert.equal(v.status, 0, `the Khronos validator accepts the ST GLB: ${v.stdout}${v.stderr}`);
        assert.deepEqual(app.pageErrors, [], 'uncaught page errors');
      });
    });

    test(`[${project.name}] h2. ST moves its panels onto fewer moulds in the worker and snaps each to its mould's radius`, { timeout: T.test }, async (t) => {
      const { server, browser } = await env();
      const fragment = 'v=1&sample=dome&method=st&sizing=faces&faces=300&opt_moulds=1&mould_tol=0.5mm';
      await withApp(t, browser, server, project, { name: 'h2-st-moulds', fragment }, async (app) => {
        const s = await waitForState(
          app,
          'st finished with its moulds',
          (s) => s.st_adapted && s.st_adapted.ready && !s.busy && s.moulds !== null && s.downloads.includes('panels.csv'),
          { timeout: T.load },
        );
        const st = s.st_adapted;
        t.diagnostic(`st: ${JSON.stringify({ ...st, timings_ms: undefined })}; moulds ${JSON.stringify(s.moulds)}; timings ${JSON.stringify(st.timings_ms)}`);
        assert.ok(!s.error, `error: ${s.error}`);
        assert.ok(s.design_link.includes('opt_moulds=1') && s.design_link.includes('mould_tol=0.5mm'), s.design_link);
        const [count, tolerance, snapped] = s.moulds;
        assert.ok(Math.abs(tolerance - 5e-4) < 1e-12, `δ = 0.5 mm in metres: ${tolerance}`);
        // The rounds ran in the worker and kept fewer moulds; every panel was snapped.
        assert.ok(st.timings_ms.fewer_moulds > 0 && st.timings_ms.snap_moulds > 0, 'the rounds and the snap ran');
        assert.ok(Number.isInteger(st.moulds_before) && count < st.moulds_before, `moulds ${st.moulds_before} → ${count}`);
        assert.equal(snapped, st.panels, 'every panel has exactly its mould radius');
        assert.equal(st.mould_colours, Math.min(count, 16), 'one panel mesh per mould colour');
        assertDrawn(await measureViewport(app, s, 'st-moulds'), 'ST panels in mould colours');
        assert.deepEqual(app.pageErrors, [], 'uncaught page errors');
      });
    });

    test(`[${project.name}] i. the UI keeps drawing while an 8k-face ST optimizes, and Cancel stops it within one iteration`, { timeout: T.test }, async (t) => {
      const { server, browser } = await env();
      // 8000 faces: the whole run takes about ten seconds, so the cancel below finds it running
      // even when the UI lags the worker by a second (at 4000 faces a slow WebGL2 run once
      // finished before the cancel reached it).
      const fragment = 'v=1&sample=dome&method=st&sizing=faces&faces=8000&variant=a';
      await withApp(t, browser, server, project, { name: 'i-st-draw-cancel', fragment }, async (app) => {
        const first = await waitForState(
          app,
          'the optimizer is running (energies arriving)',
          (s) => s.busy && s.st_adapted && s.st_adapted.energies > 0,
          { timeout: T.load, interval: 50 },
        );
        assert.ok(first.st_adapted.remeshed_faces > 6000, `about 8000 faces: ${first.st_adapted.remeshed_faces}`);
        // Orbit the view meanwhile, as a user would: every frame then redraws the scene. Frame
        // rates are measured by the benchmarks, not here (the GPU is software on these machines).
        const [x, y, w, h] = first.viewport;
        await app.page.mouse.move(x + w / 2, y + h / 2);
        await app.page.mouse.down();
        // Until the view has redrawn and the optimizer has sent an iteration and a panel
        // snapshot more (at most 400 moves), so the cancel below still finds it running.
        let mid = first;
        for (let k = 0; k < 400; k++) {
          await app.page.mouse.move(x + w / 2 + 80 * Math.sin(k / 8), y + h / 2 + 40 * Math.cos(k / 8));
          await sleep(15);
          if (k % 4 === 3) {
            mid = await readState(app.page);
            const moved = mid.frames > first.frames + 2;
            const progressed = mid.st_adapted.energies > first.st_adapted.energies && mid.st_adapted.panel_snapshots > first.st_adapted.panel_snapshots;
            if ((moved && progressed) || !mid.busy) break;
          }
        }
        await app.page.mouse.up();
        t.diagnostic(
          `while optimizing and orbiting: frames ${first.frames} -> ${mid.frames}, ui() median ${mid.ui_ms_median.toFixed(2)} ms, ` +
            `panel snapshots ${first.st_adapted.panel_snapshots} -> ${mid.st_adapted.panel_snapshots}, iterations ${first.st_adapted.energies} -> ${mid.st_adapted.energies}`,
        );
        assert.ok(mid.frames > first.frames, 'the view kept redrawing');
        assert.ok(mid.busy && mid.st_adapted.energies > first.st_adapted.energies, 'still optimizing during the orbit');
        assert.ok(mid.st_adapted.panel_snapshots > first.st_adapted.panel_snapshots, 'panels arrived during the orbit');
        // Cancel, and measure from the request: the state just before it is the reference.
        const atRequest = await readState(app.page);
        await app.page.evaluate(() => window.dispatchEvent(new Event('sf-cancel')));
        await waitForState(app, 'not busy after Cancel', (s) => !s.busy, { timeout: 15_000 });
        await sleep(1500);
        const later = await readState(app.page);
        // The iterations the worker had sent when Cancel was pressed (the app counts them once it
        // has handled every message posted before the request; the UI lags behind the worker).
        const before = later.cancels.st_adapted_iterations_at_request;
        t.diagnostic(
          `iterations: shown at the cancel request ${atRequest.st_adapted.energies}, sent by then ${before}, 1.5 s later ${later.st_adapted.energies}; ` +
            `cancels ${JSON.stringify(later.cancels)}; restarts ${later.worker_restarts}; notices ${JSON.stringify(later.notices)}`,
        );
        // Cancel went through shared memory to the running stage, not by replacing the worker.
        assert.equal(later.cancels.cross_origin_isolated, true, 'the page is cross-origin isolated (served with COOP/COEP)');
        assert.equal(later.cancels.requested, atRequest.cancels.requested + 1, 'one cancel');
        assert.equal(later.cancels.in_worker, atRequest.cancels.in_worker + 1, 'the cancel reached the running stage');
        assert.equal(later.worker_restarts, atRequest.worker_restarts, 'the worker was not restarted');
        assert.ok(later.notices.some((n) => String(n) === "Stage 'st' cancelled."), `the stage answered Cancelled: ${JSON.stringify(later.notices)}`);
        assert.ok(!later.notices.some((n) => /worker was restarted/.test(String(n))), 'no restart fallback');
        // Within one iteration: at most the iteration in flight at the request completes.
        assert.ok(Number.isInteger(before) && before >= atRequest.st_adapted.energies, `iterations sent by the request: ${before}`);
        assert.ok(later.st_adapted.energies - before <= 1, `iterations after the cancel request: ${later.st_adapted.energies - before}`);
        assert.ok(later.st_adapted.energies < 45 && !later.st_adapted.ready, 'the run did not finish');
        assert.deepEqual(app.pageErrors, [], 'uncaught page errors');
      });
    });

    test(`[${project.name}] j. without ?backend the app chooses its backend: WebGPU where the browser has it, WebGL2 otherwise`, { timeout: T.test }, async (t) => {
      const { server, browser } = await env();
      await withApp(t, browser, server, project, { name: 'j-default-backend', backend: false }, async (app) => {
        const s = await settledDefault(app);
        const gpu = await app.page.evaluate(async () => !!(navigator.gpu && (await navigator.gpu.requestAdapter())));
        t.diagnostic(`WebGPU adapter available: ${gpu}; backend chosen: ${s.backend}`);
        assert.equal(s.backend, gpu ? 'WebGPU' : 'WebGL2');
        assert.equal(s.backend, project.backend, `this browser (${project.name} flags) should get ${project.backend}`);
        assertDrawn(await measureViewport(app, s, 'default-backend'), `default sample on ${s.backend}`);
        assert.deepEqual(app.pageErrors, [], 'uncaught page errors');
      });
    });

    test(`[${project.name}] k. Copy link copies a link that restores the design`, { timeout: T.test }, async (t) => {
      const { server, browser } = await env();
      const fragment = 'v=1&sample=torus&color=k2&shading=flat';
      await withApp(t, browser, server, project, { name: 'k-copy-link', fragment }, async (app) => {
        await app.context.grantPermissions(['clipboard-read', 'clipboard-write'], { origin: server.url.replace(/\/$/, '') });
        const s = await waitForState(app, 'torus settled', (s) => s.source === 'sample:torus' && isSettled(s), { timeout: T.load });
        const [bx, by, bw, bh] = s.side_panel.copy_link_button;
        assert.ok(bw > 0 && bh > 0, `the Copy link button is laid out: ${JSON.stringify(s.side_panel)}`);
        await app.page.mouse.click(bx + bw / 2, by + bh / 2);
        const copied = await waitForState(app, 'the copy notice', (s) => s.notices.includes('Design link copied.'));
        const text = await app.page.evaluate(() => navigator.clipboard.readText());
        t.diagnostic(`clipboard: ${text}`);
        assert.ok(text.startsWith(server.url), `${text} starts with ${server.url}`);
        assert.ok(text.endsWith(copied.design_link), `${text} ends with the design link ${copied.design_link}`);
        for (const part of ['sample=torus', 'color=k2', 'shading=flat', 'cam=']) {
          assert.ok(text.includes(part), `${part} in ${text}`);
        }
        assert.deepEqual(app.pageErrors, [], 'uncaught page errors');
      });
    });

    test(`[${project.name}] l. SQ (Sec. 5.1) on the vault sample streams lines and term energies, meets θ and α, and its congruence GLB validates`, { timeout: T.test }, async (t) => {
      const { server, browser } = await env();
      // The central congruence (its optimization streams; the auto start takes constant radii here).
      const fragment = 'v=1&sample=vault&method=sq&theta=20&alpha=75&grid=20&rs=10&until=congruence&start=central';
      await withApp(t, browser, server, project, { name: 'l-sq', fragment }, async (app) => {
        const s = await waitForState(
          app,
          'sq finished (sq.ready, downloads offered)',
          (s) => s.sq && s.sq.ready && !s.busy && s.downloads.includes('congruence.glb'),
          { timeout: T.load },
        );
        const r = s.sq.report;
        const sq = r.sq;
        const c = sq.congruence;
        t.diagnostic(`sq: ${JSON.stringify({ ...s.sq, report: undefined })}; section ${JSON.stringify(sq)}`);
        assert.equal(s.method, 'sq');
        assert.equal(r.schema, 3);
        assert.ok(!s.error, `error: ${s.error}`);
        assert.equal(s.source, 'sample:vault');
        for (const part of ['method=sq&', 'theta=20&alpha=75&grid=20&rs=10', 'start=central']) {
          assert.ok(s.design_link.includes(part), `${part} in ${s.design_link}`);
        }
        assert.equal(sq.grid, 20);
        assert.equal(sq.stopped_after, 'congruence');
        assert.equal(c.start, 'central');
        assert.ok(c.figures.max_line_normal_angle_deg <= 20, `max ∠(l, n) ${c.figures.max_line_normal_angle_deg}° ≤ θ`);
        assert.ok(c.figures.min_torsal_plane_angle_deg >= 75, `min torsal-plane angle ${c.figures.min_torsal_plane_angle_deg}° ≥ α`);
        assert.equal(c.figures.quads_without_real_torsal_directions, 0);
        assert.ok(c.lc_residual_step1 <= 1e-12, `E_LC per term after step 1: ${c.lc_residual_step1}`);
        assert.ok(Number.isFinite(c.lc_residual), 'E_LC after step 2 reported');
        assert.equal(s.sq.lines, 400, 'one line segment per grid point');
        assert.equal(s.sq.initial_lines, 400);
        assert.equal(s.sq.cross_field_arms, 2 * 361, 'two torsal arms per grid quad');
        assert.equal(s.sq.energies, sq.iterations, 'one energy report per solver iteration');
        assert.equal(s.sq.quad_mesh_edges, 0, 'stopped after the congruence: no quad mesh');
        for (const term of ['total', 'line_congruence', 'line_normal_angle', 'torsal_direction', 'torsal_angle', 'line_fairness']) {
          assert.ok(s.sq.terms.some((n) => n.startsWith(term)), `term ${term} plotted (${s.sq.terms})`);
        }
        for (const f of ['congruence.glb', 'congruence.json', 'report.json']) {
          assert.ok(s.downloads.includes(f), `${f} offered (${s.downloads})`);
        }
        const shown = await scrollResultsIntoView(app, s);
        assert.equal(shown.side_panel.results_visible, true, 'the energy plot and the figures can be scrolled into view at 1280×800');
        assertDrawn(await measureViewport(app, s, 'sq'), 'surface, lines and cross field');
        const [download] = await Promise.all([
          app.page.waitForEvent('download', { timeout: 30_000 }),
          app.page.evaluate(() => window.dispatchEvent(new CustomEvent('sf-download', { detail: 'congruence.glb' }))),
        ]);
        fs.mkdirSync(ARTIFACTS_DIR, { recursive: true });
        const file = path.join(ARTIFACTS_DIR, `${project.name}-congruence.glb`);
        await download.saveAs(file);
        const v = spawnSync(process.execPath, [path.join(E2E_DIR, 'validate-gltf.mjs'), file], { encoding: 'utf8' });
        assert.equal(v.status, 0, `the Khronos validator accepts the congruence GLB: ${v.stdout}${v.stderr}`);
        assert.deepEqual(app.pageErrors, [], 'uncaught page errors');
      });
    });

    test(`[${project.name}] n. SQ end to end (Sec. 5.2) on the vault sample: quad mesh, Q′, live panels, an exact SQ mesh with support structure, downloads`, { timeout: T.test }, async (t) => {
      const { server, browser } = await env();
      // Moulds within 0.05 mm of a vault in metres: several, each in its own colour; the exact
      // mesh then moved so that every panel has its mould's radius (opt_moulds).
      const fragment = 'v=1&sample=vault&method=sq&theta=20&alpha=75&grid=20&rs=10&faces=237&until=final&opt_moulds=1&mould_tol=0.05mm';
      await withApp(t, browser, server, project, { name: 'n-sq-final', fragment }, async (app) => {
        const s = await waitForState(
          app,
          'sq finished with panels (sq.ready, panels.glb offered)',
          (s) => s.sq && s.sq.ready && !s.busy && s.downloads.includes('panels.glb'),
          { timeout: T.load },
        );
        const r = s.sq.report;
        t.diagnostic(`sq: ${JSON.stringify({ ...s.sq, report: undefined })}; section ${JSON.stringify(r.sq)}; metrics ${JSON.stringify(r.metrics)}; timings ${JSON.stringify(r.timings_ms)}`);
        assert.ok(!s.error, `error: ${s.error}`);
        assert.equal(r.sq.stopped_after, 'final');
        assert.equal(r.meets_guarantees, true, `the verdict: ${JSON.stringify(r.guarantees)}`);
        assert.equal(s.missed_guarantees, null, 'no miss in the status bar');
        for (const part of ['faces=237', 'until=final', 'opt_moulds=1', 'mould_tol=0.05mm']) {
          assert.ok(s.design_link.includes(part), `${part} in ${s.design_link}`);
        }
        // The mould view: the report's moulds within δ, the panels in their moulds' colours.
        const mo = r.moulds;
        t.diagnostic(`moulds: ${mo.count} within ${mo.tolerance} ${mo.units}, largest deviation ${mo.max_deviation}; colours ${s.sq.mould_colours}`);
        assert.equal(mo.units, 'm');
        assert.ok(Math.abs(mo.tolerance - 5e-5) < 1e-12, `δ = 0.05 mm in metres: ${mo.tolerance}`);
        assert.ok(mo.count > 1 && mo.max_deviation <= mo.tolerance, `${mo.count} moulds, largest deviation ${mo.max_deviation}`);
        assert.equal(mo.moulds.reduce((n, m) => n + m.panels, 0), r.output.panels, 'every panel on a mould');
        assert.deepEqual(s.moulds, [mo.count, mo.tolerance, mo.snap.snapped], 'the side panel shows the same moulds');
        // The rounds ran in the worker: every panel has its mould's radius, or no round was kept
        // and every panel says the method's targets stopped it.
        const rounds = r.sq.sq_mesh.mould_rounds;
        assert.ok(r.timings_ms.fewer_moulds > 0, 'timings_ms.fewer_moulds');
        assert.ok(rounds.length >= 1, `rounds ${JSON.stringify(rounds)}`);
        assert.ok(mo.count <= r.sq.sq_mesh.moulds_before, `moulds ${r.sq.sq_mesh.moulds_before} → ${mo.count}`);
        if (rounds.some((x) => x.kept)) {
          assert.equal(mo.snap.snapped, r.output.panels, `every panel snapped: ${JSON.stringify(mo.snap)}`);
        } else {
          assert.deepEqual(mo.snap.not_snapped.map((m) => [m.reason, m.panels]), [['method_targets', r.output.panels]]);
        }
        assert.equal(s.sq.mould_colours, Math.min(mo.count, 16), 'one panel mesh per mould colour');
        const m = r.sq.sq_mesh;
        const q = r.sq.quad_mesh;
        assert.ok(r.output.faces >= 150 && r.output.faces <= 330, `about 237 quads: ${r.output.faces}`);
        assert.equal(r.output.panels, r.output.faces, 'one panel per quad');
        assert.ok(m.max_vertex_sphere_residual <= 1e-8, `vertex–sphere residual ${m.max_vertex_sphere_residual}`);
        assert.ok(m.max_centre_face_planarity <= 1e-8, `centre-face planarity ${m.max_centre_face_planarity}`);
        assert.ok(m.max_torsal_plane_residual <= 1e-8, `torsal-plane residual ${m.max_torsal_plane_residual}`);
        assert.ok(m.max_axis_normal_angle_deg <= 20, `node axes within θ: ${m.max_axis_normal_angle_deg}`);
        assert.ok(m.min_torsal_plane_angle_deg >= 75, `support planes at ≥ α: ${m.min_torsal_plane_angle_deg}`);
        assert.ok(r.metrics.max_distance_to_reference < 0.01, `distance to the reference ${r.metrics.max_distance_to_reference}`);
        assert.ok(q.mean_edge_torsal_angle_deg <= 5, `edges along the torsal directions: ${q.mean_edge_torsal_angle_deg}`);
        assert.ok(q.coverage >= 0.9, `coverage ${q.coverage}`);
        for (const k of ['remesh', 'final_iteration_median', 'total']) {
          assert.ok(r.timings_ms[k] > 0, `timings_ms.${k}`);
        }
        assert.ok(s.sq.quad_mesh_edges > 0 && s.sq.panel_triangles > 0 && s.sq.support_triangles > 0 && s.sq.axes > 0, 'quad mesh, panels, support and axes shown');
        // The auto start: the SQ mesh from constant radii meets every guarantee, so the central
        // congruence never runs, and the constant one is taken as it is (no congruence iterations).
        const c = r.sq.congruence;
        assert.equal(c.start, 'constant');
        assert.deepEqual(c.attempts.map((a) => a.start), ['constant']);
        for (const step of ['fairing', 'warm_up', 'spheres', 'projection']) {
          assert.ok(s.sq.energy_steps.includes(step), `energies of ${step} plotted (${s.sq.energy_steps})`);
        }
        assert.ok(!s.sq.energy_steps.includes('line_congruence'), `no congruence iterations (${s.sq.energy_steps})`);
        for (const f of ['panels.glb', 'panels.obj', 'panels.csv', 'panels.json', 'moulds.csv', 'support.csv', 'mesh.obj', 'report.json', 'congruence.glb']) {
          assert.ok(s.downloads.includes(f), `${f} offered (${s.downloads})`);
        }
        assertDrawn(await measureViewport(app, s, 'sq-final'), 'panels, support and axes');
        const [download] = await Promise.all([
          app.page.waitForEvent('download', { timeout: 30_000 }),
          app.page.evaluate(() => window.dispatchEvent(new CustomEvent('sf-download', { detail: 'panels.glb' }))),
        ]);
        fs.mkdirSync(ARTIFACTS_DIR, { recursive: true });
        const file = path.join(ARTIFACTS_DIR, `${project.name}-sq-panels.glb`);
        await download.saveAs(file);
        const v = spawnSync(process.execPath, [path.join(E2E_DIR, 'validate-gltf.mjs'), file], { encoding: 'utf8' });
        assert.equal(v.status, 0, `the Khronos validator accepts the SQ panels GLB: ${v.stdout}${v.stderr}`);
        // The exact surfaces: OpenCascade reads one face per panel and support element.
        assert.ok(s.downloads.includes('panels.step'), `panels.step offered (${s.downloads})`);
        const [step] = await Promise.all([
          app.page.waitForEvent('download', { timeout: 30_000 }),
          app.page.evaluate(() => window.dispatchEvent(new CustomEvent('sf-download', { detail: 'panels.step' }))),
        ]);
        const stepFile = path.join(ARTIFACTS_DIR, `${project.name}-sq-panels.step`);
        await step.saveAs(stepFile);
        const read = spawnSync(process.execPath, [path.join(E2E_DIR, 'read-step.mjs'), stepFile, '--unit', 'm'], { encoding: 'utf8', maxBuffer: 1 << 28 });
        assert.equal(read.status, 0, `OpenCascade reads panels.step: ${read.stderr}`);
        const faces = JSON.parse(read.stdout).faces;
        assert.equal(faces.length, r.exact_surfaces.panels + r.exact_surfaces.support_elements, 'one face per exact surface');
        assert.equal(r.exact_surfaces.panels, r.output.panels, `every panel exact: ${JSON.stringify(r.exact_surfaces)}`);
        assert.ok(faces.every((f) => f.length >= 9), 'every face triangulated');
        // panels.3dm, written in the worker with rhino3dm: every object valid, one surface per panel.
        assert.ok(s.downloads.includes('panels.3dm') && !s.downloads.includes('panels.3dm.json'), `panels.3dm offered (${s.downloads})`);
        const [rhinoFile] = await Promise.all([
          app.page.waitForEvent('download', { timeout: 30_000 }),
          app.page.evaluate(() => window.dispatchEvent(new CustomEvent('sf-download', { detail: 'panels.3dm' }))),
        ]);
        const file3dm = path.join(ARTIFACTS_DIR, `${project.name}-sq-panels.3dm`);
        await rhinoFile.saveAs(file3dm);
        const read3dm = spawnSync(process.execPath, [path.join(E2E_DIR, 'read-3dm.mjs'), file3dm, '--grid', '2'], { encoding: 'utf8', maxBuffer: 1 << 28 });
        assert.equal(read3dm.status, 0, `rhino3dm reads panels.3dm: ${read3dm.stderr}`);
        const doc = JSON.parse(read3dm.stdout);
        assert.equal(doc.units, 'Meters');
        assert.ok(doc.objects.every((o) => o.valid), 'every object valid');
        assert.equal(doc.objects.filter((o) => o.layer.startsWith('panels::mould ')).length, r.output.panels, 'one surface per panel on its mould layer');
        assert.deepEqual(s.exact_surfaces, [r.exact_surfaces.panels, r.exact_surfaces.support_elements, 0], 'the downloads say what the CAD files hold');
        assert.deepEqual(app.pageErrors, [], 'uncaught page errors');
      });
    });

    test(`[${project.name}] n2. an SQ result that misses a guarantee says so in the status bar, with its figure`, { timeout: T.test }, async (t) => {
      const { server, browser } = await env();
      // Torsal planes at exactly 90° are more than a discrete mesh reaches.
      const fragment = 'v=1&sample=vault&method=sq&theta=20&alpha=90&grid=12&rs=10&faces=60&until=final';
      await withApp(t, browser, server, project, { name: 'n2-sq-miss', fragment }, async (app) => {
        const s = await waitForState(app, 'sq finished', (s) => s.sq && s.sq.ready && !s.busy, { timeout: T.load });
        const r = s.sq.report;
        t.diagnostic(`missed: ${s.missed_guarantees}; guarantees ${JSON.stringify(r.guarantees)}`);
        assert.equal(r.meets_guarantees, false);
        assert.ok(r.guarantees.some((g) => g.name === 'min_support_plane_angle_deg' && !g.holds), 'the missed guarantee in the report');
        assert.ok(s.missed_guarantees && s.missed_guarantees.includes('min_support_plane_angle_deg') && s.missed_guarantees.includes('≥ 90'), `status bar: ${s.missed_guarantees}`);
        // A missed result is never called exact (the guarantee `panels_without_exact_surface` may be named).
        assert.ok(!/\bexact\b/.test(s.missed_guarantees), 'no word of exactness');
        // The miss in a designer's words, at the top of the side panel and above the downloads,
        // which are marked as coming from a failed result.
        t.diagnostic(`in words: ${JSON.stringify(s.missed_in_words)}; side panel ${JSON.stringify(s.side_panel)}`);
        assert.ok(s.missed_in_words.some((w) => /^support planes meet at angles down to [\d.]+° \(must be at least 90°\)$/.test(w)), `${s.missed_in_words}`);
        assert.ok(s.missed_in_words.every((w) => !/_deg|_residual|NaN|\binf\b/.test(w)), `no code words or NaN: ${s.missed_in_words}`);
        assert.ok(!JSON.stringify(s).includes('NaN'), 'no NaN in the state');
        assert.equal(s.downloads_marked_failed, true, 'the downloads are marked as coming from a failed result');
        const [vx, vy, vw, vh] = s.side_panel.verdict;
        assert.ok(s.side_panel.downloads && vy < s.side_panel.downloads[1], `the verdict ${s.side_panel.verdict} is above the downloads ${s.side_panel.downloads}`);
        assert.ok(vy >= 0 && vy + vh <= 800, `the verdict is visible without scrolling: ${s.side_panel.verdict}`);
        const m = await measureViewport(app, s, 'sq-miss');
        assertDrawn(m, 'the failed result');
        const red = countPixels(m, ([r, g, b]) => r > 200 && g < 120 && b < 120, [vx, vy, vw, vh]);
        assert.ok(red > 50, `the verdict is drawn in red (${red} red pixels in ${s.side_panel.verdict})`);
        fs.mkdirSync(ARTIFACTS_DIR, { recursive: true });
        await app.page.screenshot({ path: path.join(ARTIFACTS_DIR, `${project.name}-n2-sq-miss.png`), timeout: 15_000 });
        assert.deepEqual(app.pageErrors, [], 'uncaught page errors');
      });
    });

    test(`[${project.name}] o. a dropped Rhino .3dm opens its first NURBS surface, lists its objects, and SQ runs on it`, { timeout: T.test }, async (t) => {
      const { server, browser } = await env();
      await withApp(t, browser, server, project, { name: 'o-3dm', fragment: 'v=1&sample=vault&method=sq&until=congruence' }, async (app) => {
        await waitForState(app, 'vault settled', (s) => s.source === 'sample:vault' && s.sq && !s.busy, { timeout: T.load });
        await dropFile(app, 'mixed.3dm', fs.readFileSync(MIXED_3DM), 'application/octet-stream');
        const s = await waitForState(app, 'the .3dm surface and its congruence', (s) => s.source.includes('mixed.3dm') && s.is_bspline && s.sq && s.sq.ready && !s.busy, { timeout: T.load });
        t.diagnostic(`source ${s.source}, objects ${JSON.stringify(s.file_objects)}, error ${s.error}`);
        assert.deepEqual(s.file_objects, ['grid_mesh', 'tunnel_arch', 'torus_patch']);
        assert.equal(s.file_object, 1, 'the first surface');
        assert.equal(s.error, null);
        assert.deepEqual(app.pageErrors, [], 'uncaught page errors');
      });
    });

    test(`[${project.name}] m. SQ's central start refuses a B-spline whose mean curvature changes sign and shows the sign of H`, { timeout: T.test }, async (t) => {
      const { server, browser } = await env();
      await withApp(t, browser, server, project, { name: 'm-sq-refusal', fragment: 'v=1&sample=vault&method=sq&start=central' }, async (app) => {
        await waitForState(app, 'vault settled', (s) => s.source === 'sample:vault' && s.sq && !s.busy, { timeout: T.load });
        await dropFile(app, 'saddle_sign_change.json', fs.readFileSync(SADDLE), 'application/json');
        const s = await waitForState(app, 'the refusal', (s) => s.source === 'file:saddle_sign_change.json' && s.sq && s.sq.refused && !s.busy, { timeout: T.load });
        t.diagnostic(`error: ${s.error}`);
        assert.match(String(s.error), /central start needs a mean curvature of one sign/);
        assert.match(String(s.error), /constant radii/);
        assert.equal(s.sq.ready, false);
        // The refusal offers the menu's other methods by their menu names, not the CLI's.
        assert.deepEqual(s.error_offers, ['ST, adapted face size (Sec. 3)', 'ST with support structure (Sec. 4)']);
        assert.ok(!/\b(st-support|--start)\b/.test(s.error), `no CLI words: ${s.error}`);
        const m = await measureViewport(app, s, 'sq-refused');
        assertDrawn(m, 'the surface coloured by the sign of H');
        // A robust diverging map: both signs show in colour, not washed out to white by peaks.
        const blue = countPixels(m, ([r, g, b]) => b > r + 60);
        const red = countPixels(m, ([r, g, b]) => r > b + 60);
        t.diagnostic(`H < 0 (blue) ${blue} px, H > 0 (red) ${red} px of ${m.drawn} drawn`);
        assert.ok(blue > 0.1 * m.drawn && red > 0.1 * m.drawn, `both signs of H show: blue ${blue}, red ${red} of ${m.drawn}`);
        assert.deepEqual(app.pageErrors, [], 'uncaught page errors');
      });
    });

    test(`[${project.name}] p. editing θ, α, δ and the mould count in the link of an open page reruns SQ with them`, { timeout: T.test }, async (t) => {
      const { server, browser } = await env();
      const base = 'v=1&sample=vault&method=sq&grid=12&rs=10&faces=60&until=final';
      await withApp(t, browser, server, project, { name: 'p-link-rerun', fragment: `${base}&theta=20&alpha=75` }, async (app) => {
        const limit = (s, name) => s.sq.report.guarantees.find((g) => g.name === name)?.limit;
        const done = (pred) => (s) => s.sq && s.sq.ready && !s.busy && s.sq.report && pred(s);
        let s = await waitForState(app, 'sq at θ 20, α 75', done((s) => limit(s, 'max_axis_normal_angle_deg') === 20), { timeout: T.load });
        assert.equal(limit(s, 'min_support_plane_angle_deg'), 75);
        const before = await measureViewport(app, s, 'theta20');
        await editLink(app, `${base}&theta=15&alpha=45`);
        s = await waitForState(app, 'sq rerun at θ 15, α 45', done((s) => limit(s, 'max_axis_normal_angle_deg') === 15 && limit(s, 'min_support_plane_angle_deg') === 45), { timeout: T.load });
        assert.ok(s.design_link.includes('theta=15') && s.design_link.includes('alpha=45'), s.design_link);
        const after = await measureViewport(app, s, 'theta15');
        t.diagnostic(`the view changed on ${(100 * changedFraction(before, after)).toFixed(1)} % of its pixels`);
        assert.ok(changedFraction(before, after) > 0.002, 'the view shows the new result');
        // δ: the moulds are grouped again within the new tolerance.
        await editLink(app, `${base}&theta=15&alpha=45&mould_tol=0.05`);
        s = await waitForState(app, 'moulds within δ 0.05', done((s) => s.moulds && Math.abs(s.moulds[1] - 0.05) < 1e-12), { timeout: T.load });
        const within = s.moulds[0];
        // K: at most K moulds.
        await editLink(app, `${base}&theta=15&alpha=45&moulds=2`);
        s = await waitForState(app, 'at most 2 moulds', done((s) => s.moulds && s.moulds[0] <= 2 && s.design_link.includes('moulds=2')), { timeout: T.load });
        t.diagnostic(`moulds: ${within} within δ 0.05, then ${JSON.stringify(s.moulds)} for K = 2`);
        assert.ok(s.moulds[0] >= 1 && s.moulds[0] <= 2);
        assert.deepEqual(app.pageErrors, [], 'uncaught page errors');
      });
    });

    test(`[${project.name}] q. an error belongs to its run: switching method after SQ refused a mesh clears it`, { timeout: T.test }, async (t) => {
      const { server, browser } = await env();
      await withApp(t, browser, server, project, { name: 'q-cleared-error', fragment: 'v=1&sample=dome&method=sq' }, async (app) => {
        let s = await waitForState(app, 'SQ refuses the dome mesh', (s) => /B-spline/.test(String(s.error)) && !s.busy && s.curvature_ready, { timeout: T.load });
        assert.deepEqual(s.error_offers, ['ST, adapted face size (Sec. 3)', 'ST with support structure (Sec. 4)'], 'the menu names of the other methods');
        const red = await measureViewport(app, s, 'sq-refused-mesh');
        const width = s.side_panel.width;
        await editLink(app, 'v=1&sample=dome&method=st-support');
        s = await waitForState(app, 'st-support done, no error', (s) => s.st_support && s.st_support.ready && !s.busy, { timeout: T.load });
        assert.equal(s.error, null, 'the refusal of the last run is gone');
        assert.deepEqual(s.error_offers, []);
        assert.ok(s.side_panel.verdict, 'the new verdict shows at the top');
        assert.equal(s.side_panel.width, width, 'the side panel keeps its width when results arrive');
        assertDrawn(await measureViewport(app, s, 'st-support-after-error'), 'the new result');
        t.diagnostic(`viewport before ${red.file}`);
        assert.deepEqual(app.pageErrors, [], 'uncaught page errors');
      });
    });

    test(`[${project.name}] r. a link naming a file keeps it, asks for the file in the view, and gives the same link back after the drop`, { timeout: T.test }, async (t) => {
      const { server, browser } = await env();
      const bytes = fs.readFileSync(TRI_DOME);
      let link;
      await withApp(t, browser, server, project, { name: 'r-file-link-1', fragment: 'v=1&sample=dome&method=curvature&jet_degree=2&color=k1' }, async (app) => {
        await settledDefault(app);
        await dropFile(app, 'tri_dome.obj', bytes, 'model/obj');
        const s = await waitForState(app, 'tri_dome.obj settled', (s) => s.source === 'file:tri_dome.obj' && isSettled(s));
        link = s.design_link;
      });
      t.diagnostic(`the design's link: ${link}`);
      assert.ok(link.includes('sample=file') && link.includes('file=tri_dome.obj') && link.includes('cam='), link);
      await withApp(t, browser, server, project, { name: 'r-file-link-2', fragment: link }, async (app) => {
        let s = await waitForState(app, 'the drop prompt', (s) => s.ready === true && s.awaiting_file === 'tri_dome.obj', { timeout: T.load });
        assert.equal(s.design_link, link, 'the link is kept as it was');
        assert.equal(s.error, null, 'no error while the file is awaited');
        assert.equal(s.source, '', 'nothing else is shown instead');
        const m = await measureViewport(app, s, 'drop-prompt');
        const text = countPixels(m, ([r, g, b]) => r > 200 && g > 200 && b > 200);
        assert.ok(text > 300, `the prompt is written in the view (${text} white pixels)`);
        await dropFile(app, 'tri_dome.obj', bytes, 'model/obj');
        s = await waitForState(app, 'tri_dome.obj settled', (s) => s.source === 'file:tri_dome.obj' && isSettled(s));
        assert.equal(s.awaiting_file, null);
        assert.equal(s.jet_degree, 2);
        assert.equal(s.color_by, 'k1');
        assert.ok(!s.notices.some((n) => /drop/i.test(n)), `no stale prompt among the notices: ${JSON.stringify(s.notices)}`);
        s = await waitForState(app, 'the same link back', (s) => s.design_link === link, { timeout: 15_000 }).catch(() => app.lastState);
        assert.equal(s.design_link, link, 'copying the link gives the same link back');
        assertDrawn(await measureViewport(app, s, 'file-link-dropped'), 'tri_dome.obj');
        assert.deepEqual(app.pageErrors, [], 'uncaught page errors');
      });
    });
  });
}
