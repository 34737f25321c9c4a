#!/usr/bin/env node
// node www/rhino3dm/write-cli.mjs MODEL.json OUT.3dm
//
// Writes the Rhino .3dm file of a Spherical Faces CAD model (the JSON of src/export/rhino.rs, see
// write.mjs) with rhino3dm.js from node_modules beside this file (`npm ci`). Prints one line
// on stdout: {"objects": N, "bytes": B}. Errors: a message on stderr, exit status 2.

import { existsSync, readFileSync, writeFileSync } from 'node:fs';
import { write3dm } from './write.mjs';

const RHINO = new URL('./node_modules/rhino3dm/rhino3dm.module.js', import.meta.url);
const [input, out] = process.argv.slice(2);

function fail(message) {
  process.stderr.write(`${String(message).split('\n')[0].slice(0, 2000)}\n`);
  process.exit(2);
}

if (!input || !out) fail('usage: node www/rhino3dm/write-cli.mjs MODEL.json OUT.3dm');
if (!existsSync(RHINO)) fail('rhino3dm.js is not installed: run `npm ci` in www/rhino3dm');
let model;
try {
  model = JSON.parse(readFileSync(input, 'utf8'));
} catch (e) {
  fail(`cannot read ${input}: ${e.message}`);
}
try {
  const rhino = await (await import(RHINO.href)).default();
  const bytes = write3dm(model, rhino);
  writeFileSync(out, bytes);
  const objects = ['surfaces', 'curves', 'lines', 'points', 'spheres'].reduce((n, k) => n + (model[k]?.length ?? 0), 0);
  process.stdout.write(`${JSON.stringify({ objects, bytes: bytes.length })}\n`);
} catch (e) {
  fail(`${out}: ${e?.message ?? e}`);
}
