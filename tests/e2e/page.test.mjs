// The page as a person uses it, in a real browser: open it, try a sample, see the model, move a
// slider, undo, change the detail, download the GLB (checked by the Khronos validator) and the
// params JSON, open them again; add photos by picker, drop, paste and the (fake) camera; a bad
// file gives a message and the page stays usable; nothing is requested outside the origin.
// Screenshots of each step land in test-artifacts/.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { readFileSync } from 'node:fs';
import { join } from 'node:path';
import validator from 'gltf-validator';
import { startServer, launchBrowser, openPage, screenshot, writeArtifact, ROOT, ARTIFACTS } from './harness.mjs';

let server;
let browser;
let page;
let log;

before(async () => {
  server = await startServer();
  browser = await launchBrowser();
  ({ page, log } = await openPage(browser.context, server.url));
  await page.waitForSelector('body[data-ready="true"]', { timeout: 90000 });
  await settled();
});

after(async () => {
  await browser?.close();
  server?.stop();
});

/** Waits until every scheduled model change is on screen. */
const settled = () => page.evaluate(() => window.procfit.editor.settled());

/**
 * A 32×24 grey-level fingerprint of the 3D view (read back from the WebGL canvas) and how many
 * distinct grey levels it has: enough to tell a blank canvas from a model, and one model from
 * another.
 */
function viewFingerprint() {
  return page.evaluate(() => {
    const src = document.getElementById('viewer');
    const c = new OffscreenCanvas(32, 24);
    const ctx = c.getContext('2d');
    ctx.drawImage(src, 0, 0, 32, 24);
    const px = ctx.getImageData(0, 0, 32, 24).data;
    const grey = [];
    for (let i = 0; i < px.length; i += 4) grey.push(Math.round((px[i] + px[i + 1] + px[i + 2]) / 3));
    return { grey, levels: new Set(grey).size };
  });
}

const meanAbsDiff = (a, b) => a.grey.reduce((s, v, i) => s + Math.abs(v - b.grey[i]), 0) / a.grey.length;

async function validate(bytes) {
  const report = await validator.validateBytes(new Uint8Array(bytes), {
    uri: 'download.glb',
    externalResourceFunction: (uri) => Promise.reject(new Error(`external resource ${uri}`)),
  });
  return report.issues;
}

async function downloadOf(selector) {
  const [dl] = await Promise.all([page.waitForEvent('download'), page.click(selector)]);
  return { name: dl.suggestedFilename(), bytes: readFileSync(await dl.path()) };
}

const messageOf = (id) => page.evaluate((id) => {
  const m = document.getElementById(id);
  return m.hidden ? '' : m.textContent;
}, id);

test('opening the page shows the model editor with a model in the 3D view', async () => {
  const fp = await viewFingerprint();
  assert.ok(fp.levels > 20, `the 3D view looks blank (${fp.levels} grey levels)`);
  assert.match(await page.textContent('#viewer-info'), /2 parts · [\d,]+ triangles/);
  await screenshot(page, '01-open');
});

test('a sample puts its photo in step 1 and picks its generator', async () => {
  await page.click('button[data-sample="mug"]');
  await page.waitForSelector('#photo-view:not([hidden])');
  assert.match(await page.textContent('#photo-caption'), /mug\.jpg — 640×480 px/);
  assert.equal(await page.isChecked('#gen-dish'), true);
  await settled();
  await screenshot(page, '02-sample');
});

test('the sample gets an automatic mask drawn over the photo, and a box redraws it', async () => {
  await page.waitForFunction(() => /Object found|check the mask/.test(document.getElementById('mask-state').textContent), null, { timeout: 60000 });
  const m = await page.evaluate(() => {
    const p = window.procfit.state.photos.at(-1);
    const codes = p.mask.codes;
    let obj = 0;
    for (const c of codes) if (c === 255) obj += 1;
    return { width: p.mask.width, height: p.mask.height, share: obj / codes.length, bbox: p.mask.bbox };
  });
  // The sample mug fills a known part of the frame: the mask must find an object of that size.
  assert.equal(m.width, 512);
  assert.ok(m.share > 0.05 && m.share < 0.6, `object covers ${(m.share * 100).toFixed(1)} % of the photo`);
  await screenshot(page, '02b-mask');
  // A box tool drag from corner to corner of the mask's bounding box, grown a little.
  await page.check('input[name="tool"][value="rect"]');
  const box = await page.locator('#mask-canvas').boundingBox();
  const [x0, y0, x1, y1] = m.bbox;
  const sx = box.width / m.width;
  const sy = box.height / m.height;
  await page.mouse.move(box.x + (x0 - 10) * sx, box.y + (y0 - 10) * sy);
  await page.mouse.down();
  await page.mouse.move(box.x + (x1 + 10) * sx, box.y + (y1 + 10) * sy, { steps: 4 });
  const before = await page.evaluate(() => window.procfit.state.photos.at(-1).mask.codes);
  await page.mouse.up();
  await page.waitForFunction((b) => window.procfit.state.photos.at(-1).mask.codes !== b, before);
  const share = await page.evaluate(() => {
    const codes = window.procfit.state.photos.at(-1).mask.codes;
    return codes.filter((c) => c === 255).length / codes.length;
  });
  assert.ok(Math.abs(share - m.share) < 0.05, `the box changed the object share from ${m.share} to ${share}`);
  await page.check('input[name="tool"][value="none"]');
});

test('the fit runs with progress, draws its outline, and the editor gets the fitted model', async () => {
  await page.selectOption('#fit-quality', '0.25');
  const before = await page.evaluate(() => window.procfit.editor.params.slice());
  const stages = [];
  await page.exposeFunction('recordStage', (s) => stages.push(s));
  await page.evaluate(() => window.procfit.fitter.addEventListener('progress', (e) => window.recordStage(e.detail.stage)));
  const t0 = Date.now();
  await page.click('#fit-start');
  await page.waitForFunction(() => document.body.dataset.fitted, null, { timeout: 180000 });
  const seconds = (Date.now() - t0) / 1000;
  assert.equal(await page.evaluate(() => document.body.dataset.fitted), 'done', await messageOf('fit-message'));
  assert.match(await messageOf('fit-message'), /Fitted in/);
  assert.ok(stages.includes(1) && stages.includes(3), `stages seen: ${[...new Set(stages)]}`);
  assert.equal(await page.evaluate(() => document.getElementById('fit-bar').value), 1);
  await settled();
  const after = await page.evaluate(() => window.procfit.editor.params.slice());
  assert.notDeepEqual(after, before, 'the editor did not receive the fitted parameters');
  assert.equal(await page.inputValue('#preset'), 'fitted');
  console.log(`# sample mug fit (quick): ${seconds.toFixed(1)} s`);
  // The GLB of a fitted model carries the photo's camera, and is still valid glTF.
  const bytes = Buffer.from(await page.evaluate(() => Array.from(window.procfit.editor.glb.bytes)));
  const jsonLength = bytes.readUInt32LE(12);
  const gltf = JSON.parse(bytes.subarray(20, 20 + jsonLength).toString('utf8'));
  assert.equal(gltf.cameras?.length, 1, 'the fitted GLB has no camera for the photo');
  assert.ok(gltf.nodes.some((n) => n.camera === 0 && n.name === 'photo 1'));
  const issues = await validate(bytes);
  assert.equal(issues.numErrors, 0, JSON.stringify(issues.messages.slice(0, 5)));
  await screenshot(page, '02c-fitted');

  // The fitted model is in the colours measured in the photo (issue 17): the GLB's materials
  // carry them, and "Colours from the photo" switches back to the generator's and again.
  const colors = await page.evaluate(() => window.procfit.editor.colors);
  assert.ok(colors && colors.body?.length === 3, `no part colours from the photo: ${JSON.stringify(colors)}`);
  assert.ok(await page.isVisible('#photo-colors-label'));
  assert.ok(await page.isChecked('#photo-colors'));
  const near = (a, b) => a.every((v, i) => Math.abs(v - b[i]) < 1e-6);
  assert.ok(near(bodyColour(bytes), colors.body), `${bodyColour(bytes)} vs ${colors.body}`);
  await page.uncheck('#photo-colors');
  await settled();
  const plain = bodyColour(Buffer.from(await page.evaluate(() => Array.from(window.procfit.editor.glb.bytes))));
  assert.ok(!near(plain, colors.body), 'the toggle did not restore the default colours');
  await page.check('#photo-colors');
  await settled();
  const again = bodyColour(Buffer.from(await page.evaluate(() => Array.from(window.procfit.editor.glb.bytes))));
  assert.ok(near(again, colors.body));
});

test('a long fit can be cancelled and keeps the best model so far', async () => {
  await page.selectOption('#fit-quality', '3');
  await page.evaluate(() => delete document.body.dataset.fitted);
  await page.click('#fit-start');
  await page.waitForFunction(() => document.getElementById('fit-bar').value > 0, null, { timeout: 60000 });
  await page.click('#fit-cancel');
  await page.waitForFunction(() => document.body.dataset.fitted, null, { timeout: 60000 });
  assert.equal(await page.evaluate(() => document.body.dataset.fitted), 'cancelled');
  assert.match(await messageOf('fit-message'), /Stopped after/);
  assert.equal(await page.isHidden('#fit-cancel'), true);
  await page.selectOption('#fit-quality', '1');
  await page.selectOption('#preset', 'mug');
  await settled();
});

test('multi-view: a second photo of the mug by the file picker, and the fit uses both', async () => {
  const side = readFileSync(join(ROOT, 'www', 'samples', 'mug-side.jpg'));
  await page.setInputFiles('#file', { name: 'mug from the side.jpg', mimeType: 'image/jpeg', buffer: side });
  await page.waitForFunction(() => window.procfit.state.photos.length === 2 && window.procfit.state.photos.every((p) => p.mask));
  await page.selectOption('#fit-quality', '0.25');
  await page.evaluate(() => delete document.body.dataset.fitted);
  await page.click('#fit-start');
  await page.waitForFunction(() => document.body.dataset.fitted, null, { timeout: 180000 });
  assert.equal(await page.evaluate(() => document.body.dataset.fitted), 'done', await messageOf('fit-message'));
  await settled();
  const bytes = Buffer.from(await page.evaluate(() => Array.from(window.procfit.editor.glb.bytes)));
  const gltf = JSON.parse(bytes.subarray(20, 20 + bytes.readUInt32LE(12)).toString('utf8'));
  assert.equal(gltf.cameras?.length, 2, 'a two-photo fit should export two cameras');
  await screenshot(page, '02d-two-views');
  await page.click('#thumbs li:last-child .remove');
  await page.selectOption('#fit-quality', '1');
  await page.selectOption('#preset', 'mug');
  await settled();
});

/**
 * `jpeg` with an EXIF block (APP1, after the JFIF APP0) whose only tag is FocalLengthIn35mmFilm
 * = `mm`: a little-endian TIFF header, IFD0 pointing at the Exif IFD, which holds tag 0xA405.
 */
function withExifFocal(jpeg, mm) {
  const tiff = Buffer.alloc(44);
  tiff.write('II', 0, 'latin1');
  tiff.writeUInt16LE(42, 2);
  tiff.writeUInt32LE(8, 4); // IFD0
  tiff.writeUInt16LE(1, 8);
  tiff.writeUInt16LE(0x8769, 10); // ExifIFDPointer, LONG × 1 → 26
  tiff.writeUInt16LE(4, 12);
  tiff.writeUInt32LE(1, 14);
  tiff.writeUInt32LE(26, 18);
  tiff.writeUInt32LE(0, 22);
  tiff.writeUInt16LE(1, 26);
  tiff.writeUInt16LE(0xa405, 28); // FocalLengthIn35mmFilm, SHORT × 1
  tiff.writeUInt16LE(3, 30);
  tiff.writeUInt32LE(1, 32);
  tiff.writeUInt16LE(mm, 36);
  tiff.writeUInt32LE(0, 40);
  const body = Buffer.concat([Buffer.from('Exif\0\0', 'latin1'), tiff]);
  const head = Buffer.from([0xff, 0xe1, 0, 0]);
  head.writeUInt16BE(body.length + 2, 2);
  assert.deepEqual([...jpeg.subarray(0, 4)], [0xff, 0xd8, 0xff, 0xe0], 'expected a JFIF JPEG');
  const app0End = 4 + jpeg.readUInt16BE(4);
  return Buffer.concat([jpeg.subarray(0, app0End), head, body, jpeg.subarray(app0End)]);
}

test('a photo with an EXIF focal length shows it, and the fit uses its field of view', async () => {
  const side = withExifFocal(readFileSync(join(ROOT, 'www', 'samples', 'mug-side.jpg')), 28);
  await page.setInputFiles('#file', { name: 'mug at 28 mm.jpg', mimeType: 'image/jpeg', buffer: side });
  await page.waitForFunction(() => window.procfit.state.photos.length === 2 && window.procfit.state.photos.every((p) => p.mask));
  const focals = await page.evaluate(() => window.procfit.state.photos.map((p) => p.focal35mm));
  assert.deepEqual(focals, [null, 28], 'the sample has no EXIF; the built JPEG says 28 mm');
  assert.match(await page.textContent('#photo-caption'), /fov from EXIF: 28 mm/);
  // The fit's cameras carry the field of view each view was fitted with (yfov first of 18).
  await page.selectOption('#fit-quality', '0.25');
  await page.evaluate(() => delete document.body.dataset.fitted);
  await page.click('#fit-start');
  await page.waitForFunction(() => document.body.dataset.fitted, null, { timeout: 180000 });
  assert.equal(await page.evaluate(() => document.body.dataset.fitted), 'done', await messageOf('fit-message'));
  await settled();
  const yfov = await page.evaluate(() => [window.procfit.editor.cameras[0], window.procfit.editor.cameras[18]]);
  // 28 mm on a 4:3 landscape photo: half the diagonal of 36 × 24 over the focal length, scaled
  // to the vertical side (3 of the diagonal's 5).
  const want = 2 * Math.atan((Math.hypot(36, 24) / 2 / 28) * (3 / 5));
  assert.ok(Math.abs(yfov[1] - want) < 1e-4, `view 2's yfov ${yfov[1]} ≠ ${want} from 28 mm`);
  // View 1 has no EXIF: the core's DEFAULT_FOV_Y (reconstruct::views).
  assert.ok(Math.abs(yfov[0] - 2 * Math.atan(12 / 50)) < 1e-6, `view 1's yfov ${yfov[0]} is not the default`);
  await page.click('#thumbs li:last-child .remove');
  await page.selectOption('#fit-quality', '1');
  await page.selectOption('#preset', 'mug');
  await settled();
});

test('"Refit from here" fits again starting from the sliders', async () => {
  // The model as a person left it: one slider moved by hand.
  await page.focus('#param-y_scale');
  await page.keyboard.press('ArrowUp');
  await settled();
  const sliders = await page.evaluate(() => window.procfit.editor.params.slice());
  const generator = await page.evaluate(() => window.procfit.editor.spec.name);
  // Record what the page asks the worker for.
  await page.evaluate(() => {
    const client = window.procfit.client;
    const call = client.call.bind(client);
    window.fitRequests = [];
    client.call = (type, payload, opts) => {
      if (type === window.procfit.REQUESTS.FIT_RUN) window.fitRequests.push({ generator: payload.generator, start: payload.start });
      return call(type, payload, opts);
    };
  });
  await page.selectOption('#fit-quality', '0.25');
  await page.evaluate(() => delete document.body.dataset.fitted);
  assert.equal(await page.isDisabled('#refit'), false);
  await page.click('#refit');
  await page.waitForFunction(() => document.body.dataset.fitted, null, { timeout: 180000 });
  assert.equal(await page.evaluate(() => document.body.dataset.fitted), 'done', await messageOf('fit-message'));
  const reqs = await page.evaluate(() => window.fitRequests);
  assert.deepEqual(reqs, [{ generator, start: sliders }]);
  await settled();
  const after = await page.evaluate(() => window.procfit.editor.params.slice());
  assert.notDeepEqual(after, sliders, 'the refit did not hand a model to the editor');
  assert.equal(await page.inputValue('#preset'), 'fitted');
  await page.selectOption('#fit-quality', '1');
  await page.selectOption('#preset', 'mug');
  await settled();
});

test('a slider moved from the keyboard changes the mesh, the view and the GLB; undo/redo restore it', async () => {
  const before = await viewFingerprint();
  const glbBefore = await page.evaluate(() => window.procfit.editor.glb.bytes.length);
  const heightBefore = await page.evaluate(() => window.procfit.editor.params[9]);
  await page.focus('#param-y_scale');
  await page.keyboard.press('Home');
  await settled();
  const heightAfter = await page.evaluate(() => window.procfit.editor.params[9]);
  assert.equal(heightAfter, 0.1, 'Home should take the height slider to its minimum');
  const after = await viewFingerprint();
  const diff = meanAbsDiff(before, after);
  assert.ok(diff > 2, `the 3D view barely changed (mean grey difference ${diff.toFixed(2)})`);
  const info = await page.evaluate(() => ({
    glb: window.procfit.editor.glb,
    latency: window.procfit.editor.latencies.at(-1),
    timing: window.procfit.editor.timings.at(-1),
  }));
  console.log(`# timing ${JSON.stringify(info.timing)}`);
  assert.equal(info.glb.params[9], 0.1, 'the GLB shown is not the one for the new params');
  assert.ok(info.latency > 0, 'no slider-to-frame latency was measured');
  console.log(`# slider → new frame: ${info.latency.toFixed(1)} ms incl. the DevTools key dispatch (MEDIUM, ${glbBefore} → ${info.glb.bytes.length} bytes)`);
  await screenshot(page, '03-slider');

  await page.click('#undo');
  await settled();
  assert.equal(await page.evaluate(() => window.procfit.editor.params[9]), heightBefore);
  // The range shows the value snapped to its step (0.001 for the height).
  assert.ok(Math.abs(Number(await page.inputValue('#param-y_scale')) - heightBefore) <= 0.0005 + 1e-9, 'the slider did not follow undo');
  await page.keyboard.press('Control+Shift+Z');
  await settled();
  assert.equal(await page.evaluate(() => window.procfit.editor.params[9]), 0.1);
  await page.click('#reset');
  await settled();
  assert.equal(await page.evaluate(() => window.procfit.editor.params[9]), heightBefore);
});

test('the detail selector changes the triangle count', async () => {
  const tris = async () => Number((await page.textContent('#viewer-info')).match(/([\d,]+) triangles/)[1].replace(/,/g, ''));
  // A fitted model opens at the detail its fit ended at (HIGH): start from MEDIUM.
  await page.selectOption('#lod', '1');
  await settled();
  const medium = await tris();
  await page.selectOption('#lod', '0');
  await settled();
  const low = await tris();
  await page.selectOption('#lod', '2');
  await settled();
  const high = await tris();
  assert.ok(low < medium && medium < high, `triangles low ${low}, medium ${medium}, high ${high}`);
});

test('wireframe and colour-by-part change the view and show a legend', async () => {
  const plain = await viewFingerprint();
  await page.check('#wireframe');
  await page.check('#part-colors');
  await page.evaluate(() => window.procfit.viewer.nextFrame());
  const styled = await viewFingerprint();
  assert.ok(meanAbsDiff(plain, styled) > 2, 'wireframe + part colours did not change the view');
  assert.deepEqual(await page.$$eval('#legend .swatch', (s) => s.map((x) => x.textContent)), ['body', 'handle']);
  await screenshot(page, '04-wireframe-parts');
  await page.uncheck('#wireframe');
  await page.uncheck('#part-colors');
});

test('the downloaded GLB is the model shown, passes the glTF validator and opens again', async () => {
  await page.focus('#param-handle_center_y');
  await page.keyboard.press('End');
  await settled();
  const shown = await page.evaluate(() => {
    const g = window.procfit.editor.glb;
    return { params: g.params, lod: g.lod, bytes: Array.from(g.bytes) };
  });
  const glb = await downloadOf('#download-glb');
  assert.match(glb.name, /^dish-.*\.glb$/);
  assert.deepEqual(Array.from(glb.bytes), shown.bytes, 'the download is not the GLB in the view');
  const issues = await validate(glb.bytes);
  writeArtifact('download.glb', glb.bytes);
  assert.equal(issues.numErrors, 0, JSON.stringify(issues.messages.slice(0, 5)));
  console.log(`# downloaded GLB: ${glb.bytes.length} bytes, validator: ${issues.numErrors} errors, ${issues.numWarnings} warnings`);

  const json = await downloadOf('#download-json');
  assert.match(json.name, /\.json$/);
  const doc = JSON.parse(json.bytes.toString('utf8'));
  assert.equal(doc.generator, 'dish');
  assert.equal(doc.params.handle_center_y, 0.7);
  // The photo's colours go with the model into the params JSON too.
  assert.deepEqual(Object.keys(doc.colors ?? {}).includes('body'), true, JSON.stringify(doc.colors));
  const savedColors = await page.evaluate(() => window.procfit.editor.colors);

  // Change the model, then open the saved GLB: the editor comes back to the saved state.
  await page.selectOption('#preset', 'bowl');
  await settled();
  await page.setInputFiles('#open-model', { name: 'saved.glb', mimeType: 'model/gltf-binary', buffer: glb.bytes });
  await openedMessage('saved.glb');
  assert.deepEqual(await page.evaluate(() => window.procfit.editor.params), shown.params);
  assert.deepEqual(await page.evaluate(() => window.procfit.editor.colors), savedColors);
  assert.match(await messageOf('out-message'), /Opened “saved\.glb”/);

  // And the JSON, after another change.
  await page.selectOption('#preset', 'vase');
  await settled();
  await page.setInputFiles('#open-model', { name: 'saved.json', mimeType: 'application/json', buffer: json.bytes });
  await openedMessage('saved.json');
  assert.deepEqual(await page.evaluate(() => window.procfit.editor.params), shown.params);
});

/** The base colour (RGB) of the `body` part's material in a GLB. */
function bodyColour(bytes) {
  const jsonLength = bytes.readUInt32LE(12);
  const gltf = JSON.parse(bytes.subarray(20, 20 + jsonLength).toString('utf8'));
  const material = gltf.materials.find((m) => m.name === 'body');
  return material.pbrMetallicRoughness.baseColorFactor.slice(0, 3);
}

/** Waits for the page to say it opened `name`, then for the model to be on screen. */
async function openedMessage(name) {
  await page.waitForFunction((n) => document.getElementById('out-message').textContent.includes(`Opened “${n}”`), name);
  await settled();
}

test('files that are not procfit models are refused with a message', async () => {
  const check = async (name, mimeType, text, pattern) => {
    await page.setInputFiles('#open-model', { name, mimeType, buffer: Buffer.from(text) });
    await page.waitForFunction((n) => document.getElementById('out-message').textContent.includes(`Could not open “${n}”`), name);
    assert.match(await messageOf('out-message'), pattern);
  };
  await check('other.json', 'application/json', '{"hello": 1}', /Could not open “other\.json”/);
  await check('bad.glb', 'model/gltf-binary', 'glTF-but-not-really', /Could not open “bad\.glb”: (malformed|unsupported)/);
  await check('unknown.json', 'application/json', '{"generator":"teapot","version":1,"params":{}}', /unknown generator `teapot`/);
});

test('a photo by the file picker, a bad file, a drop and a paste', async () => {
  const mug = readFileSync(join(ROOT, 'www', 'samples', 'mug.jpg'));
  const count = () => page.$$eval('#thumbs li', (l) => l.length);
  const n0 = await count();
  await page.setInputFiles('#file', { name: 'my cup.jpg', mimeType: 'image/jpeg', buffer: mug });
  await page.waitForFunction((n) => document.querySelectorAll('#thumbs li').length === n + 1, n0);

  await page.setInputFiles('#file', { name: 'notes.txt', mimeType: 'text/plain', buffer: Buffer.from('not a photo') });
  await page.waitForSelector('#photos-message:not([hidden])');
  assert.match(await messageOf('photos-message'), /“notes\.txt” is not a photo/);
  await page.setInputFiles('#file', { name: 'broken.jpg', mimeType: 'image/jpeg', buffer: Buffer.from('not really a jpeg') });
  await page.waitForFunction(() => /could not be read as an image/.test(document.getElementById('photos-message').textContent));
  await screenshot(page, '05-bad-file');
  assert.equal(await count(), n0 + 1, 'a bad file was added as a photo');

  // Drop onto the page (anywhere) and paste: a second and third view.
  const b64 = mug.toString('base64');
  await page.evaluate(async (b64) => {
    const bytes = Uint8Array.from(atob(b64), (c) => c.charCodeAt(0));
    const file = new File([bytes], 'dropped.jpg', { type: 'image/jpeg' });
    const dt = new DataTransfer();
    dt.items.add(file);
    document.querySelector('footer').dispatchEvent(new DragEvent('drop', { dataTransfer: dt, bubbles: true, cancelable: true }));
  }, b64);
  await page.waitForFunction((n) => document.querySelectorAll('#thumbs li').length === n + 2, n0);
  await page.evaluate(async (b64) => {
    const bytes = Uint8Array.from(atob(b64), (c) => c.charCodeAt(0));
    const dt = new DataTransfer();
    dt.items.add(new File([bytes], 'image.png', { type: 'image/jpeg' }));
    document.body.dispatchEvent(new ClipboardEvent('paste', { clipboardData: dt, bubbles: true, cancelable: true }));
  }, b64);
  await page.waitForFunction((n) => document.querySelectorAll('#thumbs li').length === n + 3, n0);
  assert.match(await page.textContent('#photo-caption'), /photo \d+ of \d+/);
  assert.equal(await messageOf('photos-message'), '', 'a good photo should clear the old message');

  // Remove one: the list shrinks and the page still works.
  await page.click('#thumbs li:last-child .remove');
  assert.equal(await count(), n0 + 2);
  await screenshot(page, '06-photos');
});

test('a photo with no object gets a message, and so does a fit that cannot work', async () => {
  // A plain grey picture: nothing to cut out.
  await page.evaluate(async () => {
    const c = new OffscreenCanvas(320, 240);
    const ctx = c.getContext('2d');
    ctx.fillStyle = '#808080';
    ctx.fillRect(0, 0, 320, 240);
    const blob = await c.convertToBlob({ type: 'image/png' });
    const dt = new DataTransfer();
    dt.items.add(new File([blob], 'plain wall.png', { type: 'image/png' }));
    document.body.dispatchEvent(new DragEvent('drop', { dataTransfer: dt, bubbles: true, cancelable: true }));
  });
  await page.waitForFunction(() => /No object found|check the mask/i.test(document.getElementById('mask-state').textContent), null, { timeout: 60000 });
  const text = await page.textContent('#mask-state');
  assert.doesNotMatch(text, /^Object found/);
  await screenshot(page, '05b-no-object');
  // Fitting the plain photo alone fails with a message; the page stays usable.
  const count = await page.evaluate(() => window.procfit.state.photos.length);
  for (let i = 0; i < count - 1; i += 1) await page.click('#thumbs li:first-child .remove');
  await page.waitForFunction(() => window.procfit.state.photos.length === 1);
  await page.selectOption('#fit-quality', '0.25');
  await page.evaluate(() => delete document.body.dataset.fitted);
  await page.click('#fit-start');
  await page.waitForFunction(() => document.body.dataset.fitted, null, { timeout: 120000 });
  assert.equal(await page.evaluate(() => document.body.dataset.fitted), 'failed');
  assert.match(await messageOf('fit-message'), /The fit failed: .+/);
  await screenshot(page, '05c-fit-failed');
  await page.selectOption('#fit-quality', '1');
});

test('the camera (fake device) takes several shots', async () => {
  const n0 = await page.$$eval('#thumbs li', (l) => l.length);
  await page.click('#camera-open');
  await page.waitForSelector('dialog#camera[open]');
  await page.waitForFunction(() => document.querySelector('dialog#camera video').videoWidth > 0);
  await screenshot(page, '07-camera');
  await page.click('#camera-shoot');
  await page.click('#camera-shoot');
  await page.waitForFunction(() => /2 shots taken/.test(document.querySelector('dialog#camera [role=status]').textContent));
  await page.click('#camera-done');
  await page.waitForFunction((n) => document.querySelectorAll('#thumbs li').length === n + 2, n0);
  assert.equal(await page.evaluate(() => document.querySelector('dialog#camera').open), false);
  // The camera is released when the dialog closes.
  assert.equal(await page.evaluate(() => document.querySelector('dialog#camera video').srcObject), null);
  assert.equal(await page.evaluate(() => window.procfit.lastCameraTracks?.every((t) => t.readyState === 'ended')), true);
});

test('the photo limit holds on every path in, with one message', async () => {
  const n0 = await page.$$eval('#thumbs li', (l) => l.length);
  const mug = readFileSync(join(ROOT, 'www', 'samples', 'mug.jpg'));
  const extra = 8 - n0 + 2;
  const files = Array.from({ length: extra }, (_, k) => ({ name: `cup ${k + 1}.jpg`, mimeType: 'image/jpeg', buffer: mug }));
  await page.setInputFiles('#file', files);
  await page.waitForFunction(() => /takes up to 8 photos/.test(document.getElementById('photos-message').textContent), null, { timeout: 60000 });
  assert.equal(await page.$$eval('#thumbs li', (l) => l.length), 8);
  const said = await page.textContent('#photos-message');
  assert.equal(said.match(/takes up to 8 photos/g).length, 1, said);
  assert.match(said, /2 photos were not added/);
  // A sample is one more photo: refused the same way, not added as a ninth.
  await page.click('button[data-sample="mug"]');
  await page.waitForFunction(() => /takes up to 8 photos/.test(document.getElementById('photos-message').textContent));
  assert.equal(await page.$$eval('#thumbs li', (l) => l.length), 8);
  // Back to where the other tests left it.
  while ((await page.$$eval('#thumbs li', (l) => l.length)) > n0) {
    await page.click('#thumbs li:last-child button.remove');
  }
});

test('every control is reachable by keyboard and has a label', async () => {
  const unlabeled = await page.evaluate(() =>
    [...document.querySelectorAll('input, select, button, canvas[tabindex]')]
      .filter((e) => !e.closest('[hidden]') && !e.closest('dialog:not([open])'))
      .filter((e) => {
        const name = e.getAttribute('aria-label') || (e.labels && [...e.labels].map((l) => l.textContent).join('')) || e.textContent;
        return !name || !name.trim();
      })
      .map((e) => e.outerHTML.slice(0, 80)),
  );
  assert.deepEqual(unlabeled, []);
  // Tab from the top reaches the file picker, the camera, the generator, the viewer and download.
  await page.focus('a.skip');
  const seen = new Set();
  for (let i = 0; i < 80; i += 1) {
    await page.keyboard.press('Tab');
    seen.add(await page.evaluate(() => document.activeElement?.id || ''));
  }
  for (const id of ['file', 'camera-open', 'gen-dish', 'preset', 'viewer', 'wireframe', 'lod']) {
    assert.ok(seen.has(id), `Tab never reached #${id}: ${[...seen].join(', ')}`);
  }
});

test('on a phone in portrait the page fits the width', async () => {
  const phone = await browser.context.newPage();
  await phone.setViewportSize({ width: 390, height: 844 });
  await phone.goto(server.url);
  await phone.waitForSelector('body[data-ready="true"]', { timeout: 90000 });
  await phone.evaluate(() => window.procfit.editor.settled());
  const overflow = await phone.evaluate(() => document.documentElement.scrollWidth - window.innerWidth);
  assert.ok(overflow <= 0, `the page is ${overflow}px wider than the phone`);
  await screenshot(phone, '08-phone');
  // The camera fills the phone's screen, its buttons within reach.
  await phone.click('#camera-open');
  await phone.waitForFunction(() => document.querySelector('dialog#camera video').videoWidth > 0);
  const shutter = await phone.locator('#camera-shoot').boundingBox();
  assert.ok(shutter && shutter.y + shutter.height <= 844, 'the shutter is off the phone screen');
  await phone.screenshot({ path: `${ARTIFACTS}/08b-phone-camera.png` });
  await phone.click('#camera-done');
  await phone.close();
});

test('no console errors, no page errors, no request outside the origin', () => {
  assert.deepEqual(log.pageErrors, []);
  assert.deepEqual(log.consoleErrors, []);
  const origin = new URL(server.url).origin;
  const outside = log.requests.filter((u) => !u.startsWith(origin) && !u.startsWith('data:') && !u.startsWith('blob:'));
  assert.deepEqual(outside, []);
});
