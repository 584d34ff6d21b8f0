// Issue 17: the page's first load from dist/ (served by scripts/serve.py, which sends the
// precompressed copies `make dist` writes) transfers at most 2 MB until the first model is on
// screen, and neither the page nor its workers print a console warning or error. Prints what
// each file cost (transferred and decoded bytes), largest first.
import { test, after } from 'node:test';
import assert from 'node:assert/strict';
import { existsSync } from 'node:fs';
import { join } from 'node:path';
import { startServer, firstLoad, ROOT } from './harness.mjs';

const DIST = join(ROOT, 'dist');
const LIMIT = 2_000_000;
const cleanup = [];

after(async () => {
  for (const f of cleanup.reverse()) await f();
});

test('first load from dist/ is at most 2 MB transferred, with no console warnings', async () => {
  assert.ok(existsSync(join(DIST, 'index.html')), 'dist/ is missing: run `make dist`');
  const server = await startServer({ root: DIST, isolation: true });
  cleanup.push(() => server.stop());
  const { files, noise, close } = await firstLoad(server.url);
  cleanup.push(close);
  const total = files.reduce((s, f) => s + f.transferred, 0);
  const decoded = files.reduce((s, f) => s + f.decoded, 0);
  files.sort((a, b) => b.transferred - a.transferred);
  console.log('| file | transferred | decoded |\n|---|---:|---:|');
  for (const f of files.slice(0, 12)) {
    console.log(`| ${f.url.replace(server.url, '/')} | ${f.transferred} | ${f.decoded} |`);
  }
  console.log(`| **${files.length} requests** | ${total} | ${decoded} |`);
  assert.ok(files.some((f) => f.url.endsWith('.wasm')), 'the wasm was fetched and counted');
  assert.ok(total <= LIMIT, `first load transferred ${total} bytes > ${LIMIT}`);
  assert.deepEqual(noise, [], 'console warnings or errors');
});
