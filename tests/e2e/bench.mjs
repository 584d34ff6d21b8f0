// The page's benchmark (printed, not asserted): time to interactive, and slider → new frame
// latency at each level of detail, in headless Chromium on this machine. Latency is measured by
// the page itself (Editor.timings): from the slider's input event to the requestAnimationFrame
// in which the new GLB is drawn, split into queueing, worker (generate + GLB export), message
// round trip, GLTFLoader parse and the wait for the frame.
//
// Usage (after `make wasm`): node tests/e2e/bench.mjs   (or `make bench-page`)
import { existsSync, readFileSync } from 'node:fs';
import { join } from 'node:path';
import { startServer, launchBrowser, openPage, firstLoad, ROOT } from './harness.mjs';

const MOVES = 15;
const median = (xs) => {
  const s = [...xs].sort((a, b) => a - b);
  return s.length ? (s.length % 2 ? s[(s.length - 1) / 2] : (s[s.length / 2 - 1] + s[s.length / 2]) / 2) : NaN;
};

/** A bundled sample's entry in www/samples/index.json (its file, generator and truth). */
async function sample(server, name) {
  return JSON.parse(await (await fetch(`${server.url}www/samples/index.json`)).text()).samples.find((x) => x.name === name);
}

/**
 * Runs the page's fit `runs` times on the loaded photo: wall time, the result line and the
 * IoU-64 of the fitted model against the sample's `truth` (in the model frames: the fitted
 * yaw is not aligned, so a turned handle counts against it — a lower bound).
 */
async function timedFits(page, truth, runs) {
  const out = [];
  for (let run = 0; run < runs; run += 1) {
    await page.evaluate(() => delete document.body.dataset.fitted);
    const t0 = Date.now();
    await page.click('#fit-start');
    await page.waitForFunction(() => document.body.dataset.fitted, null, { timeout: 600000 });
    const seconds = (Date.now() - t0) / 1000;
    const message = await page.textContent('#fit-message');
    const { iou } = await page.evaluate(
      (truth) => {
        const { client, REQUESTS, editor } = window.procfit;
        return client.call(REQUESTS.IOU64, { a: { generator: editor.spec.name, params: editor.base }, b: { generator: truth.generator, params: truth.truth.params }, lod: 1, side: 128 });
      },
      truth,
    );
    out.push({ seconds, iou, message });
  }
  return out;
}

const server = await startServer();
const browser = await launchBrowser();
try {
  const rows = [];
  const ttis = [];
  for (let run = 0; run < 3; run += 1) {
    const { page } = await openPage(browser.context, server.url);
    await page.waitForSelector('body[data-ready="true"]', { timeout: 120000 });
    await page.evaluate(() => window.procfit.editor.settled());
    // From navigation start to the first model frame on screen.
    ttis.push(await page.evaluate(() => performance.now()));
    if (run < 2) {
      await page.close();
      continue;
    }
    for (const [lod, name] of [[0, 'LOW'], [1, 'MEDIUM'], [2, 'HIGH'], [3, 'ULTRA']]) {
      await page.selectOption('#lod', String(lod));
      await page.evaluate(() => window.procfit.editor.settled());
      await page.evaluate(() => (window.procfit.editor.timings.length = 0));
      // The slider's input events are dispatched in the page, as a drag delivers them:
      // Playwright's keyboard goes through the DevTools protocol, which holds the page's main
      // thread for ~70 ms a key press and would measure itself, not the page.
      await page.evaluate(async (moves) => {
        const input = document.getElementById('param-y_scale');
        for (let i = 0; i < moves; i += 1) {
          input.value = String(0.5 + (i % 2) * 0.1);
          input.dispatchEvent(new Event('input', { bubbles: true }));
          await window.procfit.editor.settled();
          // A pause, as between a person's slider moves; lets the page go idle.
          await new Promise((r) => setTimeout(r, 60));
        }
      }, MOVES);
      const t = await page.evaluate(() => window.procfit.editor.timings.slice());
      const tris = (await page.textContent('#viewer-info')).match(/([\d,]+) triangles/)[1];
      const m = (k) => median(t.map((x) => x[k])).toFixed(1);
      rows.push(`| ${name} | ${tris} | ${t.length} | **${m('latency')}** | ${m('queued')} | ${m('worker')} | ${m('trip')} | ${m('parse')} | ${m('frame')} |`);
    }
    await page.close();
  }
  // The sample cup fit at Normal effort with the page's threads, and how close it came to the
  // truth the sample was rendered from.
  const { page } = await openPage(browser.context, server.url);
  await page.waitForSelector('body[data-ready="true"]', { timeout: 120000 });
  const threads = await page.evaluate(() => window.procfit.client.info.threads);
  await page.click('button[data-sample="mug"]');
  await page.waitForFunction(() => /Object found|check the mask/.test(document.getElementById('mask-state').textContent), null, { timeout: 60000 });
  const fits = await timedFits(page, await sample(server, 'mug'), 3);
  // Responsiveness while a fit runs: slider moves during a Thorough fit (the worker yields
  // between slices, so a regeneration waits at most one slice).
  await page.selectOption('#fit-quality', '3');
  await page.evaluate(() => delete document.body.dataset.fitted);
  await page.click('#fit-start');
  await page.waitForFunction(() => document.getElementById('fit-bar').value > 0, null, { timeout: 60000 });
  const during = await page.evaluate(async (moves) => {
    const { editor } = window.procfit;
    editor.timings.length = 0;
    const input = document.getElementById('param-y_scale');
    for (let i = 0; i < moves; i += 1) {
      input.value = String(0.5 + (i % 2) * 0.1);
      input.dispatchEvent(new Event('input', { bubbles: true }));
      await editor.settled();
      await new Promise((r) => setTimeout(r, 60));
    }
    return editor.timings.map((t) => t.latency);
  }, MOVES);
  await page.click('#fit-cancel');
  await page.waitForFunction(() => document.body.dataset.fitted, null, { timeout: 60000 });
  await page.close();
  // The oak sample's tree fit at Normal effort (the default budget of the native tree fit),
  // and its IoU-64 against the tree the sample was rendered from (the paper's metric: each
  // model normalised to its bounding box; the fitted seed shuffles branches, so ~0.6–0.8 is
  // the ceiling, see `cargo bench --bench tree`).
  let trees;
  {
    // A fresh profile: the pages above saved their session, which this one would restore.
    const fresh = await launchBrowser();
    const { page } = await openPage(fresh.context, server.url);
    await page.waitForSelector('body[data-ready="true"]', { timeout: 120000 });
    await page.click('button[data-sample="oak"]');
    await page.waitForFunction(() => /What the tree fit sees/.test(document.getElementById('tree-state').textContent), null, { timeout: 60000 });
    await page.selectOption('#fit-quality', '1');
    trees = await timedFits(page, await sample(server, 'oak'), 2);
    await page.close();
    await fresh.close();
  }
  // Issue 14: the tree fit in the page on a photo of a tree procfit did not make (the
  // independent benchmark's, `node scripts/make-tree-bench.mjs`; skipped when absent), by the
  // file picker as a user gives it, Normal effort, the field of view unknown (a PNG has no
  // EXIF). Its scores are `cargo bench --bench tree_bench`'s; this times the page.
  const ezTrees = [];
  for (const name of ['oak-medium', 'pine-medium']) {
    const photo = join(ROOT, 'target', 'tree-bench', name, 'photo.png');
    if (!existsSync(photo)) continue;
    const fresh = await launchBrowser();
    const { page } = await openPage(fresh.context, server.url);
    await page.waitForSelector('body[data-ready="true"]', { timeout: 120000 });
    await page.setInputFiles('#file', { name: `${name}.png`, mimeType: 'image/png', buffer: readFileSync(photo) });
    await page.waitForFunction(() => window.procfit.state.photos.length === 1 && window.procfit.state.photos[0].mask, null, { timeout: 60000 });
    await page.check('input[name="generator"][value="tree"]');
    await page.waitForFunction(() => /What the tree fit sees/.test(document.getElementById('tree-state').textContent), null, { timeout: 60000 });
    await page.selectOption('#fit-quality', '1');
    await page.evaluate(() => delete document.body.dataset.fitted);
    const t0 = Date.now();
    await page.click('#fit-start');
    await page.waitForFunction(() => document.body.dataset.fitted, null, { timeout: 600000 });
    ezTrees.push({ name, seconds: (Date.now() - t0) / 1000, state: await page.evaluate(() => document.body.dataset.fitted), message: (await page.textContent('#fit-message')).replace(/\s+/g, ' ').trim() });
    await page.close();
    await fresh.close();
  }
  const evaluations = (trees[0].message.match(/\(([\d,]+) evaluations/) || [])[1];
  console.log(`\nOak sample tree fit (Normal effort, ${threads} threads), 2 runs: median ${median(trees.map((f) => f.seconds)).toFixed(1)} s, IoU-64 vs truth ${trees.map((f) => f.iou.toFixed(3)).join(', ')} (${evaluations} evaluations; target ≤ 120 s)`);
  for (const t of ezTrees) console.log(`\nez-tree ${t.name} photo, tree fit in the page (Normal effort, ${threads} threads, fov unknown): ${t.seconds.toFixed(1)} s, ${t.state}: ${t.message} (target ≤ 120 s)`);
  console.log(`\nSlider → new frame during a running fit (MEDIUM, ${during.length} moves): median ${median(during).toFixed(1)} ms, max ${Math.max(...during).toFixed(1)} ms`);
  console.log(`\nSample cup fit (Normal effort, ${threads} threads), 3 runs: median ${median(fits.map((f) => f.seconds)).toFixed(1)} s, IoU-64 vs truth median ${median(fits.map((f) => f.iou)).toFixed(3)} (runs: ${fits.map((f) => `${f.seconds.toFixed(1)} s / ${f.iou.toFixed(3)}`).join(', ')})`);
  console.log(`\nTime to interactive (navigation → first model frame), median of ${ttis.length}: ${median(ttis).toFixed(0)} ms\n`);
  console.log('Slider → new frame latency, medians in ms (headless Chromium, SwiftShader WebGL):\n');
  console.log('| detail | triangles | moves | latency | queued | worker | round trip | parse | frame |');
  console.log('|---|---:|---:|---:|---:|---:|---:|---:|---:|');
  for (const r of rows) console.log(r);
  // The first load as a visitor gets it: from dist/ (minified, precompressed), when built.
  if (existsSync(join(ROOT, 'dist', 'index.html'))) {
    const dist = await startServer({ root: join(ROOT, 'dist'), isolation: true });
    try {
      const { files, close } = await firstLoad(dist.url);
      await close();
      const sum = (k) => files.reduce((s, f) => s + f[k], 0);
      console.log(`\nFirst load from dist/ (until the first model is drawn): ${sum('transferred').toLocaleString('en')} bytes transferred, ${sum('decoded').toLocaleString('en')} decoded, ${files.length} requests (limit 2,000,000 transferred: tests/e2e/weight.test.mjs)`);
    } finally {
      dist.stop();
    }
  } else {
    console.log('\nFirst load: dist/ not built (`make dist`), not measured');
  }
} finally {
  await browser.close();
  server.stop();
}
