#!/usr/bin/env node
// node www/rhino3dm/cli.mjs FILE.3dm [--list] [--object K] [--out OUT] [--timeout SECONDS]
//
//   --list        one JSON object per line on stdout: {"index","kind","name","summary","units"}
//                 (units: the file's model unit system by its Rhino name, or null)
//   --object K    the object to write: its index from --list, or its name; default: the first
//                 surface, else the first mesh
//   --out OUT     write there instead of stdout (B-spline JSON for a surface, OBJ for a mesh)
//   --timeout S   give up after S seconds (default 60): openNURBS can take long on damaged files
//
// Notes (skipped objects, ignored trims, …) go to stderr as "note: …". Errors: a message on
// stderr, exit status 2. rhino3dm.js is loaded from node_modules beside this file (`npm ci`).

import { Worker, isMainThread, parentPort, workerData } from 'node:worker_threads';
import { existsSync, readFileSync, writeFileSync } from 'node:fs';

const RHINO = new URL('./node_modules/rhino3dm/rhino3dm.module.js', import.meta.url);
const USAGE = 'usage: node www/rhino3dm/cli.mjs FILE.3dm [--list] [--object K] [--out OUT] [--timeout SECONDS]';

if (isMainThread) {
  main().then(
    (code) => {
      process.exitCode = code;
    },
    (e) => fail(e?.message ?? String(e)),
  );
} else {
  // The conversion runs in a worker so that the main thread can stop it after --timeout.
  (async () => {
    try {
      const { read3dm } = await import('./convert.mjs');
      const rhino = await (await import(RHINO.href)).default();
      const out = await read3dm(workerData.bytes, rhino);
      parentPort.postMessage({ ok: true, out });
    } catch (e) {
      parentPort.postMessage({ ok: false, message: e?.message ?? String(e) });
    }
  })();
}

function fail(message) {
  process.stderr.write(`${String(message).split('\n')[0].slice(0, 2000)}\n`);
  process.exitCode = 2;
  return 2;
}

function parseArgs(argv) {
  const opts = { file: null, list: false, object: null, out: null, timeout: 60 };
  for (let i = 0; i < argv.length; i++) {
    const a = argv[i];
    const value = () => {
      if (i + 1 >= argv.length) throw new Error(`${a} needs a value\n${USAGE}`);
      return argv[++i];
    };
    if (a === '--list') opts.list = true;
    else if (a === '--object') opts.object = value();
    else if (a === '--out' || a === '-o') opts.out = value();
    else if (a === '--timeout') {
      opts.timeout = Number(value());
      if (!(opts.timeout > 0)) throw new Error(`--timeout must be a positive number of seconds\n${USAGE}`);
    } else if (a === '--help' || a === '-h') opts.help = true;
    else if (a.startsWith('-') && a !== '-') throw new Error(`unknown option ${a}\n${USAGE}`);
    else if (opts.file === null) opts.file = a;
    else throw new Error(`more than one input file\n${USAGE}`);
  }
  return opts;
}

async function main() {
  let opts;
  try {
    opts = parseArgs(process.argv.slice(2));
  } catch (e) {
    return fail(e.message.replace(`\n${USAGE}`, ` (${USAGE})`));
  }
  if (opts.help) {
    process.stdout.write(`${USAGE}\n`);
    return 0;
  }
  if (!opts.file) return fail(USAGE);
  if (!existsSync(RHINO)) return fail('rhino3dm.js is not installed: run `npm ci` in www/rhino3dm');

  let bytes;
  try {
    bytes = readFileSync(opts.file);
  } catch (e) {
    return fail(`cannot read ${opts.file}: ${e.code === 'ENOENT' ? 'no such file' : e.message}`);
  }

  let result;
  try {
    result = await convertInWorker(new Uint8Array(bytes), opts.timeout);
  } catch (e) {
    return fail(`${opts.file}: ${e.message}`);
  }
  for (const note of result.notes) process.stderr.write(`note: ${note}\n`);

  const { objects } = result;
  if (opts.list) {
    const units = result.units ?? null;
    const lines = objects.map(({ index, kind, name, summary }) => JSON.stringify({ index, kind, name, summary, units }));
    process.stdout.write(`${lines.join('\n')}\n`);
    return 0;
  }

  let chosen;
  if (opts.object === null) {
    chosen = objects.find((o) => o.kind === 'surface') ?? objects.find((o) => o.kind === 'mesh');
  } else if (/^\d+$/.test(opts.object)) {
    chosen = objects[Number(opts.object)];
    if (!chosen) return fail(`${opts.file}: no object ${opts.object}; the file has objects 0 to ${objects.length - 1} (see --list)`);
  } else {
    const named = objects.filter((o) => o.name === opts.object);
    if (named.length !== 1) {
      return fail(`${opts.file}: ${named.length ? `${named.length} objects are` : 'no object is'} named "${opts.object}" (see --list)`);
    }
    chosen = named[0];
  }

  if (opts.out && opts.out !== '-') {
    try {
      writeFileSync(opts.out, chosen.text);
    } catch (e) {
      return fail(`cannot write ${opts.out}: ${e.message}`);
    }
    process.stderr.write(`wrote ${opts.out}: object ${chosen.index} "${chosen.name}", ${chosen.summary}\n`);
  } else {
    process.stdout.write(chosen.text.endsWith('\n') ? chosen.text : `${chosen.text}\n`);
  }
  return 0;
}

function convertInWorker(bytes, timeoutSeconds) {
  return new Promise((resolve, reject) => {
    const worker = new Worker(new URL(import.meta.url), { workerData: { bytes }, stdout: true, stderr: true });
    let done = false;
    const finish = (fn, arg) => {
      if (done) return;
      done = true;
      clearTimeout(timer);
      worker.terminate().finally(() => fn(arg));
    };
    const timer = setTimeout(
      () => finish(reject, new Error(`not a readable Rhino .3dm file: openNURBS did not finish within ${timeoutSeconds} s (damaged file?)`)),
      timeoutSeconds * 1000,
    );
    worker.on('message', (m) => (m.ok ? finish(resolve, m.out) : finish(reject, new Error(m.message))));
    worker.on('error', (e) => finish(reject, new Error(`rhino3dm failed: ${e?.message ?? e}`)));
    worker.on('exit', (code) => finish(reject, new Error(`rhino3dm stopped (exit code ${code}) without an answer`)));
  });
}
