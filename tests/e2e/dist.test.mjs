// `make dist` produces a folder a static host serves as is: served from dist/ alone (with and
// without the isolation headers), the page starts, shows the model, and fetches nothing that
// dist/ lacks.
import { test, after } from 'node:test';
import assert from 'node:assert/strict';
import { existsSync } from 'node:fs';
import { join } from 'node:path';
import { startServer, launchBrowser, openPage, ROOT } from './harness.mjs';

const DIST = join(ROOT, 'dist');
const browsers = [];
const servers = [];

after(async () => {
  for (const b of browsers) await b.close();
  for (const s of servers) s.stop();
});

function check(isolation, threadedExpected) {
  test(`dist/ served ${isolation ? 'with' : 'without'} COOP/COEP runs the page`, async () => {
    assert.ok(existsSync(join(DIST, 'index.html')), 'dist/ is missing: run `make dist` (make test-e2e does)');
    const server = await startServer({ root: DIST, isolation });
    servers.push(server);
    const browser = await launchBrowser();
    browsers.push(browser);
    const { page, log } = await openPage(browser.context, server.url);
    await page.waitForSelector('body[data-ready="true"]', { timeout: 90000 });
    await page.evaluate(() => window.procfit.editor.settled());
    const info = await page.evaluate(() => window.procfit.client.call(window.procfit.REQUESTS.PING));
    assert.equal(info.threaded, threadedExpected);
    assert.match(await page.textContent('#viewer-info'), /triangles/);
    assert.deepEqual(log.consoleErrors, [], 'a missing file shows up as a console error');
    assert.deepEqual(log.pageErrors, []);
  });
}

check(true, true);
check(false, false);
