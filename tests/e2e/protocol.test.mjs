// The worker protocol's version (www/protocol.js PROTOCOL_VERSION) is checked when the worker
// starts: a worker of this version is taken, one of another version (here: the page's worker.js
// rewritten on its way to report the version before) is refused with a message that says to
// reload, and no request is sent to it.
import { test, after } from 'node:test';
import assert from 'node:assert/strict';
import { startServer, launchBrowser, openPage, waitReady } from './harness.mjs';
import { PROTOCOL_VERSION } from '../../www/protocol.js';

const open = [];
after(async () => {
  for (const { browser, server } of open) {
    await browser.close();
    server.stop();
  }
});

async function start(rewrite = null) {
  const server = await startServer();
  const browser = await launchBrowser();
  open.push({ browser, server });
  let rewritten = false;
  if (rewrite) {
    await browser.context.route('**/www/worker.js', async (route) => {
      const res = await route.fetch();
      const text = await res.text();
      const body = rewrite(text);
      rewritten = body !== text;
      await route.fulfill({ response: res, body });
    });
  }
  const { page, log } = await openPage(browser.context, server.url);
  return { page, log, rewritten: () => rewritten };
}

test('a worker of this protocol version is taken', async () => {
  const { page } = await start();
  await waitReady(page);
  const info = await page.evaluate(() => window.procfit.client.call(window.procfit.REQUESTS.PING));
  assert.equal(info.protocol, PROTOCOL_VERSION);
});

test('a worker of another protocol version is refused, with a message to reload', async () => {
  const { page, rewritten } = await start((js) => js.replace('protocol: PROTOCOL_VERSION,', 'protocol: PROTOCOL_VERSION - 1,'));
  await page.waitForFunction(() => document.getElementById('status').dataset.state === 'failed', null, { timeout: 60000 });
  assert.equal(rewritten(), true, 'the worker was not rewritten');
  const status = await page.textContent('#status');
  assert.match(status, new RegExp(`could not start: the worker speaks protocol ${PROTOCOL_VERSION - 1} but this page speaks ${PROTOCOL_VERSION}.*reload the page`));
  await page.waitForFunction(() => document.getElementById('model-message').textContent, null, { timeout: 10000 });
  assert.match(await page.textContent('#model-message'), /could not start: the worker speaks protocol/);
  // Refused for good: no restart, so the page does not spin on a worker it will never take.
  await page.waitForTimeout(500);
  assert.equal(await page.evaluate(() => window.procfit.client.restarts), 0);
});
