#!/usr/bin/env node
// Validates a .glb / .gltf file with the Khronos glTF validator (npm `gltf-validator`).
//
//   node tests/e2e/validate-gltf.mjs FILE [--max-issues N]
//
// Prints one JSON object on stdout: the validator version, the issue counts (numErrors,
// numWarnings, numInfos, numHints), every message (code, severity, pointer, message) up to the
// limit, and some asset info (draw calls, primitive count). Exits 1 when the validator reports an
// error, 2 when the file cannot be read or the validator cannot run, 0 otherwise.
// Run `npm ci` in tests/e2e first.

import { readFile } from 'node:fs/promises';
import { basename } from 'node:path';

const args = process.argv.slice(2);
const file = args.find((a) => !a.startsWith('--'));
const maxIdx = args.indexOf('--max-issues');
const maxIssues = maxIdx >= 0 ? Number(args[maxIdx + 1]) : 200;
if (!file) {
  console.error('usage: node validate-gltf.mjs FILE.glb [--max-issues N]');
  process.exit(2);
}

let validator;
try {
  validator = await import('gltf-validator');
} catch (e) {
  console.error(`gltf-validator is not installed: run \`npm ci\` in tests/e2e (${e.message})`);
  process.exit(2);
}

let bytes;
try {
  bytes = new Uint8Array(await readFile(file));
} catch (e) {
  console.error(`cannot read ${file}: ${e.message}`);
  process.exit(2);
}

let report;
try {
  report = await validator.validateBytes(bytes, { uri: basename(file), maxIssues });
} catch (e) {
  console.error(`validator failed on ${file}: ${e}`);
  process.exit(2);
}

const issues = report.issues ?? {};
const info = report.info ?? {};
const summary = {
  file,
  validator: report.validatorVersion,
  numErrors: issues.numErrors ?? 0,
  numWarnings: issues.numWarnings ?? 0,
  numInfos: issues.numInfos ?? 0,
  numHints: issues.numHints ?? 0,
  truncated: issues.truncated ?? false,
  messages: (issues.messages ?? []).map(({ code, severity, pointer, message }) => ({
    code,
    severity: ['error', 'warning', 'info', 'hint'][severity] ?? severity,
    pointer,
    message,
  })),
  info: {
    version: info.version,
    generator: info.generator,
    drawCallCount: info.drawCallCount,
    totalVertexCount: info.totalVertexCount,
    totalTriangleCount: info.totalTriangleCount,
    primitivesCount: info.primitivesCount,
  },
};
console.log(JSON.stringify(summary, null, 2));
process.exit(summary.numErrors > 0 ? 1 : 0);
