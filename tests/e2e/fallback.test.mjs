// Served like a plain static host (no COOP/COEP headers, so no SharedArrayBuffer), the page
// loads the single-threaded build (pkg-st/), says so, and the journey still works: the model
// shows, a sample gets its mask, a quick fit completes.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { startServer, launchBrowser, openPage, screenshot } from './harness.mjs';

let server;
let browser;
let page;
let log;

before(async () => {
  server = await startServer({ isolation: false });
  browser = await launchBrowser();
  ({ page, log } = await openPage(browser.context, server.url));
  await page.waitForSelector('body[data-ready="true"]', { timeout: 90000 });
});

after(async () => {
  await browser?.close();
  server?.stop();
});

test('without isolation the single-threaded build runs and the page says so', async () => {
  assert.equal(await page.evaluate(() => self.crossOriginIsolated), false);
  assert.equal(await page.textContent('#status'), 'ready — 1 thread');
  const info = await page.evaluate(() => window.procfit.client.call(window.procfit.REQUESTS.PING));
  assert.equal(info.threaded, false);
  assert.equal(await page.isVisible('#notice'), true);
  assert.match(await page.textContent('#notice'), /one thread.*cross-origin isolation/);
  assert.ok(log.requests.some((u) => u.includes('/pkg-st/procfit_bg.wasm')), 'pkg-st was not loaded');
  assert.ok(!log.requests.some((u) => u.includes('/pkg/procfit_bg.wasm')), 'the threaded build was loaded too');
});

test('the model, the mask and a quick fit work single-threaded', async () => {
  await page.evaluate(() => window.procfit.editor.settled());
  assert.match(await page.textContent('#viewer-info'), /triangles/);
  await page.click('button[data-sample="mug"]');
  await page.waitForFunction(() => /Object found|check the mask/.test(document.getElementById('mask-state').textContent), null, { timeout: 60000 });
  await page.selectOption('#fit-quality', '0.25');
  await page.click('#fit-start');
  await page.waitForFunction(() => document.body.dataset.fitted, null, { timeout: 180000 });
  assert.equal(await page.evaluate(() => document.body.dataset.fitted), 'done', await page.textContent('#fit-message'));
  await screenshot(page, '10-single-threaded');
});

test('no console errors, no page errors, no request outside the origin', () => {
  assert.deepEqual(log.pageErrors, []);
  assert.deepEqual(log.consoleErrors, []);
  const origin = new URL(server.url).origin;
  assert.deepEqual(log.requests.filter((u) => !u.startsWith(origin) && !u.startsWith('data:') && !u.startsWith('blob:')), []);
});
