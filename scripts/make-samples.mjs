// Makes the page's bundled samples (www/samples/): synthetic "photos" of known models, so a
// newcomer can try procfit without a photo of their own and tests have inputs whose truth is
// known. Each sample is a generator preset rendered by the page's own viewer (the GLB the worker
// builds, loaded with GLTFLoader) on a table in front of a wall, from a recorded camera; the
// model's parameters and the camera go into www/samples/index.json next to the JPEG.
//
// Usage (after `make wasm`): node scripts/make-samples.mjs
// Deterministic for a given build: same presets, same cameras, same renderer.
import { writeFileSync, mkdirSync } from 'node:fs';
import { join } from 'node:path';
import { startServer, launchBrowser, openPage, ROOT } from '../tests/e2e/harness.mjs';

/**
 * What to render: preset, body colour (sRGB), table and wall colours, and the view: the camera
 * looks at the model's bounding-box centre from direction `dir`, at the distance where the
 * bounding sphere fills `fill` of the image height.
 */
const SAMPLES = [
  {
    name: 'mug',
    label: 'Blue mug',
    generator: 'dish',
    preset: 'mug',
    color: 0x3d6fb6,
    table: 0xb39b7a,
    wall: 0xe6e1d8,
    view: { dir: [0.0, 0.35, 1.0], yfov_deg: 32, fill: 0.75 },
    // A second photo of the same mug from its side, for multi-view fits.
    more: [{ suffix: 'side', dir: [1.0, 0.3, 0.25], yfov_deg: 32, fill: 0.75 }],
  },
  {
    name: 'bowl',
    label: 'White bowl',
    generator: 'dish',
    preset: 'bowl',
    color: 0xf1eee8,
    table: 0x5b4636,
    wall: 0x9aa3a8,
    view: { dir: [0.2, 0.5, 1.0], yfov_deg: 32, fill: 0.7 },
  },
  {
    name: 'vase',
    label: 'Green vase',
    generator: 'dish',
    preset: 'vase',
    color: 0x4f8a5b,
    table: 0xcfc6b6,
    wall: 0xf3efe9,
    view: { dir: [-0.1, 0.25, 1.0], yfov_deg: 34, fill: 0.75 },
  },
];
const WIDTH = 640;
const HEIGHT = 480;

const server = await startServer();
const browser = await launchBrowser();
try {
  const { page } = await openPage(browser.context, server.url);
  await page.waitForSelector('body[data-ready="true"]', { timeout: 120000 });
  const outDir = join(ROOT, 'www', 'samples');
  mkdirSync(outDir, { recursive: true });
  const index = [];
  /** Renders sample `s` seen along `view`; resolves with the JPEG data URL and the truth. */
  const render = (s, view) =>
    page.evaluate(
      async ({ s, view, WIDTH, HEIGHT }) => {
        const { editor, viewer } = window.procfit;
        const THREE = await import('three');
        const spec = editor.specs.get(s.generator);
        const preset = spec.presets.find((p) => p.name === s.preset);
        editor.open(s.generator, preset.values, 3);
        await editor.settled();
        const scene = viewer.scene;
        // Props for a photo: a table top and a wall behind it, no grid.
        const table = new THREE.Mesh(
          new THREE.PlaneGeometry(6, 6),
          new THREE.MeshStandardMaterial({ color: s.table, roughness: 0.8 }),
        );
        table.rotation.x = -Math.PI / 2;
        const wall = new THREE.Mesh(
          new THREE.PlaneGeometry(6, 3),
          new THREE.MeshStandardMaterial({ color: s.wall, roughness: 0.95 }),
        );
        scene.add(table, wall);
        viewer.grid.visible = false;
        viewer.model.traverse((o) => {
          if (o.isMesh) {
            o.material = o.material.clone();
            o.material.color.set(s.color);
            o.material.roughness = 0.35;
          }
        });
        const box = new THREE.Box3().setFromObject(viewer.model);
        const center = box.getCenter(new THREE.Vector3());
        const radius = box.getSize(new THREE.Vector3()).length() / 2;
        const half = THREE.MathUtils.degToRad(view.yfov_deg / 2);
        const dist = radius / Math.tan(half * view.fill);
        const eye = center.clone().addScaledVector(new THREE.Vector3(...view.dir).normalize(), dist);
        const cam = new THREE.PerspectiveCamera(view.yfov_deg, WIDTH / HEIGHT, dist / 100, dist * 100);
        cam.position.copy(eye);
        cam.lookAt(center);
        // The table under the object; the wall behind it, far enough to stay out of focus.
        table.position.y = box.min.y;
        table.scale.setScalar(dist);
        wall.scale.setScalar(dist);
        // The wall stands behind the object as this camera sees it, facing the camera, so
        // every view has a backdrop and no wall edge.
        const flat = new THREE.Vector3(view.dir[0], 0, view.dir[2]).normalize();
        wall.position.set(center.x - flat.x * dist, box.min.y + 1.5 * dist, center.z - flat.z * dist);
        wall.lookAt(center.x + flat.x * dist, box.min.y + 1.5 * dist, center.z + flat.z * dist);
        const r = viewer.renderer;
        const size = r.getSize(new THREE.Vector2());
        const ratio = r.getPixelRatio();
        r.setPixelRatio(1);
        r.setSize(WIDTH, HEIGHT, false);
        r.render(scene, cam);
        const url = r.domElement.toDataURL('image/jpeg', 0.88);
        scene.remove(table, wall);
        viewer.grid.visible = true;
        r.setPixelRatio(ratio);
        r.setSize(size.x, size.y, false);
        return { url, params: preset.values, eye: eye.toArray(), target: center.toArray() };
      },
      { s, view, WIDTH, HEIGHT },
    );
  const camera = (shot, view) => ({ eye: shot.eye, target: shot.target, yfov_deg: view.yfov_deg, width: WIDTH, height: HEIGHT });
  for (const s of SAMPLES) {
    const shot = await render(s, s.view);
    const file = `${s.name}.jpg`;
    writeFileSync(join(outDir, file), Buffer.from(shot.url.split(',')[1], 'base64'));
    const more = [];
    for (const view of s.more ?? []) {
      const extra = await render(s, view);
      const name = `${s.name}-${view.suffix}.jpg`;
      writeFileSync(join(outDir, name), Buffer.from(extra.url.split(',')[1], 'base64'));
      more.push({ file: name, camera: camera(extra, view) });
      console.log(`wrote www/samples/${name}`);
    }
    index.push({
      name: s.name,
      label: s.label,
      file,
      generator: s.generator,
      // The truth, for tests and benchmarks of the fit: the model and the camera of the photo
      // (glTF convention: the camera looks down −Z; y up; yfov is vertical).
      truth: { preset: s.preset, params: shot.params, lod: 3 },
      camera: camera(shot, s.view),
      // Further photos of the same object (not on the sample button; for multi-view tests).
      ...(more.length ? { more_views: more } : {}),
    });
    console.log(`wrote www/samples/${file}`);
  }
  writeFileSync(join(outDir, 'index.json'), JSON.stringify({ samples: index }, null, 1) + '\n');
} finally {
  await browser.close();
  server.stop();
}
