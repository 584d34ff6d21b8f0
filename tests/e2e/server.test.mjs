// The dev server: isolation headers on every response, MIME types, and no way out of its root.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import http from 'node:http';
import { mkdtempSync, writeFileSync, symlinkSync, mkdirSync, rmSync, utimesSync } from 'node:fs';
import { gunzipSync, brotliCompressSync, brotliDecompressSync } from 'node:zlib';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { spawnSync } from 'node:child_process';
import { startServer, ROOT } from './harness.mjs';

let server;
let root;
const BIG_JS = Buffer.from('export const x = "procfit";\n'.repeat(400));
const BIG_WASM = Buffer.concat([Buffer.from([0, 97, 115, 109, 1, 0, 0, 0]), Buffer.alloc(20000, 7)]);

before(async () => {
  root = mkdtempSync(join(tmpdir(), 'procfit-serve-'));
  const outside = mkdtempSync(join(tmpdir(), 'procfit-outside-'));
  writeFileSync(join(outside, 'secret.txt'), 'secret');
  writeFileSync(join(root, 'index.html'), '<!doctype html><title>t</title>');
  writeFileSync(join(root, 'a.wasm'), Buffer.from([0, 97, 115, 109]));
  writeFileSync(join(root, 'a.js'), 'export {}');
  writeFileSync(join(root, 'a.mjs'), 'export {}');
  writeFileSync(join(root, 'a.glb'), 'glTF');
  mkdirSync(join(root, 'sub'));
  writeFileSync(join(root, 'sub', 'ok.txt'), 'ok');
  symlinkSync(join(outside, 'secret.txt'), join(root, 'link-out.txt'));
  symlinkSync(outside, join(root, 'dir-out'));
  symlinkSync(join(root, 'sub', 'ok.txt'), join(root, 'link-in.txt'));
  // Compression: a large script (gzipped on the fly), a wasm with a precompressed .br beside it,
  // and a stale .br (older than its file) that must not be sent.
  writeFileSync(join(root, 'big.js'), BIG_JS);
  writeFileSync(join(root, 'big.wasm'), BIG_WASM);
  writeFileSync(join(root, 'big.wasm.br'), brotliCompressSync(BIG_WASM));
  writeFileSync(join(root, 'stale.js'), BIG_JS);
  writeFileSync(join(root, 'stale.js.br'), brotliCompressSync(Buffer.from('old contents')));
  utimesSync(join(root, 'stale.js.br'), new Date(2000, 0, 1), new Date(2000, 0, 1));
  server = await startServer({ root });
});

after(() => {
  server?.stop();
  rmSync(root, { recursive: true, force: true });
});

/** A raw GET: node's http does not normalise the path, so `..` reaches the server as sent. */
function get(path, headers = {}) {
  const { port } = new URL(server.url);
  return new Promise((resolve, reject) => {
    const req = http.request({ host: '127.0.0.1', port, path, method: 'GET', headers }, (res) => {
      const chunks = [];
      res.on('data', (d) => chunks.push(d));
      res.on('end', () => {
        const bytes = Buffer.concat(chunks);
        resolve({ status: res.statusCode, headers: res.headers, body: bytes.toString(), bytes });
      });
    });
    req.on('error', reject);
    req.end();
  });
}

/** `status` is a code or a list of acceptable codes (403 or 404 both keep a path out). */
function check(path, status, type) {
  const ok = [status].flat();
  test(`GET ${path} → ${ok.join(' or ')}`, async () => {
    const res = await get(path);
    assert.ok(ok.includes(res.status), `status ${res.status}`);
    assert.equal(res.headers['cross-origin-opener-policy'], 'same-origin');
    assert.equal(res.headers['cross-origin-embedder-policy'], 'require-corp');
    if (type) assert.equal(res.headers['content-type'], type);
    if (!ok.includes(200)) assert.ok(!res.body.includes('secret'));
  });
}

check('/', 200, 'text/html; charset=utf-8');
check('/a.wasm', 200, 'application/wasm');
check('/a.js', 200, 'text/javascript; charset=utf-8');
check('/a.mjs', 200, 'text/javascript; charset=utf-8');
check('/a.glb', 200, 'model/gltf-binary');
check('/sub/ok.txt', 200);
check('/link-in.txt', 200);
check('/missing.txt', 404);
check('/../secret.txt', 403);
check('/sub/../../secret.txt', 403);
check('/%2e%2e/secret.txt', 403);
check('/%2E%2E/%2e%2e/etc/passwd', 403);
check('/sub/%2e%2e%2f%2e%2e%2fetc/passwd', 403);
// Python collapses a leading `//` to `/` before we see it: that stays inside the root.
check('//etc/passwd', [403, 404]);
check('/..%5c..%5cetc%5cpasswd', 403);
check('/a.js%00.html', 403);
check('/link-out.txt', 403);
check('/dir-out/secret.txt', 403);

/** A raw request with any method, path and extra header lines. */
function raw(method, path, headers = {}) {
  const { port } = new URL(server.url);
  return new Promise((resolve, reject) => {
    const req = http.request({ host: '127.0.0.1', port, path, method, headers }, (res) => {
      res.resume();
      res.on('end', () => resolve({ status: res.statusCode, headers: res.headers }));
    });
    req.on('error', reject);
    req.end();
  });
}

// Issue 19: http.server's own error replies lacked COOP/COEP.
for (const [name, args, status] of [
  ['an unknown method', ['BREW', '/'], 501],
  ['a too-long URI', ['GET', '/' + 'a'.repeat(70000)], 414],
  ['too many headers', ['GET', '/', Object.fromEntries([...Array(120)].map((_, i) => [`x-h${i}`, 'v']))], 431],
]) {
  test(`${name} → ${status}, with the isolation headers`, async () => {
    const res = await raw(...args);
    assert.equal(res.status, status);
    assert.equal(res.headers['cross-origin-opener-policy'], 'same-origin');
    assert.equal(res.headers['cross-origin-embedder-policy'], 'require-corp');
  });
}

// Issue 19: with a listen backlog of 5, 200 concurrent GETs of the wasm took up to 27.6 s.
test('200 concurrent GETs are all served within 10 s', async () => {
  const agent = new http.Agent({ keepAlive: false, maxSockets: Infinity });
  const { port } = new URL(server.url);
  const started = Date.now();
  const one = () =>
    new Promise((resolve, reject) => {
      const req = http.get({ host: '127.0.0.1', port, path: '/a.wasm', agent }, (res) => {
        res.resume();
        res.on('end', () => resolve(res.statusCode));
      });
      req.setTimeout(10000, () => req.destroy(new Error('timed out')));
      req.on('error', reject);
    });
  const codes = await Promise.all([...Array(200)].map(one));
  assert.ok(codes.every((c) => c === 200), `statuses ${[...new Set(codes)]}`);
  assert.ok(Date.now() - started < 10000);
});

test('binds loopback only', () => {
  assert.match(server.url, /^http:\/\/127\.0\.0\.1:\d+\/$/);
});

test('a busy port gets a one-line message that suggests PORT=', () => {
  const { port } = new URL(server.url);
  const r = spawnSync('python3', [join(ROOT, 'scripts', 'serve.py'), '--root', root, '--port', port], {
    encoding: 'utf8',
    timeout: 10000,
  });
  assert.notEqual(r.status, 0);
  assert.match(r.stderr, /busy.*PORT=/);
  assert.equal(r.stderr.trim().split('\n').length, 1);
});

// Issue 17: the dev server compresses by Accept-Encoding, and keeps COOP/COEP on those replies.
test('compression follows Accept-Encoding, precompressed files first, never a stale one', async () => {
  const isolated = (res) => {
    assert.equal(res.headers['cross-origin-opener-policy'], 'same-origin');
    assert.equal(res.headers['cross-origin-embedder-policy'], 'require-corp');
    assert.equal(res.headers.vary, 'Accept-Encoding');
  };
  let res = await get('/big.js', { 'Accept-Encoding': 'gzip, deflate, br' });
  assert.equal(res.headers['content-encoding'], 'gzip', 'no .br beside it: gzip on the fly');
  assert.deepEqual(gunzipSync(res.bytes), BIG_JS);
  assert.ok(res.bytes.length < BIG_JS.length / 10, `${res.bytes.length} bytes`);
  assert.equal(Number(res.headers['content-length']), res.bytes.length);
  isolated(res);

  res = await get('/big.wasm', { 'Accept-Encoding': 'gzip, br' });
  assert.equal(res.headers['content-encoding'], 'br');
  assert.equal(res.headers['content-type'], 'application/wasm');
  assert.deepEqual(brotliDecompressSync(res.bytes), BIG_WASM);
  isolated(res);

  res = await get('/big.wasm', { 'Accept-Encoding': 'br;q=0, gzip' });
  assert.equal(res.headers['content-encoding'], 'gzip', 'br refused with q=0');
  assert.deepEqual(gunzipSync(res.bytes), BIG_WASM);

  res = await get('/big.wasm');
  assert.equal(res.headers['content-encoding'], undefined, 'no Accept-Encoding: identity');
  assert.deepEqual(res.bytes, BIG_WASM);
  isolated(res);

  res = await get('/stale.js', { 'Accept-Encoding': 'br' });
  assert.equal(res.headers['content-encoding'], undefined, 'a .br older than its file is not sent');
  assert.deepEqual(res.bytes, BIG_JS);
});
