// node --test (in www/rhino3dm, after `npm ci`): the .3dm converter against the JSON sources.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFileSync, existsSync, mkdtempSync, copyFileSync, rmSync } from 'node:fs';
import { execFileSync, spawnSync } from 'node:child_process';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { fileURLToPath } from 'node:url';

import rhino3dm from 'rhino3dm';
import { read3dm, loadRhino, RHINO_BROWSER_FILES } from './convert.mjs';

const HERE = fileURLToPath(new URL('.', import.meta.url));
const DATA = join(HERE, '..', '..', 'tests', 'data', '3dm');
const SOURCES = process.env.BSPLINE_DIR ?? join(HERE, '..', '..', '..', 'shared', 'data', 'bsplines');
const NAMES = ['tunnel_arch', 'paraboloid_dome', 'torus_patch', 'cylinder_patch'];

const rhino = await rhino3dm();
const file = (name) => readFileSync(join(DATA, `${name}.3dm`));

/** Our JSON in the openNURBS knot form (a textbook source loses its first and last knot). */
function normalized(json) {
  const points = json.controlPoints.length / 4;
  const open = (len, p) => len - p + 1;
  const book = (len, p) => len - p - 1;
  for (const [fu, fv] of [[open, open], [book, book], [open, book], [book, open]]) {
    const nu = fu(json.knotsU.length, json.degreeU);
    const nv = fv(json.knotsV.length, json.degreeV);
    if (nu > 0 && nv > 0 && nu * nv === points) {
      return {
        ...json,
        knotsU: fu === open ? json.knotsU : json.knotsU.slice(1, -1),
        knotsV: fv === open ? json.knotsV : json.knotsV.slice(1, -1),
      };
    }
  }
  throw new Error('source JSON: knots do not match the control points');
}

function assertSameSurface(got, want, label) {
  assert.equal(got.degreeU, want.degreeU, `${label}: degreeU`);
  assert.equal(got.degreeV, want.degreeV, `${label}: degreeV`);
  assert.deepEqual(Object.keys(got).sort(), ['controlPoints', 'degreeU', 'degreeV', 'knotsU', 'knotsV'], `${label}: keys`);
  for (const key of ['knotsU', 'knotsV']) {
    assert.equal(got[key].length, want[key].length, `${label}: ${key} length`);
    const scale = Math.max(...want[key].map(Math.abs), 1e-300);
    got[key].forEach((t, i) => assert.ok(Math.abs(t - want[key][i]) <= 1e-12 * scale, `${label}: ${key}[${i}] ${t} vs ${want[key][i]}`));
  }
  assert.equal(got.controlPoints.length, want.controlPoints.length, `${label}: control point count`);
  const lo = [Infinity, Infinity, Infinity];
  const hi = [-Infinity, -Infinity, -Infinity];
  for (let k = 0; k < want.controlPoints.length; k += 4) {
    for (let c = 0; c < 3; c++) {
      lo[c] = Math.min(lo[c], want.controlPoints[k + c]);
      hi[c] = Math.max(hi[c], want.controlPoints[k + c]);
    }
  }
  const diag = Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
  for (let k = 0; k < want.controlPoints.length; k++) {
    const tol = k % 4 === 3 ? 1e-12 * Math.abs(want.controlPoints[k]) : 1e-12 * diag;
    assert.ok(Math.abs(got.controlPoints[k] - want.controlPoints[k]) <= tol, `${label}: controlPoints[${k}] ${got.controlPoints[k]} vs ${want.controlPoints[k]}`);
  }
}

for (const name of NAMES) {
  test(`${name}.3dm converts back to ${name}.json`, async (t) => {
    const source = join(SOURCES, `${name}.json`);
    if (!existsSync(source)) return t.skip(`no ${source} (set BSPLINE_DIR)`);
    const want = normalized(JSON.parse(readFileSync(source, 'utf8')));
    const { objects, notes } = await read3dm(file(name), rhino);
    assert.equal(objects.length, 1, JSON.stringify(notes));
    const [o] = objects;
    assert.equal(o.index, 0);
    assert.equal(o.kind, 'surface');
    assert.equal(o.name, name);
    assert.match(o.summary, new RegExp(`degree ${want.degreeU}×${want.degreeV}`));
    assertSameSurface(JSON.parse(o.text), want, name);
  });
}

test('mixed.3dm: two named surfaces and a quad mesh; the line is skipped with a note', async (t) => {
  const { objects, notes } = await read3dm(file('mixed'), rhino);
  assert.deepEqual(
    objects.map((o) => [o.index, o.kind, o.name]),
    [
      [0, 'mesh', 'grid_mesh'],
      [1, 'surface', 'tunnel_arch'],
      [2, 'surface', 'torus_patch'],
    ],
  );
  assert.ok(notes.some((n) => /skipped.*1 LineCurve/.test(n)), notes.join('; '));
  const obj = objects[0].text;
  const v = obj.split('\n').filter((l) => l.startsWith('v '));
  const f = obj.split('\n').filter((l) => l.startsWith('f '));
  assert.equal(v.length, 9);
  assert.equal(f.length, 4);
  for (const line of f) {
    const idx = line.split(/\s+/).slice(1).map(Number);
    assert.equal(idx.length, 4, line);
    assert.equal(new Set(idx).size, 4, line);
    assert.ok(idx.every((i) => i >= 1 && i <= 9), line);
  }
  assert.ok(v.includes('v 2 2 0.25'), v.join('|'));
  for (const name of ['tunnel_arch', 'torus_patch']) {
    const source = join(SOURCES, `${name}.json`);
    if (!existsSync(source)) continue;
    const got = JSON.parse(objects.find((o) => o.name === name).text);
    assertSameSurface(got, normalized(JSON.parse(readFileSync(source, 'utf8'))), `mixed/${name}`);
  }
  void t;
});

test('garbage, empty and truncated bytes give the clear error quickly', async () => {
  const bad = [
    new Uint8Array(0),
    new TextEncoder().encode('{"degreeU": 3}'),
    new TextEncoder().encode('hello, this is not a 3dm file at all '.repeat(200)),
    Uint8Array.from({ length: 5000 }, (_, i) => (i * 7919) % 256),
  ];
  const good = new Uint8Array(file('mixed'));
  for (const cut of [40, 500, 2000, Math.floor(good.length / 2), good.length - 1]) bad.push(good.slice(0, cut));
  const junk = good.slice();
  junk.fill(0xab, 32); // the header of a .3dm, then rubbish
  bad.push(junk);
  const damaged = good.slice();
  damaged[1101] = 59; // a record length in the settings table (took openNURBS ~30 s)
  bad.push(damaged);
  for (const bytes of bad) {
    const t0 = performance.now();
    await assert.rejects(read3dm(bytes, rhino), /^Error: not a readable Rhino \.3dm file: /);
    assert.ok(performance.now() - t0 < 5000, `took ${performance.now() - t0} ms`);
  }
  await assert.rejects(read3dm(file('mixed'), {}), /initialized rhino3dm module/);
});

test('a file with only a line: "no NURBS surface or mesh" naming what it holds', async () => {
  const doc = new rhino.File3dm();
  doc.objects().addLine([0, 0, 0], [1, 1, 1]);
  doc.objects().addPointXYZ(1, 2, 3);
  const bytes = doc.toByteArray();
  doc.delete();
  await assert.rejects(read3dm(bytes, rhino), /^Error: no NURBS surface or mesh in this \.3dm file; it holds: .*LineCurve.*Point/);
});

test('breps (trimmed faces noted), extrusions, other surfaces and triangles', async () => {
  const doc = new rhino.File3dm();
  const cylinder = new rhino.Cylinder(new rhino.Circle(2), 5);
  const attrs = new rhino.ObjectAttributes();
  attrs.name = 'capped';
  doc.objects().addBrep(rhino.Brep.createFromCylinder(cylinder, true, true), attrs);
  doc.objects().add(rhino.Extrusion.createCylinderExtrusion(cylinder, false, false), null);
  doc.objects().addSphere(new rhino.Sphere([0, 0, 0], 3), null);
  const mesh = new rhino.Mesh();
  mesh.vertices().add(0.1, 0.2, 0.3);
  mesh.vertices().add(1, 0, 0);
  mesh.vertices().add(0, 1, 0);
  mesh.vertices().add(1, 1, 0);
  mesh.faces().addTriFace(0, 1, 2);
  mesh.faces().addQuadFace(1, 3, 2, 0);
  doc.objects().addMesh(mesh, null);
  const bytes = doc.toByteArray();
  doc.delete();

  const { objects, notes } = await read3dm(bytes, rhino);
  const kinds = objects.map((o) => `${o.kind}:${o.name}`);
  assert.deepEqual(kinds.slice(0, 3), ['surface:capped face 0', 'surface:capped face 1', 'surface:capped face 2'], kinds.join(', '));
  assert.ok(notes.some((n) => /trims ignored: "capped face 1", "capped face 2" are trimmed faces/.test(n)), notes.join('; '));
  assert.ok(kinds.includes('surface:Extrusion 1'), kinds.join(', '));
  assert.ok(objects.filter((o) => o.kind === 'surface').length >= 5, kinds.join(', '));
  const side = JSON.parse(objects[0].text);
  assert.equal(side.controlPoints.length / 4, ((side.knotsU.length - side.degreeU + 1) * (side.knotsV.length - side.degreeV + 1)));
  // The rational circle of the cylinder: corner weights 1 and 1/sqrt(2) in between, and every
  // Euclidean control point at radius 2 or 2*sqrt(2).
  const ws = new Set(side.controlPoints.filter((_, k) => k % 4 === 3).map((w) => w.toFixed(12)));
  assert.deepEqual([...ws].sort(), [Math.SQRT1_2.toFixed(12), '1.000000000000']);
  for (let k = 0; k < side.controlPoints.length; k += 4) {
    const r = Math.hypot(side.controlPoints[k], side.controlPoints[k + 1]);
    assert.ok(Math.abs(r - 2) < 1e-12 || Math.abs(r - 2 * Math.SQRT2) < 1e-12, `radius ${r}`);
  }
  const m = objects.find((o) => o.kind === 'mesh');
  assert.ok(m, kinds.join(', '));
  assert.match(m.summary, /4 vertices, 2 faces \(1 quads, 1 triangles\)/);
  assert.match(m.text, /\nv 0\.1 0\.2 0\.3\n/);
  assert.match(m.text, /\nf 1 2 3\nf 2 4 3 1\n/);
});

test('the browser files exist in the package', () => {
  for (const f of RHINO_BROWSER_FILES) assert.ok(existsSync(join(HERE, 'node_modules', 'rhino3dm', f)), f);
});

test('loadRhino initializes the module from a folder URL', async () => {
  const r = await loadRhino(new URL('./node_modules/rhino3dm/', import.meta.url).href);
  const { objects } = await read3dm(file('torus_patch'), r);
  assert.equal(objects[0].name, 'torus_patch');
  await assert.rejects(loadRhino(new URL('./no-such-folder/', import.meta.url).href), /could not load rhino3dm\.js/);
});

test('cli.mjs: --list, default object, --object, --out, errors', () => {
  const cli = join(HERE, 'cli.mjs');
  const run = (...args) => spawnSync(process.execPath, [cli, ...args], { encoding: 'utf8' });
  const list = run(join(DATA, 'mixed.3dm'), '--list');
  assert.equal(list.status, 0, list.stderr);
  const rows = list.stdout.trim().split('\n').map((l) => JSON.parse(l));
  assert.deepEqual(rows.map((r) => [r.index, r.kind, r.name]), [[0, 'mesh', 'grid_mesh'], [1, 'surface', 'tunnel_arch'], [2, 'surface', 'torus_patch']]);
  assert.deepEqual(Object.keys(rows[0]), ['index', 'kind', 'name', 'summary', 'units']);
  assert.ok(rows.every((r) => r.units === rows[0].units), 'one unit system per file');
  assert.match(list.stderr, /note: .*LineCurve/);

  const first = JSON.parse(execFileSync(process.execPath, [cli, join(DATA, 'mixed.3dm')], { encoding: 'utf8', stdio: ['ignore', 'pipe', 'ignore'] }));
  assert.equal(first.degreeU, 5); // tunnel_arch, the first surface (the mesh comes first in the file)
  const mesh = run(join(DATA, 'mixed.3dm'), '--object', '0');
  assert.equal(mesh.status, 0, mesh.stderr);
  assert.equal(mesh.stdout.split('\n').filter((l) => l.startsWith('f ')).length, 4);
  const tmp = mkdtempSync(join(tmpdir(), 'rhino3dm-cli-'));
  try {
    const out = join(tmp, 'torus.json');
    const byName = run(join(DATA, 'mixed.3dm'), '--object', 'torus_patch', '--out', out);
    assert.equal(byName.status, 0, byName.stderr);
    assert.equal(JSON.parse(readFileSync(out, 'utf8')).degreeU, 2);

    for (const [args, message] of [
      [[join(DATA, 'mixed.3dm'), '--object', '7'], /no object 7/],
      [[join(HERE, 'package.json')], /not a readable Rhino \.3dm file/],
      [[join(tmp, 'missing.3dm')], /cannot read/],
      [[], /usage/],
    ]) {
      const r = run(...args);
      assert.equal(r.status, 2, `${args}: ${r.stderr}`);
      assert.match(r.stderr, message);
      assert.equal(r.stdout, '');
    }
    // Without node_modules beside it: exit 2 and say what to run.
    copyFileSync(cli, join(tmp, 'cli.mjs'));
    copyFileSync(join(HERE, 'convert.mjs'), join(tmp, 'convert.mjs'));
    const bare = spawnSync(process.execPath, [join(tmp, 'cli.mjs'), join(DATA, 'mixed.3dm')], { encoding: 'utf8' });
    assert.equal(bare.status, 2);
    assert.match(bare.stderr, /run `npm ci` in www\/rhino3dm/);
  } finally {
    rmSync(tmp, { recursive: true, force: true });
  }
});
