// node --test write.test.mjs: the .3dm writer (write.mjs) on a small model, read back by rhino3dm.
import assert from 'node:assert/strict';
import { test } from 'node:test';
import { FILE_VERSION, write3dm } from './write.mjs';

const rhino = await (await import(new URL('./node_modules/rhino3dm/rhino3dm.module.js', import.meta.url).href)).default();
const w = Math.SQRT1_2;

test('a rational quarter cylinder, an arc, a line, a point and a sphere read back exactly, on their layers', () => {
  const model = {
    units: 'ft',
    layers: [{ name: 'panels', parent: null, color: [190, 190, 190] }, { name: 'mould 0', parent: 0, color: [230, 80, 70] }, { name: 'reference', parent: null, color: [0, 0, 0] }],
    surfaces: [{ layer: 1, name: 'panel 0', degree: [2, 1], points: [[1, 0, 0], [1, 0, 1], [1, 1, 0], [1, 1, 1], [0, 1, 0], [0, 1, 1]], weights: [1, 1, w, w, 1, 1], user_text: { id: 0, mould: 0 } }],
    curves: [{ layer: 2, name: 'arc', points: [[1, 0, 0], [1, 1, 0], [0, 1, 0]], weights: [1, w, 1] }],
    lines: [{ layer: 2, name: 'axis', from: [0, 0, 0], to: [0, 0, 1] }],
    points: [{ layer: 2, name: 'm', at: [0, 0, 0] }],
    spheres: [{ layer: 2, name: 'Ω', center: [0, 0, 0], radius: 2 }],
  };
  const doc = rhino.File3dm.fromByteArray(write3dm(model, rhino));
  assert.equal(Math.floor(doc.archiveVersion / 10), FILE_VERSION, `a Rhino ${FILE_VERSION} file (archive version ${doc.archiveVersion})`);
  assert.equal(doc.settings().modelUnitSystem.value, rhino.UnitSystem.Feet.value);
  assert.equal(doc.objects().count, 5);
  const byName = {};
  for (let i = 0; i < doc.objects().count; i++) byName[doc.objects().get(i).attributes().name] = doc.objects().get(i);
  const panel = byName['panel 0'];
  assert.equal(doc.layers().get(panel.attributes().layerIndex).fullPath, 'panels::mould 0');
  assert.equal(panel.attributes().getUserString('mould'), '0');
  const s = panel.geometry();
  assert.ok(s.isValid);
  for (const [u, v] of [[0.1, 0.2], [0.5, 0.5], [0.93, 0.7]]) {
    const p = s.pointAt(u, v);
    assert.ok(Math.abs(Math.hypot(p[0], p[1]) - 1) < 1e-15, `on the cylinder: ${p}`);
  }
  const m = byName.arc.geometry().pointAt(0.5);
  assert.ok(Math.abs(m[0] - w) < 1e-15 && Math.abs(m[1] - w) < 1e-15);
  assert.ok(Object.values(byName).every((o) => o.geometry().isValid));
});

test('an unknown unit is refused', () => {
  assert.throws(() => write3dm({ units: 'furlong' }, rhino), /unknown unit/);
});
