// Makes the independent tree benchmark (issue 14): trees from a generator this project did not
// write, ez-tree (npm `@dgreenheck/ez-tree`, MIT, with its own bark and leaf textures), rendered
// by three.js in headless Chromium. For every case it writes into target/tree-bench/<name>/:
//
// - `photo.png`: a 512² photo-like render (textured, lit, on a sky gradient);
// - `labels.png`: the label image of the same view (grey 0 background, 1 branch, 2 leaf; leaves
//   alpha-cut by their texture as the photo's are), the object mask being labels ≠ 0;
// - `camera.json`: the photo's camera (position, target, vertical field of view in radians,
//   image size) in ez-tree's frame (Y up, the trunk's foot at the origin);
// - `truth.bin` and `other.bin`: the tree's mesh (and the same species under another seed) with
//   every leaf quad alpha-cut into triangles where its texture is opaque, for the paper's IoU-64
//   (`cargo bench --bench tree_bench` renders the 64 turntable views in Rust). Format, little
//   endian: b"PFTB", u32 vertex count, u32 triangle count, f32 xyz per vertex, u32 × 3 per
//   triangle, u8 per triangle (0 branch, 1 leaf).
//
// Usage: node scripts/make-tree-bench.mjs [--out DIR] [name …]   (about a minute)
// Deterministic: fixed presets, seeds, cameras and renderer (SwiftShader WebGL).
import { writeFileSync, mkdirSync } from 'node:fs';
import { join } from 'node:path';
import { startServer, launchBrowser, ROOT } from '../tests/e2e/harness.mjs';

/**
 * The cases: ez-tree preset, seed, leaf tint (null keeps the preset's), the camera's vertical
 * field of view (degrees) and elevation (degrees above the horizon; the camera looks at the
 * tree's middle from the +Z side).
 */
export const CASES = [
  { name: 'oak-medium', kind: 'broadleaf round', preset: 'Oak Medium', seed: 11, fov: 40, elev: 0 },
  { name: 'oak-large', kind: 'broadleaf round', preset: 'Oak Large', seed: 12, fov: 50, elev: 5 },
  { name: 'ash-medium', kind: 'broadleaf round', preset: 'Ash Medium', seed: 13, fov: 35, elev: 0 },
  { name: 'aspen-large', kind: 'tall narrow', preset: 'Aspen Large', seed: 14, fov: 45, elev: 0 },
  { name: 'aspen-medium', kind: 'tall narrow', preset: 'Aspen Medium', seed: 15, fov: 40, elev: 3 },
  { name: 'pine-large', kind: 'conifer', preset: 'Pine Large', seed: 16, fov: 40, elev: 0 },
  { name: 'pine-medium', kind: 'conifer', preset: 'Pine Medium', seed: 17, fov: 50, elev: 0 },
  { name: 'oak-autumn', kind: 'autumn', preset: 'Oak Medium', seed: 18, fov: 40, elev: 0, tint: 'autumn-red' },
  { name: 'ash-yellow', kind: 'autumn', preset: 'Ash Medium', seed: 19, fov: 45, elev: 0, tint: 'yellow' },
  { name: 'bush-1', kind: 'bush', preset: 'Bush 1', seed: 20, fov: 40, elev: 8 },
  { name: 'bush-2', kind: 'bush', preset: 'Bush 2', seed: 21, fov: 40, elev: 8 },
];

/** Seed offset of the "same species, another seed" mesh. */
const OTHER_SEED = 1000;
const SIZE = 512;

const PAGE = `<!doctype html><html><head>
<script type="importmap">{"imports":{"three":"/node_modules/three/build/three.module.js"}}</script>
</head><body><script type="module">
import * as THREE from 'three';
import { Tree } from '/node_modules/@dgreenheck/ez-tree/build/ez-tree.es.js';

const SIZE = ${SIZE};
const canvas = document.createElement('canvas');
canvas.width = canvas.height = SIZE;
document.body.appendChild(canvas);
const renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(1);
renderer.setSize(SIZE, SIZE, false);

// Leaf colours that are not green: the texture's luminance times a colour, so the leaf keeps
// its texture's shading but not its hue (a tint alone only darkens green).
const RECOLOUR = { 'autumn-red': [0.95, 0.35, 0.08], 'yellow': [1.0, 0.82, 0.15] };

function loaded(tex) {
  return new Promise((resolve) => {
    const check = () => (tex && tex.image && tex.image.complete && tex.image.naturalWidth > 0)
      ? resolve() : setTimeout(check, 20);
    check();
  });
}

function imageData(img, w, h) {
  const c = document.createElement('canvas');
  c.width = w; c.height = h;
  const ctx = c.getContext('2d');
  ctx.drawImage(img, 0, 0, w, h);
  return ctx.getImageData(0, 0, w, h);
}

function recoloured(tex, rgb) {
  const d = imageData(tex.image, tex.image.naturalWidth, tex.image.naturalHeight);
  const p = d.data;
  for (let i = 0; i < p.length; i += 4) {
    const l = Math.min(1, 1.6 * (0.3 * p[i] + 0.59 * p[i + 1] + 0.11 * p[i + 2]) / 255);
    p[i] = 255 * l * rgb[0]; p[i + 1] = 255 * l * rgb[1]; p[i + 2] = 255 * l * rgb[2];
  }
  const c = document.createElement('canvas');
  c.width = d.width; c.height = d.height;
  c.getContext('2d').putImageData(d, 0, 0);
  const t = new THREE.CanvasTexture(c);
  t.colorSpace = THREE.SRGBColorSpace;
  t.premultiplyAlpha = tex.premultiplyAlpha;
  return t;
}

async function build(preset, seed) {
  const tree = new Tree();
  tree.loadPreset(preset);
  tree.options.seed = seed;
  tree.generate();
  // No wind: the leaves stay where their geometry says.
  tree.leavesMesh.material.onBeforeCompile = () => {};
  await loaded(tree.leavesMesh.material.map);
  if (tree.branchesMesh.material.map) await loaded(tree.branchesMesh.material.map);
  return tree;
}

// The tree as a binary mesh, every leaf quad alpha-cut on a GRID² lattice of its texture.
const GRID = 12;
function exportMesh(tree) {
  const pos = [], tris = [], parts = [];
  const bg = tree.branchesMesh.geometry;
  const bp = bg.attributes.position.array, bi = bg.index.array;
  for (let i = 0; i < bp.length; i++) pos.push(bp[i]);
  for (let i = 0; i < bi.length; i += 3) { tris.push(bi[i], bi[i + 1], bi[i + 2]); parts.push(0); }
  const lg = tree.leavesMesh.geometry;
  const lp = lg.attributes.position.array, li = lg.index.array;
  const mat = tree.leavesMesh.material;
  const img = mat.map.image;
  const R = 64;
  const alpha = imageData(img, R, R).data;
  // Cell (cu, cv) is solid when most of its texels pass the material's alpha test. Texture
  // v = 0 is the image's bottom row (flipY).
  const solid = (cu, cv) => {
    let pass = 0, all = 0;
    for (let y = Math.floor(cv * R / GRID); y < Math.floor((cv + 1) * R / GRID); y++)
      for (let x = Math.floor(cu * R / GRID); x < Math.floor((cu + 1) * R / GRID); x++) {
        all++;
        if (alpha[4 * ((R - 1 - y) * R + x) + 3] >= 255 * mat.alphaTest) pass++;
      }
    return pass * 2 >= all;
  };
  const cells = [];
  for (let cv = 0; cv < GRID; cv++) for (let cu = 0; cu < GRID; cu++) if (solid(cu, cv)) cells.push([cu, cv]);
  const v = (k) => [lp[3 * k], lp[3 * k + 1], lp[3 * k + 2]];
  // Quads as ez-tree writes them: indices (i, i+1, i+2, i, i+2, i+3), corner uvs
  // i: (0,1), i+1: (0,0), i+2: (1,0), i+3: (1,1).
  for (let q = 0; q + 5 < li.length; q += 6) {
    const p0 = v(li[q + 1]), pu = v(li[q + 2]), pv = v(li[q]);
    const at = (u, w) => [0, 1, 2].map((c) => p0[c] + u * (pu[c] - p0[c]) + w * (pv[c] - p0[c]));
    for (const [cu, cv] of cells) {
      const base = pos.length / 3;
      for (const [du, dv] of [[0, 0], [1, 0], [1, 1], [0, 1]]) pos.push(...at((cu + du) / GRID, (cv + dv) / GRID));
      tris.push(base, base + 1, base + 2, base, base + 2, base + 3);
      parts.push(1, 1);
    }
  }
  const nv = pos.length / 3, nt = tris.length / 3;
  const buf = new ArrayBuffer(12 + 12 * nv + 12 * nt + nt);
  const dv = new DataView(buf);
  [0x50, 0x46, 0x54, 0x42].forEach((b, i) => dv.setUint8(i, b));
  dv.setUint32(4, nv, true); dv.setUint32(8, nt, true);
  let o = 12;
  for (const x of pos) { dv.setFloat32(o, x, true); o += 4; }
  for (const x of tris) { dv.setUint32(o, x, true); o += 4; }
  for (const x of parts) { dv.setUint8(o, x); o += 1; }
  const bytes = new Uint8Array(buf);
  let s = '';
  for (let i = 0; i < bytes.length; i += 0x8000) s += String.fromCharCode(...bytes.subarray(i, i + 0x8000));
  return { b64: btoa(s), triangles: nt, leafQuads: li.length / 6 };
}

window.makeCase = async (c) => {
  const tree = await build(c.preset, c.seed);
  // The texture's own map: its alpha cuts the leaves in the labels and the exported mesh.
  const leafMap = tree.leavesMesh.material.map;
  if (c.tint) {
    const m = tree.leavesMesh.material;
    m.map = recoloured(m.map, RECOLOUR[c.tint]);
    m.color = new THREE.Color(0xffffff);
    m.needsUpdate = true;
  }
  const box = new THREE.Box3().setFromObject(tree);
  const size = box.getSize(new THREE.Vector3());
  const centre = box.getCenter(new THREE.Vector3());
  // The camera: from +Z (tilted up by elev), at the distance where the box's longest side
  // fills about 80 % of the image height, in front of the box.
  const fov = c.fov * Math.PI / 180;
  const dist = 0.5 * Math.max(size.x, size.y, size.z) / 0.8 / Math.tan(0.5 * fov) + 0.5 * size.z;
  const e = c.elev * Math.PI / 180;
  const target = centre.clone();
  const position = target.clone().add(new THREE.Vector3(0, Math.sin(e), Math.cos(e)).multiplyScalar(dist));
  const camera = new THREE.PerspectiveCamera(c.fov, 1, 0.05 * dist, 10 * dist);
  camera.position.copy(position);
  camera.lookAt(target);

  // Photo: sky gradient, sun and sky light.
  const scene = new THREE.Scene();
  const sky = document.createElement('canvas');
  sky.width = 4; sky.height = 256;
  const g = sky.getContext('2d');
  const grad = g.createLinearGradient(0, 0, 0, 256);
  grad.addColorStop(0, '#6f9fd8'); grad.addColorStop(1, '#d7e6f2');
  g.fillStyle = grad; g.fillRect(0, 0, 4, 256);
  const skyTex = new THREE.CanvasTexture(sky);
  skyTex.colorSpace = THREE.SRGBColorSpace;
  scene.background = skyTex;
  scene.add(new THREE.HemisphereLight(0xdfefff, 0x6b5a40, 1.6));
  const sun = new THREE.DirectionalLight(0xfff2dd, 2.2);
  sun.position.set(0.6, 1.0, 0.8).multiplyScalar(100);
  scene.add(sun);
  scene.add(tree);
  renderer.setClearColor(0x000000, 1);
  renderer.render(scene, camera);
  const photo = canvas.toDataURL('image/png');

  // Labels: unlit, no antialiasing in effect (labels are read by nearest colour), the leaves cut
  // by the same alpha test.
  const bm = tree.branchesMesh.material, lm = tree.leavesMesh.material;
  tree.branchesMesh.material = new THREE.MeshBasicMaterial({ color: 0xff0000 });
  tree.leavesMesh.material = new THREE.MeshBasicMaterial({
    color: 0x00ff00, map: leafMap, alphaTest: lm.alphaTest, side: THREE.DoubleSide,
  });
  tree.leavesMesh.material.onBeforeCompile = () => {};
  scene.background = null;
  scene.remove(sun);
  renderer.render(scene, camera);
  const raw = new Uint8Array(SIZE * SIZE * 4);
  renderer.getContext().readPixels(0, 0, SIZE, SIZE, WebGL2RenderingContext.RGBA, WebGL2RenderingContext.UNSIGNED_BYTE, raw);
  const lab = document.createElement('canvas');
  lab.width = lab.height = SIZE;
  const lctx = lab.getContext('2d');
  const out = lctx.createImageData(SIZE, SIZE);
  let counts = [0, 0, 0];
  for (let y = 0; y < SIZE; y++) for (let x = 0; x < SIZE; x++) {
    const i = 4 * ((SIZE - 1 - y) * SIZE + x), o = 4 * (y * SIZE + x);
    const r = raw[i], gg = raw[i + 1];
    const l = gg > 16 ? 2 : r > 64 ? 1 : 0;
    counts[l]++;
    out.data[o] = out.data[o + 1] = out.data[o + 2] = l;
    out.data[o + 3] = 255;
  }
  lctx.putImageData(out, 0, 0);
  const labels = lab.toDataURL('image/png');
  tree.branchesMesh.material = bm; tree.leavesMesh.material = lm;
  scene.remove(tree);

  lm.map = leafMap;
  const truth = exportMesh(tree);
  const other = exportMesh(await build(c.preset, c.seed + ${OTHER_SEED}));
  return {
    photo, labels, counts, truth, other,
    camera: {
      width: SIZE, height: SIZE, fov_y: fov,
      position: position.toArray(), target: target.toArray(),
      box_min: box.min.toArray(), box_max: box.max.toArray(),
    },
  };
};
window.benchReady = true;
</script></body></html>`;

async function main() {
  const args = process.argv.slice(2);
  let out = join(ROOT, 'target', 'tree-bench');
  const oi = args.indexOf('--out');
  if (oi >= 0) {
    out = args[oi + 1];
    args.splice(oi, 2);
  }
  const only = new Set(args);
  const cases = CASES.filter((c) => only.size === 0 || only.has(c.name));
  if (cases.length === 0) throw new Error(`no case named ${[...only].join(', ')}`);
  const server = await startServer();
  const browser = await launchBrowser();
  try {
    const page = await browser.context.newPage();
    const errors = [];
    page.on('pageerror', (e) => errors.push(String(e)));
    const url = `${server.url}__tree_bench__.html`;
    await page.route(url, (route) => route.fulfill({ contentType: 'text/html', body: PAGE }));
    await page.goto(url);
    await page.waitForFunction(() => window.benchReady === true, null, { timeout: 60000 }).catch(() => {
      throw new Error(`the bench page did not start: ${errors.join('; ')}`);
    });
    const index = [];
    for (const c of cases) {
      const t = Date.now();
      const r = await page.evaluate((c) => window.makeCase(c), c);
      const dir = join(out, c.name);
      mkdirSync(dir, { recursive: true });
      const png = (d) => Buffer.from(d.split(',')[1], 'base64');
      writeFileSync(join(dir, 'photo.png'), png(r.photo));
      writeFileSync(join(dir, 'labels.png'), png(r.labels));
      writeFileSync(join(dir, 'truth.bin'), Buffer.from(r.truth.b64, 'base64'));
      writeFileSync(join(dir, 'other.bin'), Buffer.from(r.other.b64, 'base64'));
      writeFileSync(join(dir, 'camera.json'), JSON.stringify({ ...c, ...r.camera }, null, 1) + '\n');
      index.push({ name: c.name, kind: c.kind });
      console.log(
        `${c.name}: ${r.truth.leafQuads} leaf quads, ${r.truth.triangles} triangles, ` +
          `labels bg/branch/leaf ${r.counts.join('/')}, ${((Date.now() - t) / 1000).toFixed(1)} s`,
      );
    }
    if (only.size === 0) writeFileSync(join(out, 'index.json'), JSON.stringify(index, null, 1) + '\n');
    if (errors.length) throw new Error(`page errors: ${errors.join('; ')}`);
  } finally {
    await browser.close();
    server.stop();
  }
}

await main();
