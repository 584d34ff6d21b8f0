// Trees in the page: on the bundled tree sample (an oak rendered by procfit itself, bark brown
// and leaf green; see scripts/make-samples.mjs), the mask step shows what the tree fit sees
// (branches brown, leaves green), the tree fit runs with progress and can be cancelled, and its
// tree lands in the viewer with its sliders and downloads as a valid GLB; "Refit from here"
// refits the edited tree from where it is.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { readFileSync } from 'node:fs';
import { join } from 'node:path';
import validator from 'gltf-validator';
import { startServer, launchBrowser, openPage, screenshot, ARTIFACTS } from './harness.mjs';

let server;
let browser;
let page;
let log;

const settled = () => page.evaluate(() => window.procfit.editor.settled());
const messageOf = (id) => page.evaluate((id) => {
  const m = document.getElementById(id);
  return m.hidden ? '' : m.textContent;
}, id);

before(async () => {
  server = await startServer();
  browser = await launchBrowser();
  ({ page, log } = await openPage(browser.context, server.url));
  await page.waitForSelector('body[data-ready="true"]', { timeout: 90000 });
});

after(async () => {
  await browser?.close();
  server?.stop();
});

test('the tree sample shows its branch and leaf labels over the photo', async () => {
  await page.click('button[data-sample="oak"]');
  await page.waitForFunction(() => /Object found|check the mask/.test(document.getElementById('mask-state').textContent), null, { timeout: 60000 });
  assert.equal(await page.isChecked('#gen-tree'), true);
  assert.equal(await page.isDisabled('#gen-tree'), false);
  await page.waitForFunction(() => /What the tree fit sees/.test(document.getElementById('tree-state').textContent), null, { timeout: 30000 });
  const text = await page.textContent('#tree-state');
  const [, branch, leaf] = text.match(/branches in brown \((\d+) %\), leaves in green \((\d+) %\)/).map(Number);
  assert.ok(leaf >= 30 && branch >= 1, `branch ${branch} %, leaf ${leaf} %`);
  // The overlay shows them: green and brown pixels.
  const tints = await page.evaluate(() => {
    const c = document.getElementById('mask-canvas');
    const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
    let green = 0;
    let brown = 0;
    for (let i = 0; i < d.length; i += 4) {
      // The overlay's leaf and branch tints (masking.js), read back with rounding.
      if (Math.abs(d[i] - 40) < 6 && Math.abs(d[i + 1] - 200) < 6 && Math.abs(d[i + 2] - 60) < 6) green += 1;
      if (Math.abs(d[i] - 150) < 6 && Math.abs(d[i + 1] - 90) < 6 && Math.abs(d[i + 2] - 40) < 6) brown += 1;
    }
    return { green, brown };
  });
  await page.locator('#photo-view').screenshot({ path: join(ARTIFACTS, '11-tree-labels-photo.png') });
  await screenshot(page, '11-tree-labels');
  assert.ok(tints.green > 1000 && tints.brown > 20, JSON.stringify(tints));
  // Not a building: no windows tools.
  assert.equal(await page.isHidden('#window-tools'), true);
});

test('the colours that sort leaves from branches can be adjusted', async () => {
  const shares = async () => {
    await page.waitForFunction(() => /What the tree fit sees/.test(document.getElementById('tree-state').textContent), null, { timeout: 30000 });
    const text = await page.textContent('#tree-state');
    const [, branch, leaf] = text.match(/branches in brown \((\d+) %\), leaves in green \((\d+) %\)/).map(Number);
    return { branch, leaf, text };
  };
  const slide = (id, value) => page.evaluate(([id, value]) => {
    const input = document.getElementById(id);
    input.value = String(value);
    input.dispatchEvent(new Event('input', { bubbles: true }));
  }, [id, value]);
  const start = await shares();
  assert.equal(await page.isHidden('#tree-colors'), false);
  await page.click('#tree-colors summary');
  // Leaves only blue to purple: the oak's green leaves are not leaves any more.
  await slide('leaf-hue-from', 200);
  await slide('leaf-hue-to', 300);
  await page.waitForFunction(() => /No leaves found/.test(document.getElementById('tree-state').textContent), null, { timeout: 30000 });
  assert.equal((await shares()).leaf, 0);
  assert.equal(await page.textContent('#leaf-hue-from-out'), '200°');
  await page.locator('#tree-colors').screenshot({ path: join(ARTIFACTS, '11a-tree-colours.png') });
  // Autumn leaves (a hue range through red to green) keep the green ones too.
  await page.click('#colors-autumn');
  await page.waitForFunction(() => !/No leaves found/.test(document.getElementById('tree-state').textContent) && /What the tree fit sees/.test(document.getElementById('tree-state').textContent), null, { timeout: 30000 });
  assert.ok((await shares()).leaf >= 30, (await shares()).text);
  // Everything else inside the mask as branches: more branch, never less.
  await page.click('#colors-reset');
  await page.waitForFunction((leaf) => new RegExp(`leaves in green \\(${leaf} %\\)`).test(document.getElementById('tree-state').textContent), start.leaf, { timeout: 30000 });
  assert.deepEqual(await shares().then(({ branch, leaf }) => ({ branch, leaf })), { branch: start.branch, leaf: start.leaf });
  await page.check('#rest-as-branch');
  await page.waitForFunction(() => /What the tree fit sees/.test(document.getElementById('tree-state').textContent), null, { timeout: 30000 });
  await page.waitForFunction(() => document.getElementById('rest-as-branch').checked);
  const rest = await shares();
  assert.ok(rest.branch >= start.branch, `${rest.branch} < ${start.branch}`);
  await page.click('#colors-reset');
  await page.waitForFunction((leaf) => new RegExp(`leaves in green \\(${leaf} %\\)`).test(document.getElementById('tree-state').textContent), start.leaf, { timeout: 30000 });
  assert.equal(await page.isChecked('#rest-as-branch'), false);
  await page.click('#tree-colors summary');
});

test('the tree fit runs with progress and puts its tree in the viewer', async () => {
  const stages = [];
  await page.exposeFunction('recordTreeStage', (s) => stages.push(s));
  await page.evaluate(() => window.procfit.fitter.addEventListener('progress', (e) => window.recordTreeStage(e.detail.stage)));
  await page.selectOption('#fit-quality', '0.25');
  const before = await page.evaluate(() => window.procfit.editor.params.slice());
  const t0 = Date.now();
  await page.click('#fit-start');
  await page.waitForFunction(() => document.body.dataset.fitted, null, { timeout: 600000 });
  const seconds = (Date.now() - t0) / 1000;
  assert.equal(await page.evaluate(() => document.body.dataset.fitted), 'done', await messageOf('fit-message'));
  assert.match(await messageOf('fit-message'), /Fitted in/);
  // Issue 16: the tree's photo-view IoU is said after its fit, as for every generator.
  assert.match(await messageOf('fit-match'), /How well the fitted model matches the photo \(outline overlap, 1 = exact\): [01]\.\d\d\./);
  assert.ok(stages.includes(1), `stages seen: ${[...new Set(stages)]}`);
  assert.match(await page.textContent('#fit-preview-caption'), /Best tree so far/);
  await settled();
  const after = await page.evaluate(() => ({ generator: window.procfit.editor.spec.name, params: window.procfit.editor.params.slice() }));
  assert.equal(after.generator, 'tree');
  assert.notDeepEqual(after.params, before, 'the editor did not receive the fitted tree');
  assert.equal(await page.inputValue('#preset'), 'fitted');
  assert.ok((await page.locator('#sliders input').count()) > 5, 'the tree has no sliders');
  console.log(`# tree sample fit (quick): ${seconds.toFixed(1)} s; stages ${[...new Set(stages)].join(', ')}`);
  await screenshot(page, '11b-tree-fitted');
  await page.locator('#fit-progress').screenshot({ path: join(ARTIFACTS, '11b-tree-fit-progress.png') });
  await page.locator('#viewer').screenshot({ path: join(ARTIFACTS, '11b-tree-fitted-view.png') });
});

test('the fitted tree downloads as a valid GLB with the photo camera', async () => {
  const [dl] = await Promise.all([page.waitForEvent('download'), page.click('#download-glb')]);
  const bytes = readFileSync(await dl.path());
  assert.match(dl.suggestedFilename(), /^tree-/);
  const gltf = JSON.parse(bytes.subarray(20, 20 + bytes.readUInt32LE(12)).toString('utf8'));
  assert.equal(gltf.cameras?.length, 1, 'the fitted tree has no camera for the photo');
  const report = await validator.validateBytes(new Uint8Array(bytes), {
    uri: 'tree.glb',
    externalResourceFunction: (uri) => Promise.reject(new Error(`external resource ${uri}`)),
  });
  assert.equal(report.issues.numErrors, 0, JSON.stringify(report.issues.messages.slice(0, 5)));
  assert.equal(report.issues.numWarnings, 0, JSON.stringify(report.issues.messages.slice(0, 5)));
  // Leaves are alpha-masked cards with the leaf texture, stems carry the bark texture, both
  // embedded PNGs; their colours are the photo's leaf and branch colours (issue 17).
  assert.equal(gltf.images?.length, 2);
  assert.ok(gltf.images.every((i) => i.mimeType === 'image/png' && i.bufferView !== undefined));
  const leaf = gltf.materials.find((m) => m.name === 'leaf');
  assert.equal(leaf.alphaMode, 'MASK');
  assert.ok(leaf.pbrMetallicRoughness.baseColorTexture, 'the leaf material has no texture');
  assert.ok(gltf.materials.find((m) => m.name === 'trunk').pbrMetallicRoughness.baseColorTexture, 'the bark has no texture');
  const colors = gltf.scenes[0].extras.colors;
  assert.ok(colors?.leaf && colors?.trunk, `no colours from the photo: ${JSON.stringify(colors)}`);
  assert.deepEqual(leaf.pbrMetallicRoughness.baseColorFactor.slice(0, 3).map((v) => v.toFixed(5)), colors.leaf.map((v) => v.toFixed(5)));
  // three.js in the page decoded both textures.
  const maps = await page.evaluate(() => {
    const found = [];
    window.procfit.viewer.scene.traverse((o) => o.material?.map?.image && found.push(`${o.name}:${o.material.map.image.width}`));
    return found;
  });
  assert.ok(maps.some((m) => m.startsWith('leaf:')) && maps.some((m) => m.startsWith('trunk:')), `textures in the view: ${maps}`);
});

test('the fitted tree\'s leaves are carved by its photo, and the toggle shows them all', async () => {
  await settled();
  // On by default after a fit: the view, the download and the match message say so.
  assert.equal(await page.isVisible('#carve-leaves'), true, 'no carving toggle after a tree fit');
  assert.equal(await page.isChecked('#carve-leaves'), true);
  assert.match(await page.textContent('#viewer-info'), /carved by the photo/);
  assert.match(await messageOf('fit-match'), /Carved by the photo, pixel by pixel: [01]\.\d\d\./);
  const triangles = async () => Number((await page.textContent('#viewer-info')).match(/([\d,]+) triangles/)[1].replace(/,/g, ''));
  const carved = await triangles();
  await page.uncheck('#carve-leaves');
  await settled();
  assert.doesNotMatch(await page.textContent('#viewer-info'), /carved by the photo/);
  const whole = await triangles();
  assert.notEqual(carved, whole, 'carving changed no triangle');
  await page.check('#carve-leaves');
  await settled();
  assert.equal(await triangles(), carved);
});

test('"Refit from here" refits the edited tree: its seed stays, it never gets less like the photo', async () => {
  // The fitted tree as a person left it: one slider moved by hand.
  await settled();
  assert.equal(await page.isDisabled('#refit'), false, 'Refit from here is disabled for a fitted tree');
  const seedAt = await page.evaluate(() => window.procfit.editor.spec.params.findIndex((p) => p.name === 'seed'));
  const moved = await page.evaluate(() => window.procfit.editor.spec.params.find((p) => p.name !== 'seed' && p.kind === 'continuous')?.name ?? null);
  if (moved) {
    await page.focus(`#param-${moved}`);
    await page.keyboard.press('ArrowUp');
    await settled();
  }
  const start = await page.evaluate(() => window.procfit.editor.params.slice());
  // Record what the page asks the worker for, and what comes back.
  await page.evaluate(() => {
    const client = window.procfit.client;
    const call = client.call.bind(client);
    window.treeRuns = [];
    client.call = (type, payload, opts) => {
      const answer = call(type, payload, opts);
      if (type === window.procfit.REQUESTS.TREE_RUN) {
        const run = { start: payload.start ?? null, result: null };
        window.treeRuns.push(run);
        answer.then((out) => (run.result = out.result), () => {});
      }
      return answer;
    };
  });
  await page.selectOption('#fit-quality', '0.25');
  await page.evaluate(() => delete document.body.dataset.fitted);
  await page.click('#refit');
  await page.waitForFunction(() => document.body.dataset.fitted, null, { timeout: 600000 });
  assert.equal(await page.evaluate(() => document.body.dataset.fitted), 'done', await messageOf('fit-message'));
  const runs = await page.evaluate(() => window.treeRuns);
  assert.equal(runs.length, 1, 'the refit made no tree fit');
  assert.deepEqual(runs[0].start, start, 'the refit did not start from the sliders');
  const r = runs[0].result;
  assert.equal(r.generator, 'tree');
  assert.equal(typeof r.start_similarity, 'number', 'the refit did not evaluate its start');
  assert.ok(r.similarity >= r.start_similarity, `refit ended at ${r.similarity}, below its start ${r.start_similarity}`);
  assert.equal(r.params[seedAt], start[seedAt], "the refit changed the tree's seed");
  await settled();
  // The model stays a tree, the refit's, with its sliders.
  const after = await page.evaluate(() => ({ generator: window.procfit.editor.spec.name, params: window.procfit.editor.params.slice() }));
  assert.equal(after.generator, 'tree');
  assert.deepEqual(after.params, r.params);
  assert.equal(await page.inputValue('#preset'), 'fitted');
  assert.match(await messageOf('fit-message'), /similarity to the photo \d\.\d{3} → \d\.\d{3}|nothing closer to the photos/);
  console.log(`# tree refit (quick): similarity ${r.start_similarity.toFixed(3)} → ${r.similarity.toFixed(3)}`);
  await screenshot(page, '11c-tree-refitted');
  assert.equal(await page.isDisabled('#refit'), false);
});

test('a tree fit can be cancelled and keeps the best tree so far', async () => {
  await page.selectOption('#fit-quality', '3');
  await page.evaluate(() => delete document.body.dataset.fitted);
  await page.click('#fit-start');
  await page.waitForFunction(() => document.getElementById('fit-bar').value > 0, null, { timeout: 120000 });
  await page.click('#fit-cancel');
  await page.waitForFunction(() => document.body.dataset.fitted, null, { timeout: 120000 });
  assert.equal(await page.evaluate(() => document.body.dataset.fitted), 'cancelled');
  assert.match(await messageOf('fit-message'), /Stopped after/);
  assert.equal(await page.evaluate(() => window.procfit.editor.spec.name), 'tree');
  await page.selectOption('#fit-quality', '1');
});

test('a photo keeps its colours across a reload', async () => {
  await page.click('#tree-colors summary');
  await page.click('#colors-autumn');
  await page.waitForFunction(() => document.getElementById('leaf-hue-from-out').textContent === '330°');
  // The session is saved shortly after a change (main.js persist()).
  await page.waitForTimeout(1500);
  await page.reload();
  await page.waitForSelector('body[data-ready="true"]', { timeout: 90000 });
  await page.waitForFunction(() => /What the tree fit sees/.test(document.getElementById('tree-state').textContent), null, { timeout: 60000 });
  assert.equal(await page.textContent('#leaf-hue-from-out'), '330°');
  assert.equal(await page.textContent('#leaf-min-value-out'), '0.45');
  await page.click('#tree-colors summary');
  await page.click('#colors-reset');
  await page.waitForFunction(() => document.getElementById('leaf-hue-from-out').textContent === '60°');
});

test('no console errors, no page errors, no request outside the origin', () => {
  assert.deepEqual(log.pageErrors, []);
  assert.deepEqual(log.consoleErrors, []);
  const origin = new URL(server.url).origin;
  assert.deepEqual(log.requests.filter((u) => !u.startsWith(origin) && !u.startsWith('data:') && !u.startsWith('blob:')), []);
});
