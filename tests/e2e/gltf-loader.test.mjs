// three.js reads what procfit writes, in the browser: for every preset of every mesh generator
// at full detail, the worker builds the GLB (with two photo cameras), and GLTFLoader in the page
// must find one named node per part, both cameras with their field of view, and the generator
// state in the scene's extras (issue 7).
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { openReadyPage } from './harness.mjs';

let ctx;
let server;
let page;
let log;

before(async () => {
  ctx = await openReadyPage();
  ({ server, page, log } = ctx);
});

after(async () => {
  await ctx?.close();
});

// Two cameras as a fit gives them: yfov, aspect, then a column-major camera-to-world matrix.
const CAMERAS = [
  [0.6, 4 / 3, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0.5, 3, 1],
  [0.5, 1, 0, 0, -1, 0, 0, 1, 0, 0, 1, 0, 0, 0, 3, 0.5, 0, 1],
].flat();

test('GLTFLoader finds every named part, the cameras and the state of every preset', async () => {
  const results = await page.evaluate(async (cameras) => {
    const { GLTFLoader } = await import('three/addons/loaders/GLTFLoader.js');
    const { client, REQUESTS } = window.procfit;
    const specs = await client.call(REQUESTS.GENERATOR_SPECS);
    const loader = new GLTFLoader();
    const out = [];
    for (const spec of specs.filter((s) => s.name !== 'tree')) {
      for (const preset of spec.presets) {
        const { glb } = await client.call(REQUESTS.GENERATE_GLB, {
          generator: spec.name,
          params: preset.values,
          lod: 3,
          cameras,
        });
        const gltf = await loader.parseAsync(glb, '');
        const meshNames = [];
        gltf.scene.traverse((o) => o.isMesh && meshNames.push(o.name || o.parent?.name));
        out.push({
          generator: spec.name,
          preset: preset.name,
          nodeNames: gltf.parser.json.nodes.map((n) => n.name),
          found: gltf.parser.json.nodes
            .filter((n) => n.mesh !== undefined)
            .map((n) => [n.name, !!gltf.scene.getObjectByName(n.name)]),
          cameras: gltf.cameras.map((c) => ({ name: c.name, fov: c.fov, aspect: c.aspect })),
          extras: gltf.scene.userData,
          meshes: meshNames.length,
        });
      }
    }
    return out;
  }, CAMERAS);
  assert.ok(results.length >= 13, `only ${results.length} presets checked`);
  for (const r of results) {
    const where = `${r.generator}/${r.preset}`;
    assert.ok(r.found.length >= 1, `${where}: no part nodes`);
    for (const [name, found] of r.found) assert.ok(found, `${where}: GLTFLoader lost part node ${name}`);
    assert.ok(r.meshes >= r.found.length, `${where}: ${r.meshes} meshes for ${r.found.length} parts`);
    assert.equal(r.cameras.length, 2, `${where}: cameras ${JSON.stringify(r.cameras)}`);
    // three.js keeps fov in degrees.
    assert.ok(Math.abs(r.cameras[0].fov - (0.6 * 180) / Math.PI) < 1e-3, `${where}: fov ${r.cameras[0].fov}`);
    assert.ok(Math.abs(r.cameras[0].aspect - 4 / 3) < 1e-6);
    assert.equal(r.extras.generator, r.generator, `${where}: extras ${JSON.stringify(r.extras).slice(0, 200)}`);
    assert.equal(typeof r.extras.params, 'object');
  }
  const dishParts = new Set(results.filter((r) => r.generator === 'dish').flatMap((r) => r.found.map(([n]) => n)));
  const buildingParts = new Set(results.filter((r) => r.generator === 'building').flatMap((r) => r.found.map(([n]) => n)));
  for (const p of ['body', 'handle']) assert.ok(dishParts.has(p), `no dish preset had a ${p} node: ${[...dishParts]}`);
  for (const p of ['wall', 'window_glass', 'window_frame', 'balcony', 'roof', 'door', 'stairs']) {
    assert.ok(buildingParts.has(p), `no building preset had a ${p} node: ${[...buildingParts]}`);
  }
});

test('no console errors and no request outside the origin', () => {
  assert.deepEqual(log.pageErrors, []);
  assert.deepEqual(log.consoleErrors, []);
  const origin = new URL(server.url).origin;
  assert.deepEqual(log.requests.filter((u) => !u.startsWith(origin) && !u.startsWith('data:') && !u.startsWith('blob:')), []);
});
