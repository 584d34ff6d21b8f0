// Issue 17: the page's first load from dist/ (served by scripts/serve.py, which sends the
// precompressed copies `make dist` writes) transfers at most 2 MB until the first model is on
// screen, and neither the page nor its workers print a console warning or error. Prints what
// each file cost (transferred and decoded bytes), largest first.
import { test, after } from 'node:test';
import assert from 'node:assert/strict';
import { existsSync } from 'node:fs';
import { join } from 'node:path';
import { startServer, launchBrowser, ROOT } from './harness.mjs';

const DIST = join(ROOT, 'dist');
const LIMIT = 2_000_000;
const cleanup = [];

after(async () => {
  for (const f of cleanup.reverse()) await f();
});

/**
 * Loads `url` in a fresh browser until the first model is drawn: resolves with the requests'
 * { url, transferred, decoded } and every console warning or error of the page and its workers.
 */
async function firstLoad(url) {
  const browser = await launchBrowser();
  cleanup.push(() => browser.close());
  const files = [];
  const noise = [];
  browser.context.on('requestfinished', async (request) => {
    const response = await request.response();
    const sizes = await request.sizes();
    const body = response ? await response.body().catch(() => Buffer.alloc(0)) : Buffer.alloc(0);
    files.push({
      url: request.url(),
      transferred: sizes.responseBodySize + sizes.responseHeadersSize,
      decoded: body.length,
    });
  });
  const page = await browser.context.newPage();
  const listen = (where) => (m) => {
    // Headless Chromium's software GL driver reports its own performance notes ("GL Driver
    // Message … GPU stall due to ReadPixels") as console warnings; they are the driver's, not
    // the page's, and a hardware GPU prints none.
    if (/^\[\.WebGL-[0-9a-fx]+\]GL Driver Message/.test(m.text())) return;
    if (m.type() === 'warning' || m.type() === 'error') noise.push(`${where} ${m.type()}: ${m.text()}`);
  };
  page.on('console', listen('page'));
  page.on('worker', (w) => w.on('console', listen(`worker ${w.url()}`)));
  page.on('pageerror', (e) => noise.push(`page error: ${e}`));
  await page.goto(url);
  await page.waitForSelector('body[data-ready="true"]', { timeout: 120000 });
  await page.evaluate(() => window.procfit.editor.settled());
  // Let the last responses' sizes arrive.
  await page.waitForTimeout(500);
  return { files, noise };
}

test('first load from dist/ is at most 2 MB transferred, with no console warnings', async () => {
  assert.ok(existsSync(join(DIST, 'index.html')), 'dist/ is missing: run `make dist`');
  const server = await startServer({ root: DIST, isolation: true });
  cleanup.push(() => server.stop());
  const { files, noise } = await firstLoad(server.url);
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
