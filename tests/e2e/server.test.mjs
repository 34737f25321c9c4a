// www/serve.py, no browser and no wasm build needed: it serves a temp dir with a dummy build.
import assert from 'node:assert/strict';
import { spawn } from 'node:child_process';
import fs from 'node:fs';
import http from 'node:http';
import net from 'node:net';
import os from 'node:os';
import path from 'node:path';
import { after, before, describe, test } from 'node:test';
import { SERVE_PY, startServer } from './helpers.mjs';

const SECRET = 'SECRET-MARKER-must-never-be-served';
const WASM = Buffer.from([0x00, 0x61, 0x73, 0x6d, 0x01, 0x00, 0x00, 0x00]);

let tmp; // tmp/Cargo.toml (secret), tmp/outside.txt (secret), tmp/root/ (served)
let root;

function makeTree() {
  tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'sf-serve-test-'));
  root = path.join(tmp, 'root');
  fs.mkdirSync(path.join(root, 'pkg'), { recursive: true });
  fs.mkdirSync(path.join(root, 'assets'), { recursive: true });
  fs.writeFileSync(path.join(tmp, 'Cargo.toml'), `[package]\nname = "${SECRET}"\n`);
  fs.writeFileSync(path.join(tmp, 'outside.txt'), SECRET);
  fs.writeFileSync(path.join(root, 'index.html'), '<!doctype html><title>dummy</title><canvas id="sf-canvas"></canvas>');
  fs.writeFileSync(path.join(root, 'pkg', 'spherical_faces_bg.wasm'), WASM);
  fs.writeFileSync(path.join(root, 'pkg', 'spherical_faces.js'), 'export default function init() {}\n');
  const files = {
    'worker.mjs': 'export {};\n',
    'style.css': 'body{}\n',
    'data.json': '{}\n',
    'm.glb': 'glTF',
    'm.gltf': '{}',
    'm.obj': 'v 0 0 0\n',
    'i.png': '\x89PNG',
    'i.svg': '<svg xmlns="http://www.w3.org/2000/svg"/>',
  };
  for (const [name, body] of Object.entries(files)) fs.writeFileSync(path.join(root, 'assets', name), body);
  fs.symlinkSync(path.join(tmp, 'outside.txt'), path.join(root, 'link-out.txt'));
  fs.symlinkSync(tmp, path.join(root, 'dir-out'));
  fs.symlinkSync(path.join(root, 'pkg'), path.join(root, 'pkg-link')); // inside: allowed
}

function request(url, { method = 'GET' } = {}) {
  return new Promise((resolve, reject) => {
    const req = http.request(url, { method, agent: false }, (res) => {
      const chunks = [];
      res.on('data', (c) => chunks.push(c));
      res.on('end', () => resolve({ status: res.statusCode, headers: res.headers, body: Buffer.concat(chunks) }));
    });
    req.on('error', reject);
    req.setTimeout(5000, () => req.destroy(new Error(`timeout: ${method} ${url}`)));
    req.end();
  });
}

/** Sends a request line byte-for-byte (no client-side path normalisation) and returns the raw response. */
function rawRequest(port, target) {
  return new Promise((resolve, reject) => {
    const sock = net.connect({ host: '127.0.0.1', port });
    const chunks = [];
    sock.setTimeout(5000, () => sock.destroy(new Error(`timeout: GET ${target}`)));
    sock.on('connect', () => sock.write(`GET ${target} HTTP/1.1\r\nHost: 127.0.0.1:${port}\r\nConnection: close\r\n\r\n`));
    sock.on('data', (c) => chunks.push(c));
    sock.on('end', () => {
      const text = Buffer.concat(chunks).toString('latin1');
      const status = Number((text.match(/^HTTP\/1\.[01] (\d{3})/) || [])[1]);
      resolve({ status, text });
    });
    sock.on('error', reject);
  });
}

/** Runs serve.py to completion (for the refusal cases) and returns {code, signal, stdout, stderr}. */
function runServe(args, timeout = 10_000) {
  return new Promise((resolve, reject) => {
    const p = spawn(process.env.PYTHON || 'python3', [SERVE_PY, ...args], { stdio: ['ignore', 'pipe', 'pipe'] });
    let stdout = '';
    let stderr = '';
    p.stdout.on('data', (d) => (stdout += d));
    p.stderr.on('data', (d) => (stderr += d));
    const t = setTimeout(() => {
      p.kill('SIGKILL');
      reject(new Error(`serve.py ${args.join(' ')} did not exit within ${timeout} ms\n${stdout}\n${stderr}`));
    }, timeout);
    p.on('exit', (code, signal) => {
      clearTimeout(t);
      resolve({ code, signal, stdout, stderr });
    });
  });
}

/** Local addresses listening on `port` according to /proc/net/tcp{,6} (Linux). */
function listeningAddresses(port) {
  const found = [];
  for (const file of ['/proc/net/tcp', '/proc/net/tcp6']) {
    let text;
    try {
      text = fs.readFileSync(file, 'utf8');
    } catch {
      continue;
    }
    for (const line of text.trim().split('\n').slice(1)) {
      const cols = line.trim().split(/\s+/);
      const [addrHex, portHex] = cols[1].split(':');
      if (parseInt(portHex, 16) !== port || cols[3] !== '0A') continue; // 0A = LISTEN
      if (addrHex.length === 8) {
        found.push(Buffer.from(addrHex, 'hex').reverse().join('.'));
      } else {
        found.push(`ipv6:${addrHex}`);
      }
    }
  }
  return found;
}

describe('www/serve.py', () => {
  let server;

  before(async () => {
    makeTree();
    server = await startServer(root, { extraArgs: [] });
  });

  after(async () => {
    if (server) await server.stop({ signal: 'SIGKILL', timeout: 2000 }).catch(() => {});
    if (tmp) fs.rmSync(tmp, { recursive: true, force: true });
  });

  test('prints the real URL for --port 0 and binds only 127.0.0.1', () => {
    assert.equal(server.host, '127.0.0.1');
    assert.ok(server.port > 0 && server.port < 65536, `port ${server.port}`);
    if (fs.existsSync('/proc/net/tcp')) {
      assert.deepEqual(listeningAddresses(server.port), ['127.0.0.1'], 'listening sockets on the port');
    }
  });

  test('wasm is served as application/wasm with its bytes', async () => {
    const r = await request(`${server.url}pkg/spherical_faces_bg.wasm`);
    assert.equal(r.status, 200);
    assert.equal(r.headers['content-type'], 'application/wasm');
    assert.deepEqual(r.body, WASM);
  });

  test('cross-origin isolation and no-cache headers on /', async () => {
    const r = await request(server.url);
    assert.equal(r.status, 200);
    assert.match(r.headers['content-type'], /^text\/html\b/);
    assert.match(r.body.toString(), /sf-canvas/);
    assert.equal(r.headers['cross-origin-opener-policy'], 'same-origin');
    assert.equal(r.headers['cross-origin-embedder-policy'], 'require-corp');
    assert.equal(r.headers['cross-origin-resource-policy'], 'same-origin');
    assert.equal(r.headers['cache-control'], 'no-cache');
  });

  test('query strings are ignored (?backend=webgpu)', async () => {
    const r = await request(`${server.url}?backend=webgpu`);
    assert.equal(r.status, 200);
    assert.match(r.body.toString(), /sf-canvas/);
  });

  test('MIME types', async () => {
    const want = {
      'pkg/spherical_faces.js': /^text\/javascript\b/,
      'assets/worker.mjs': /^text\/javascript\b/,
      'assets/style.css': /^text\/css\b/,
      'assets/data.json': /^application\/json\b/,
      'assets/m.glb': /^model\/gltf-binary$/,
      'assets/m.gltf': /^model\/gltf\+json\b/,
      'assets/m.obj': /^text\/plain\b/,
      'assets/i.png': /^image\/png$/,
      'assets/i.svg': /^image\/svg\+xml\b/,
    };
    for (const [p, re] of Object.entries(want)) {
      const r = await request(`${server.url}${p}`);
      assert.equal(r.status, 200, p);
      assert.match(r.headers['content-type'], re, p);
    }
  });

  test('HEAD sends headers only; other methods get 405', async () => {
    const h = await request(`${server.url}pkg/spherical_faces_bg.wasm`, { method: 'HEAD' });
    assert.equal(h.status, 200);
    assert.equal(h.headers['content-type'], 'application/wasm');
    assert.equal(h.headers['content-length'], String(WASM.length));
    assert.equal(h.body.length, 0);
    for (const method of ['POST', 'PUT', 'DELETE']) {
      const r = await request(server.url, { method });
      assert.equal(r.status, 405, method);
    }
  });

  test('paths outside the root are refused and never leak content', async () => {
    const targets = [
      '/../Cargo.toml',
      '/%2e%2e/Cargo.toml',
      '/%2E%2E/Cargo.toml',
      '/..%2fCargo.toml',
      '/pkg/../../Cargo.toml',
      '/pkg/%2e%2e/%2e%2e/Cargo.toml',
      '/%2e%2e%2fCargo.toml',
      '/..\\Cargo.toml',
      '/%5c..%5cCargo.toml',
      '//../Cargo.toml',
      `/${encodeURIComponent(path.join(tmp, 'Cargo.toml'))}`,
      `/${path.join(tmp, 'Cargo.toml')}`,
      '/link-out.txt',
      '/dir-out/Cargo.toml',
      '/dir-out/outside.txt',
      '../Cargo.toml',
      `http://127.0.0.1:${server.port}/../Cargo.toml`,
      '/%00../Cargo.toml',
    ];
    for (const target of targets) {
      const r = await rawRequest(server.port, target);
      assert.ok(r.status === 403 || r.status === 404 || r.status === 400, `GET ${target} -> ${r.status}\n${r.text.slice(0, 300)}`);
      assert.ok(!r.text.includes(SECRET), `GET ${target} leaked the file outside the root`);
    }
    // the two cases the README promises are 403 exactly
    assert.equal((await rawRequest(server.port, '/../Cargo.toml')).status, 403);
    assert.equal((await rawRequest(server.port, '/%2e%2e/Cargo.toml')).status, 403);
  });

  test('symlinks that stay inside the root still work; unknown files are 404', async () => {
    const r = await request(`${server.url}pkg-link/spherical_faces_bg.wasm`);
    assert.equal(r.status, 200);
    assert.equal((await request(`${server.url}nope.js`)).status, 404);
  });

  test('refuses a non-loopback host without --allow-remote (one clear line, no traceback)', async () => {
    const r = await runServe(['--root', root, '--port', '0', '--host', '0.0.0.0']);
    assert.notEqual(r.code, 0);
    assert.match(r.stderr, /allow-remote/);
    assert.doesNotMatch(r.stderr, /Traceback/);
    assert.doesNotMatch(r.stdout, /being served/);
  });

  test('a taken port gives one clear error line and a non-zero exit', async () => {
    const r = await runServe(['--root', root, '--port', String(server.port)]);
    assert.notEqual(r.code, 0);
    assert.doesNotMatch(r.stderr, /Traceback/);
    assert.match(r.stderr, /already in use/);
    assert.equal(r.stderr.trim().split('\n').length, 1, `stderr: ${r.stderr}`);
  });

  test('SIGINT stops it with exit code 0 within 2 s, even with an idle keep-alive client', async () => {
    const s = await startServer(root);
    const sock = net.connect({ host: '127.0.0.1', port: s.port });
    await new Promise((res, rej) => sock.on('connect', res).on('error', rej));
    sock.write(`GET / HTTP/1.1\r\nHost: x\r\n\r\n`); // keep-alive: the handler thread waits for more
    await new Promise((res) => sock.once('data', res));
    const r = await s.stop({ signal: 'SIGINT', timeout: 2000 });
    sock.destroy();
    assert.equal(r.killed, false, `still running 2 s after SIGINT\n${s.output()}`);
    assert.equal(r.code, 0, s.output());
    assert.ok(r.ms < 2000, `took ${r.ms} ms`);
    assert.doesNotMatch(s.output(), /Traceback/);
  });

  test('SIGTERM stops it with exit code 0 within 2 s', async () => {
    const s = await startServer(root);
    const r = await s.stop({ signal: 'SIGTERM', timeout: 2000 });
    assert.equal(r.killed, false, `still running 2 s after SIGTERM\n${s.output()}`);
    assert.equal(r.code, 0, s.output());
    assert.doesNotMatch(s.output(), /Traceback/);
  });
});
