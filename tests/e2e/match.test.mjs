// Honest results (issue 16): after a fit the page says how well the fitted model matches each
// photo (its photo-view IoU, computed by the core as the CLI prints it) and, when a photo is
// below the stated level, says plainly that the model does not match and what to do. A cup
// sample fitted as a dish is a match; a flat ring fitted as a dish cannot be, whatever
// the fit does, so the page must say so.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { startServer, launchBrowser, openPage, screenshot } from './harness.mjs';

let server;
let browser;
let page;

before(async () => {
  server = await startServer();
  browser = await launchBrowser();
  ({ page } = await openPage(browser.context, server.url));
  await page.waitForSelector('body[data-ready="true"]', { timeout: 90000 });
});

after(async () => {
  await browser?.close();
  server?.stop();
});

const messageOf = (id) => page.evaluate((id) => {
  const m = document.getElementById(id);
  return m.hidden ? '' : m.textContent;
}, id);

/** Fits the photos as they are at `effort` (the quick one by default); resolves when the
 * page is at rest. */
async function fitPhotos(effort = '0.25') {
  await page.evaluate(() => delete document.body.dataset.fitted);
  await page.selectOption('#fit-quality', effort);
  await page.waitForSelector('#fit-start:not([disabled])', { timeout: 60000 });
  await page.click('#fit-start');
  await page.waitForFunction(() => document.body.dataset.fitted, null, { timeout: 180000 });
  assert.equal(await page.evaluate(() => document.body.dataset.fitted), 'done', await messageOf('fit-message'));
}

/** The numbers in the match message. */
const numbersOf = (text) => [...text.matchAll(/\b[01]\.\d\d\b/g)].map((m) => Number(m[0]));

/**
 * A PNG, `width` × `height`, of a dark shape on a light wall: one path of ellipses, each
 * `[cx, cy, rx, ry, anticlockwise]` (an anticlockwise one inside a clockwise one cuts a hole).
 */
const drawnPhoto = (width, height, ellipses) => page.evaluate(async ({ width, height, ellipses }) => {
  const c = new OffscreenCanvas(width, height);
  const ctx = c.getContext('2d');
  ctx.fillStyle = '#e8e4dc';
  ctx.fillRect(0, 0, width, height);
  ctx.fillStyle = '#3a3f66';
  ctx.beginPath();
  for (const [x, y, rx, ry, ccw] of ellipses) ctx.ellipse(x, y, rx, ry, 0, 0, 2 * Math.PI, ccw);
  ctx.fill();
  const blob = await c.convertToBlob({ type: 'image/png' });
  return [...new Uint8Array(await blob.arrayBuffer())];
}, { width, height, ellipses });

const waitForMask = () =>
  page.waitForFunction(() => /Object found|check the mask/.test(document.getElementById('mask-state').textContent), null, { timeout: 60000 });

test('a cup fitted as a dish is said to match its photo, with the number', async () => {
  await page.click('button[data-sample="mug"]');
  await waitForMask();
  await page.check('#gen-dish');
  assert.equal(await messageOf('fit-match'), '', 'nothing is said before a fit');
  await fitPhotos();
  const said = await messageOf('fit-match');
  assert.match(said, /How well the fitted model matches the photo/);
  const [iou] = numbersOf(said);
  assert.ok(iou >= 0.85 && iou <= 1, `photo-view IoU ${iou} in: ${said}`);
  assert.equal(await page.getAttribute('#fit-match', 'data-match'), 'good', said);
  assert.doesNotMatch(said, /does not match/);
  // The number is the shown model's: it opens at the detail the fit ended at and measured it.
  assert.equal(await page.inputValue('#lod'), '2', 'a fitted dish opens at HIGH detail');
  // What one photo of a mug cannot tell (the core's `one_view_caveat`), said after the numbers.
  assert.match(said, /One photo cannot tell a handle turned towards the camera from a shorter one/);
  assert.equal(await page.getAttribute('#fit-match', 'data-caveat'), 'one-view', said);
  await screenshot(page, '15-match-good');
  await page.click('#thumbs li:last-child .remove');
});

test('an object the dish cannot be is said not to match, with what to do', async () => {
  // A flat ring (a quoit) seen face on, dark on a light wall: a dish's outline has no hole
  // this large, so no cup, bowl or glass matches it, whatever the fit does.
  const png = await drawnPhoto(640, 480, [[320, 240, 170, 170, false], [320, 240, 115, 115, true]]);
  await page.setInputFiles('#file', { name: 'ring.png', mimeType: 'image/png', buffer: Buffer.from(png) });
  await waitForMask();
  await page.check('#gen-dish');
  await fitPhotos();
  const said = await messageOf('fit-match');
  const [iou] = numbersOf(said);
  assert.ok(iou < 0.85, `photo-view IoU ${iou} in: ${said}`);
  assert.equal(await page.getAttribute('#fit-match', 'data-match'), 'poor', said);
  assert.match(said, /does not match/);
  assert.match(said, /check the mask/);
  assert.match(said, /another kind of object/);
  assert.equal(await page.getAttribute('#fit-match', 'data-kind'), 'warn');
  await screenshot(page, '15-match-poor');
});

test('a building fit that cannot outline the photo tries other shapes, then says it does not match', async () => {
  // A round tower seen as a disc, dark on a light wall: no box or L outlines it at the
  // building's level (0.97), so the six runs' best is not kept as it is: the core adds two
  // runs from L footprints (the page's progress says so), and then says it does not match.
  const png = await drawnPhoto(400, 400, [[200, 200, 100, 120, false]]);
  await page.click('#thumbs li:last-child .remove');
  await page.setInputFiles('#file', { name: 'disc.png', mimeType: 'image/png', buffer: Buffer.from(png) });
  await waitForMask();
  await page.check('#gen-building');
  await fitPhotos('1');
  const stage = await page.evaluate(() => document.getElementById('fit-stage').textContent);
  assert.match(stage, /best of 8 fits run side by side, 2 added from other shapes because the best did not match the photo/);
  const said = await messageOf('fit-match');
  const [iou] = numbersOf(said);
  assert.ok(iou < 0.97, `photo-view IoU ${iou} in: ${said}`);
  assert.equal(await page.getAttribute('#fit-match', 'data-match'), 'poor', said);
  assert.match(said, /does not match/);
  await screenshot(page, '15-match-rescue');
});

test('a fit the photo does not fix says so under the match, with what to do', async () => {
  // The core's verdict (`FitSession::result`'s `agreement_warning`, tested natively on the
  // building benchmark and through the CLI) as the page shows it: whether an input is flagged
  // depends on where six runs land, so the display is driven here with a result of each kind.
  const shown = await page.evaluate(async () => {
    const { showMatch } = await import('./www/fit-step.js');
    const m = document.getElementById('fit-match');
    const read = () => ({ text: m.hidden ? '' : m.textContent, match: m.dataset.match, agreement: m.dataset.agreement, kind: m.dataset.kind });
    const warning = 'the photo does not fix the shape: other fits match it about as well but differ in 3D (agreement 0.63 < 0.85), so what it does not show (depth, the far side, the roof) is a guess: add a photo from another side, or check the sliders';
    showMatch({ photo_ious: [0.986], match_level: 0.85, match_warning: null, agreement: 0.634, agreement_warning: warning });
    const ambiguous = read();
    showMatch({ photo_ious: [0.986], match_level: 0.85, match_warning: null, agreement: 0.97, agreement_warning: null });
    const fixed = read();
    showMatch({});
    return { ambiguous, fixed };
  });
  assert.match(shown.ambiguous.text, /That is a match/);
  assert.match(shown.ambiguous.text, /The photo does not fix the shape/);
  assert.match(shown.ambiguous.text, /add a photo from another side/);
  assert.equal(shown.ambiguous.match, 'good');
  assert.equal(shown.ambiguous.agreement, 'ambiguous');
  assert.equal(shown.ambiguous.kind, 'warn');
  assert.doesNotMatch(shown.fixed.text, /does not fix/);
  assert.equal(shown.fixed.agreement, '');
  assert.equal(shown.fixed.kind, 'info');
});

test('windows the fit left out are said under the match, with what to do', async () => {
  // The core's note (`FitSession::result`'s `windows_note`, tested natively in
  // tests/reconstruct_windows.rs): a building fit with "Find windows" keeps a run of the
  // outline alone when the runs fitted to the windows match the outline less well.
  const shown = await page.evaluate(async () => {
    const { showMatch } = await import('./www/fit-step.js');
    const m = document.getElementById('fit-match');
    const read = () => ({ text: m.hidden ? '' : m.textContent, windows: m.dataset.windows, kind: m.dataset.kind });
    const note = 'the windows found were left out: the model fitted to them matched the outline less well (IoU 0.977 against 0.989 without them), so the floors and window columns are the outline\'s guess: check the windows (each should cover a window of the building and nothing else), or add a photo';
    showMatch({ photo_ious: [0.989], match_level: 0.97, match_warning: null, windows_note: note });
    const leftOut = read();
    showMatch({ photo_ious: [0.989], match_level: 0.97, match_warning: null, windows_note: null });
    const used = read();
    showMatch({});
    return { leftOut, used };
  });
  assert.match(shown.leftOut.text, /That is a match/);
  assert.match(shown.leftOut.text, /The windows found were left out/);
  assert.match(shown.leftOut.text, /check the windows/);
  assert.equal(shown.leftOut.windows, 'left-out');
  assert.equal(shown.leftOut.kind, 'warn');
  assert.doesNotMatch(shown.used.text, /left out/);
  assert.equal(shown.used.windows, '');
  assert.equal(shown.used.kind, 'info');
});
