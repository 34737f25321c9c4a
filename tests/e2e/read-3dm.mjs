#!/usr/bin/env node
// Reads a .3dm file back with rhino3dm (openNURBS in WebAssembly, from www/rhino3dm/node_modules).
//
//   node tests/e2e/read-3dm.mjs FILE.3dm [--grid N]
//
// Prints one JSON object on stdout: {units (Rhino's name: Meters, …), layers: [fullPath], objects: [{name, layer, kind,
// valid, user_text, grid?, sides?}]}: a surface's points on an (N+1)² grid over its domain and on
// each of its four sides (N+1 points each), a curve's N+1 points. Exits 2 when rhino3dm cannot run
// or the file cannot be read.

import { readFileSync } from 'node:fs';

const args = process.argv.slice(2);
const file = args.find((a, i) => !a.startsWith('--') && args[i - 1] !== '--grid');
const gi = args.indexOf('--grid');
const n = gi >= 0 ? Number(args[gi + 1]) : 20;
let rhino;
try {
  rhino = await (await import(new URL('../../www/rhino3dm/node_modules/rhino3dm/rhino3dm.module.js', import.meta.url).href)).default();
} catch (e) {
  console.error(`rhino3dm is not installed: run \`npm ci\` in www/rhino3dm (${e.message})`);
  process.exit(2);
}
const doc = rhino.File3dm.fromByteArray(new Uint8Array(readFileSync(file)));
if (!doc) {
  console.error(`${file}: rhino3dm cannot read it`);
  process.exit(2);
}
const layers = [];
const layerTable = doc.layers();
for (let i = 0; i < layerTable.count; i++) {
  const layer = layerTable.get(i);
  layers.push(layer.fullPath);
  layer.delete();
}
const objects = [];
const table = doc.objects();
for (let i = 0; i < table.count; i++) {
  const o = table.get(i);
  const g = o.geometry();
  const a = o.attributes();
  const item = { name: a.name, layer: layers[a.layerIndex], kind: g.constructor.name, valid: g.isValid, user_text: Object.fromEntries(a.getUserStrings()) };
  if (g instanceof rhino.NurbsSurface) {
    const [u0, u1] = g.domain(0);
    const [v0, v1] = g.domain(1);
    const at = (s, t) => g.pointAt(u0 + s * (u1 - u0), v0 + t * (v1 - v0));
    item.grid = [];
    for (let i2 = 0; i2 <= n; i2++) for (let j = 0; j <= n; j++) item.grid.push(at(i2 / n, j / n));
    const line = (f) => Array.from({ length: n + 1 }, (_, k) => f(k / n));
    item.sides = [line((t) => at(t, 0)), line((t) => at(1, t)), line((t) => at(1 - t, 1)), line((t) => at(0, 1 - t))];
  } else if (g instanceof rhino.NurbsCurve) {
    const [t0, t1] = g.domain;
    item.points = Array.from({ length: n + 1 }, (_, k) => g.pointAt(t0 + (k / n) * (t1 - t0)));
  }
  objects.push(item);
  // Each wrapper holds openNURBS memory in the wasm heap until deleted: a file of many thousand
  // objects runs out of it otherwise (get() then answers null).
  for (const w of [a, g, o]) w.delete();
}
const unitValue = doc.settings().modelUnitSystem.value;
const units = Object.keys(rhino.UnitSystem).find((k) => rhino.UnitSystem[k]?.value === unitValue) ?? null;
console.log(JSON.stringify({ units, layers, objects }));
