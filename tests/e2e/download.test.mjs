// Issue 17: the download menu's other formats, as a person uses them: the compact GLB passes the
// Khronos validator (0 errors, 0 warnings) and loads in three.js's GLTFLoader with the parts the
// plain GLB has; OBJ comes with the MTL it names; the STL holds every triangle of the model.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { readFileSync } from 'node:fs';
import validator from 'gltf-validator';
import { GLTFLoader } from 'three/examples/jsm/loaders/GLTFLoader.js';
import { startServer, launchBrowser, openPage } from './harness.mjs';

let server;
let browser;
let page;

before(async () => {
  server = await startServer();
  browser = await launchBrowser();
  ({ page } = await openPage(browser.context, server.url));
  await page.waitForSelector('body[data-ready="true"]', { timeout: 90000 });
  await page.evaluate(() => window.procfit.editor.settled());
});

after(async () => {
  await browser?.close();
  server?.stop();
});

/** Chooses `format` in the menu, clicks Download and collects `count` downloads. */
async function downloadAs(format, count = 1) {
  await page.selectOption('#download-format', format);
  // Each download's bytes arrive when they arrive (a small MTL can be saved before the OBJ
  // that came first), so the reads are awaited together; Chromium may also report the two
  // downloads in either order, so callers find a file by its name, not its place.
  const started = [];
  const done = new Promise((resolve) => {
    page.on('download', function onDownload(dl) {
      started.push(dl.path().then((path) => ({ name: dl.suggestedFilename(), bytes: readFileSync(path) })));
      if (started.length === count) {
        page.off('download', onDownload);
        resolve();
      }
    });
  });
  await page.click('#download-as');
  await done;
  return Promise.all(started);
}

const parse = (bytes) => new GLTFLoader().parseAsync(bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength), '');
const meshNames = (gltf) => {
  const names = [];
  gltf.scene.traverse((o) => o.isMesh && names.push(o.name));
  return names.sort();
};

test('the compact GLB validates and loads in three.js with the parts of the model shown', async () => {
  const [file] = await downloadAs('glb-compact');
  assert.match(file.name, /\.compact\.glb$/);
  const report = await validator.validateBytes(new Uint8Array(file.bytes), {
    uri: file.name,
    externalResourceFunction: (uri) => Promise.reject(new Error(`external resource ${uri}`)),
  });
  const problems = report.issues.messages.filter((m) => m.severity <= 1).map((m) => `${m.code} ${m.message}`);
  assert.deepEqual(problems, []);
  const json = JSON.parse(new TextDecoder().decode(file.bytes.subarray(20, 20 + file.bytes.readUInt32LE(12))));
  assert.deepEqual(json.extensionsRequired, ['KHR_mesh_quantization']);
  const shown = await page.evaluate(() => Array.from(window.procfit.editor.glb.bytes));
  assert.ok(file.bytes.length < shown.length, `compact ${file.bytes.length} bytes, plain ${shown.length}`);
  const compact = await parse(file.bytes);
  const plain = await parse(Buffer.from(shown));
  assert.deepEqual(meshNames(compact), meshNames(plain));
  assert.ok(meshNames(compact).length > 0);
});

test('OBJ downloads with the MTL it names, STL with every triangle', async () => {
  const files = await downloadAs('obj', 2);
  const obj = files.find((f) => /\.obj$/.test(f.name));
  const mtl = files.find((f) => /\.mtl$/.test(f.name));
  assert.ok(obj && mtl, `an OBJ and an MTL: ${files.map((f) => f.name)}`);
  const text = obj.bytes.toString();
  assert.ok(text.split('\n').includes(`mtllib ${mtl.name}`), 'the OBJ names the MTL it came with');
  const used = text.split('\n').filter((l) => l.startsWith('usemtl ')).map((l) => l.slice(7));
  const defined = mtl.bytes.toString().split('\n').filter((l) => l.startsWith('newmtl ')).map((l) => l.slice(7));
  assert.deepEqual(used, defined);
  const faces = text.split('\n').filter((l) => l.startsWith('f ')).length;

  const [stl] = await downloadAs('stl');
  assert.match(stl.name, /\.stl$/);
  const count = stl.bytes.readUInt32LE(80);
  assert.equal(stl.bytes.length, 84 + 50 * count);
  assert.equal(count, faces, 'the STL and the OBJ hold the same triangles');
  const info = await page.textContent('#viewer-info');
  const shown = Number(info.match(/([\d,]+) triangles/)[1].replace(/,/g, ''));
  assert.equal(count, shown, `the STL has the ${shown} triangles the view shows`);
});
