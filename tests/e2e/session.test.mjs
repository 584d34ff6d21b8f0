// Work is not lost: a reload restores the photos, masks and model from IndexedDB; corrections
// made before a reload still count for the next one; "Start over" clears them; a worker that dies
// mid-session is replaced and the session goes on (the model is shown again, mask corrections
// still work).
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { startServer, launchBrowser, openPage, screenshot } from './harness.mjs';

let server;
let browser;
let page;
let log;

const ready = (p = page) => p.waitForSelector('body[data-ready="true"]', { timeout: 90000 });
const settled = () => page.evaluate(() => window.procfit.editor.settled());
const maskFound = () =>
  page.waitForFunction(() => /Object found|check the mask/.test(document.getElementById('mask-state').textContent), null, { timeout: 60000 });

before(async () => {
  server = await startServer();
  browser = await launchBrowser();
  ({ page, log } = await openPage(browser.context, server.url));
  await ready();
});

after(async () => {
  await browser?.close();
  server?.stop();
});

test('a reload restores photos, masks, the model and its starting point', async () => {
  await page.click('button[data-sample="bowl"]');
  await maskFound();
  await page.selectOption('#lod', '0');
  // The sample has no EXIF; a focal length as photoOf (main.js) would have read must be kept
  // (page.test.mjs checks the reading itself). The slider change below saves it.
  await page.evaluate(() => (window.procfit.state.photos[0].focal35mm = 35));
  // Part colours (as a fit measures them in the photos) and "Colours from the photo" switched
  // off are kept too (issue 17).
  await page.evaluate(() => {
    window.procfit.editor.colors = { body: [0.1, 0.2, 0.3] };
    window.procfit.editor.setUseColors(false);
  });
  await page.focus('#param-y_scale');
  await page.keyboard.press('End');
  await settled();
  const before = await page.evaluate(() => ({
    params: window.procfit.editor.params.slice(),
    base: window.procfit.editor.base.slice(),
    lod: window.procfit.editor.lod,
    codes: Array.from(window.procfit.state.photos[0].mask.codes.slice(0, 4096)),
  }));
  // The last change must be saved too: wait for a save that finished after it.
  const changedAt = await page.evaluate(() => Date.now());
  await page.waitForFunction((t) => Number(document.body.dataset.saved || 0) > t, changedAt, { timeout: 20000 });
  await page.reload();
  await ready();
  await settled();
  const afterReload = await page.evaluate(() => ({
    params: window.procfit.editor.params.slice(),
    base: window.procfit.editor.base.slice(),
    lod: window.procfit.editor.lod,
    codes: Array.from(window.procfit.state.photos[0].mask.codes.slice(0, 4096)),
    photos: window.procfit.state.photos.length,
    focal: window.procfit.state.photos[0].focal35mm,
  }));
  assert.equal(afterReload.focal, 35, 'the EXIF focal length was not kept');
  assert.deepEqual(await page.evaluate(() => window.procfit.editor.colors), { body: [0.1, 0.2, 0.3] });
  assert.equal(await page.evaluate(() => window.procfit.editor.useColors), false);
  assert.equal(await page.isVisible('#photo-colors-label'), true);
  assert.equal(await page.isChecked('#photo-colors'), false);
  assert.equal(afterReload.photos, 1);
  assert.deepEqual(afterReload.params, before.params);
  assert.deepEqual(afterReload.base, before.base);
  assert.equal(afterReload.lod, 0);
  assert.equal(await page.inputValue('#lod'), '0');
  assert.deepEqual(afterReload.codes, before.codes);
  assert.equal(await page.isVisible('#restored'), true);
  // The step last worked in (the model's sliders) is the one scrolled to.
  assert.equal(await page.evaluate(() => window.procfit.state.step), 'step-model');
  const top = await page.evaluate(() => document.getElementById('step-model').getBoundingClientRect().top);
  assert.ok(Math.abs(top) < 5, `the model step is ${top}px from the top of the window`);
  assert.match(await page.textContent('#restored-text'), /Restored your last session \(1 photo\)/);
  await screenshot(page, '09-restored');
});

/** Drags the current brush along `points` (fractions of the mask overlay), waits for the new mask. */
async function brush(tool, points) {
  await page.check(`input[name="tool"][value="${tool}"]`);
  await page.evaluate(() => {
    const r = document.getElementById('mask-canvas').getBoundingClientRect();
    window.scrollBy(0, r.top + r.height / 2 - window.innerHeight / 2);
  });
  const box = await page.locator('#mask-canvas').boundingBox();
  const at = ([fx, fy]) => [box.x + fx * box.width, box.y + fy * box.height];
  // A handle, so the wait compares with the very array (a serialised copy never equals it).
  const before = await page.evaluateHandle(() => window.procfit.state.photos[0].mask.codes);
  await page.mouse.move(...at(points[0]));
  await page.mouse.down();
  for (const p of points.slice(1)) await page.mouse.move(...at(p), { steps: 3 });
  await page.mouse.up();
  await page.waitForFunction((b) => window.procfit.state.photos[0].mask.codes !== b, before, { timeout: 30000 });
  await page.check('input[name="tool"][value="none"]');
}

/** The mask code at (fx, fy), fractions of the photo. */
const codeAt = ([fx, fy]) =>
  page.evaluate(([fx, fy]) => {
    const m = window.procfit.state.photos[0].mask;
    return m.codes[Math.floor(fy * m.height) * m.width + Math.floor(fx * m.width)];
  }, [fx, fy]);

/** A point of the bowl that the first correction below cuts off (fractions of the photo). */
let cut;

test('a correction made before a reload still counts after it', async () => {
  // The first correction: a background stroke across the left part of the bowl.
  const [x0, y0, x1, y1] = await page.evaluate(() => {
    const m = window.procfit.state.photos[0].mask;
    const [a, b, c, d] = m.bbox;
    return [a / m.width, b / m.height, c / m.width, d / m.height];
  });
  const y = (y0 + y1) / 2;
  cut = [x0 + 0.2 * (x1 - x0), y];
  assert.equal(await codeAt(cut), 255, 'the bowl should start as object there');
  await brush('background', [[x0 + 0.12 * (x1 - x0), y], [x0 + 0.28 * (x1 - x0), y]]);
  assert.equal(await codeAt(cut), 0, 'the background stroke did not cut the bowl');
  const changedAt = await page.evaluate(() => Date.now());
  await page.waitForFunction((t) => Number(document.body.dataset.saved || 0) > t, changedAt, { timeout: 20000 });
  assert.equal(await page.evaluate(() => window.procfit.state.photos[0].edits.length), 1);
  await page.reload();
  await ready();
  assert.equal(await codeAt(cut), 0, 'the stored mask lost the correction');
  // A second correction, far from the first (the top-right corner, background already): the
  // worker re-cuts with both strokes, so the cut stays (before the replay, the worker's session
  // was the automatic one and the bowl came back whole).
  await brush('background', [[0.96, 0.04], [0.9, 0.04]]);
  assert.equal(await codeAt(cut), 0, 'the correction made before the reload was dropped');
  assert.equal(await page.evaluate(() => window.procfit.state.photos[0].edits.length), 2);
  await screenshot(page, '09b-corrections-after-reload');
});

test('the worker dies mid-session: it is replaced and the session goes on', async () => {
  const params = await page.evaluate(() => window.procfit.editor.params.slice());
  const err = await page.evaluate(() =>
    window.procfit.client.call(window.procfit.REQUESTS.DEBUG_PANIC).then(() => null, (e) => e.message),
  );
  assert.match(err, /deliberate panic/);
  await page.waitForFunction(() => document.getElementById('status').dataset.state === 'ready' && window.procfit.client.restarts > 0, null, { timeout: 60000 });
  // The model is shown again by the new worker, with the same parameters.
  await page.focus('#param-y_scale');
  await page.keyboard.press('Home');
  await settled();
  assert.equal(await page.evaluate(() => window.procfit.editor.glb.params[9]), 0.1);
  assert.deepEqual((await page.evaluate(() => window.procfit.editor.params)).slice(10), params.slice(10));
  // A mask correction needs the worker's mask session: it was made again.
  await page.check('input[name="tool"][value="background"]');
  const box = await page.locator('#mask-canvas').boundingBox();
  const before = await page.evaluate(() => window.procfit.state.photos[0].mask.codes);
  await page.mouse.move(box.x + 5, box.y + 5);
  await page.mouse.down();
  await page.mouse.move(box.x + 40, box.y + 10, { steps: 3 });
  await page.mouse.up();
  await page.waitForFunction((b) => window.procfit.state.photos[0].mask.codes !== b, before, { timeout: 30000 });
  assert.equal(await page.isHidden('#photos-message'), true, await page.textContent('#photos-message'));
  await page.check('input[name="tool"][value="none"]');
  log.consoleErrors = log.consoleErrors.filter((m) => !/deliberate panic|unreachable|RuntimeError/.test(m));
});

test('another kind of object cuts the mask again for itself, the corrections kept', async () => {
  const photo0 = () => page.evaluate(() => {
    const p = window.procfit.state.photos[0];
    return { maskFor: p.maskFor, state: p.maskState, edits: p.edits.length };
  });
  const was = await photo0();
  assert.equal(was.maskFor, 'dish', 'the bowl sample is cut for a dish');
  // A kind whose masks are cut as a dish's (a tree's) leaves the mask as it is.
  const codes = await page.evaluateHandle(() => window.procfit.state.photos[0].mask.codes);
  await page.check('#gen-tree');
  await settled();
  assert.equal(await page.evaluate((c) => window.procfit.state.photos[0].mask.codes === c, codes), true);
  assert.equal((await photo0()).maskFor, 'dish');
  // A building's mask is cut closer to its outline: the photo is cut again, and the person's
  // corrections are replayed on the new cut.
  await page.check('#gen-building');
  await page.waitForFunction(
    (c) => {
      const p = window.procfit.state.photos[0];
      return p.maskFor === 'building' && p.maskState === 'ready' && p.mask.codes !== c;
    },
    codes,
    { timeout: 60000 },
  );
  assert.equal((await photo0()).edits, was.edits, 'the corrections were dropped');
  assert.equal(await codeAt(cut), 0, 'the first correction no longer cuts the bowl');
  // The kind the mask was cut for is kept: a reload revives the same cut.
  const changedAt = await page.evaluate(() => Date.now());
  await page.waitForFunction((t) => Number(document.body.dataset.saved || 0) > t, changedAt, { timeout: 20000 });
  await page.reload();
  await ready();
  assert.deepEqual(await photo0(), { maskFor: 'building', state: 'ready', edits: was.edits });
  assert.equal(await codeAt(cut), 0, 'the stored mask lost the correction');
  await page.check('#gen-dish');
  await page.waitForFunction(() => window.procfit.state.photos[0].maskFor === 'dish' && window.procfit.state.photos[0].maskState === 'ready', null, { timeout: 60000 });
  assert.equal(await codeAt(cut), 0);
});

test('"Start over" clears the saved session', async () => {
  await Promise.all([page.waitForNavigation(), page.click('#start-over')]);
  await ready();
  assert.equal(await page.evaluate(() => window.procfit.state.photos.length), 0);
  assert.equal(await page.isHidden('#restored'), true);
  await page.reload();
  await ready();
  assert.equal(await page.evaluate(() => window.procfit.state.photos.length), 0);
});

test('no console errors, no page errors, no request outside the origin', () => {
  assert.deepEqual(log.pageErrors, []);
  assert.deepEqual(log.consoleErrors, []);
  const origin = new URL(server.url).origin;
  assert.deepEqual(log.requests.filter((u) => !u.startsWith(origin) && !u.startsWith('data:') && !u.startsWith('blob:')), []);
});
