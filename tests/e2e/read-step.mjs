#!/usr/bin/env node
// Reads a STEP file with OpenCascade (npm `occt-import-js`), an independent reader, and
// triangulates it.
//
//   node tests/e2e/read-step.mjs FILE.step --unit m|cm|mm|ft|in
//
// Prints one JSON object on stdout: {success, faces: [[x, y, z, ...], ...]}, the vertices of each
// B-rep face's triangulation, in the file's face order, in the given unit. Exits 1 when OpenCascade
// cannot read the file, 2 when the reader cannot run. Run `npm ci` in tests/e2e first.

import { readFile } from 'node:fs/promises';
import { createRequire } from 'node:module';

const args = process.argv.slice(2);
const file = args.find((a) => !a.startsWith('--') && a !== args[args.indexOf('--unit') + 1]);
const unitIdx = args.indexOf('--unit');
const unit = unitIdx >= 0 ? args[unitIdx + 1] : 'm';
const linearUnit = { m: 'meter', cm: 'centimeter', mm: 'millimeter', ft: 'foot', in: 'inch' }[unit];
if (!file || !linearUnit) {
  console.error('usage: node read-step.mjs FILE.step --unit m|cm|mm|ft|in');
  process.exit(2);
}

let occt;
try {
  const require = createRequire(import.meta.url);
  occt = await require('occt-import-js')();
} catch (e) {
  console.error(`occt-import-js is not installed: run \`npm ci\` in tests/e2e (${e.message})`);
  process.exit(2);
}

const bytes = new Uint8Array(await readFile(file));
const result = occt.ReadStepFile(bytes, { linearUnit, linearDeflectionType: 'bounding_box_ratio', linearDeflection: 0.001 });
if (!result.success) {
  console.log(JSON.stringify({ success: false, faces: [] }));
  process.exit(1);
}
const faces = [];
for (const mesh of result.meshes) {
  const pos = mesh.attributes.position.array;
  const idx = mesh.index.array;
  for (const f of mesh.brep_faces) {
    const used = new Set();
    for (let t = f.first; t <= f.last; t++) {
      for (let k = 0; k < 3; k++) used.add(idx[3 * t + k]);
    }
    faces.push([...used].flatMap((v) => [pos[3 * v], pos[3 * v + 1], pos[3 * v + 2]]));
  }
}
console.log(JSON.stringify({ success: true, faces }));
