// Loads every .glb in a directory with three.js's GLTFLoader (in node: parsing needs no WebGL)
// and checks that it finds what the file declares: every named mesh node as a three.js Mesh of
// that name, every camera node as a PerspectiveCamera, every base colour texture on its material
// (embedded PNGs), and the generator state (scene extras) as the scene's userData.
//
// A file `X.compact.glb` (quantised) beside `X.glb` must load to the same world-space bounding
// box of every part, within the quantisation step (1/32767 of the part's size) plus 1e-6.
//
// Usage: node tests/gltf_three.mjs <dir>
// Exits non-zero on a load failure, a missing part or camera, or an empty directory.

import { readdirSync, readFileSync } from 'node:fs';
import { join } from 'node:path';
import { GLTFLoader } from 'three/examples/jsm/loaders/GLTFLoader.js';
import { Box3, PropertyBinding } from 'three';

const dir = process.argv[2];
if (!dir) {
  console.error('usage: node tests/gltf_three.mjs <dir-with-glb-files>');
  process.exit(2);
}
const files = readdirSync(dir).filter((f) => f.endsWith('.glb')).sort();
if (files.length === 0) {
  console.error(`no .glb files in ${dir}`);
  process.exit(1);
}

/** The JSON chunk of a GLB, parsed. */
function gltfJson(bytes) {
  const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  const length = view.getUint32(12, true);
  return JSON.parse(new TextDecoder().decode(bytes.subarray(20, 20 + length)));
}

// Node has no DOM: GLTFLoader reaches a GLB's embedded images through `self.URL` (a blob: URL)
// and `createImageBitmap`. This one checks the bytes are a PNG and reports its size, so a
// textured material gets its texture (the browser tests decode the pixels for real).
globalThis.self ??= globalThis;
let images = 0;
globalThis.createImageBitmap ??= async (blob) => {
  const b = new Uint8Array(await blob.arrayBuffer());
  if (![0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a].every((v, i) => b[i] === v)) throw new Error('an embedded image is not a PNG');
  const view = new DataView(b.buffer, b.byteOffset, b.byteLength);
  images += 1;
  return { width: view.getUint32(16), height: view.getUint32(20), close() {} };
};

const loader = new GLTFLoader();
/** World-space bounding box of each named mesh, by file. */
const boxes = new Map();
let compared = 0;
let failed = 0;
let parts = 0;
let cameras = 0;
for (const file of files) {
  const bytes = new Uint8Array(readFileSync(join(dir, file)));
  const json = gltfJson(bytes);
  const problems = [];
  try {
    const ab = bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength);
    const gltf = await loader.parseAsync(ab, '');
    const found = { Mesh: new Set(), PerspectiveCamera: new Set() };
    gltf.scene.traverse((o) => found[o.type]?.add(o.name));
    gltf.scene.updateMatrixWorld(true);
    const byPart = new Map();
    gltf.scene.traverse((o) => {
      if (o.type === 'Mesh') byPart.set(o.name, new Box3().setFromObject(o));
    });
    boxes.set(file, byPart);
    for (const node of json.nodes ?? []) {
      // three.js sanitises node names for animation bindings (spaces become underscores).
      const name = PropertyBinding.sanitizeNodeName(node.name ?? '');
      if (node.mesh !== undefined) {
        parts += 1;
        if (!found.Mesh.has(name)) problems.push(`part "${node.name}" not found`);
      }
      if (node.camera !== undefined) {
        cameras += 1;
        if (!found.PerspectiveCamera.has(name)) problems.push(`camera "${node.name}" not found`);
      }
    }
    if (gltf.cameras.length !== (json.cameras ?? []).length) {
      problems.push(`${gltf.cameras.length} cameras loaded, ${(json.cameras ?? []).length} declared`);
    }
    // A material with a base colour texture in the file has it in three.js.
    gltf.scene.traverse((o) => {
      if (o.type !== 'Mesh') return;
      const declared = (json.materials ?? []).find((m) => m.name === o.material?.name);
      if (declared?.pbrMetallicRoughness?.baseColorTexture && !o.material.map) problems.push(`part "${o.name}" lost its texture`);
    });
    const extras = json.scenes?.[json.scene ?? 0]?.extras;
    if (extras && gltf.scene.userData.generator !== extras.generator) {
      problems.push('generator state missing from the scene userData');
    }
  } catch (e) {
    problems.push(`GLTFLoader failed: ${e?.message ?? e}`);
  }
  if (problems.length > 0) {
    failed += 1;
    console.error(`${file}: ${problems.join('; ')}`);
  }
}
for (const file of files.filter((f) => f.endsWith('.compact.glb'))) {
  const plain = boxes.get(file.replace(/\.compact\.glb$/, '.glb'));
  const small = boxes.get(file);
  if (!plain || !small) continue;
  compared += 1;
  for (const [name, box] of plain) {
    const other = small.get(name);
    const size = box.getSize(box.min.clone()).length();
    const tol = size / 32767 + 1e-6;
    const off = other
      ? Math.max(box.min.distanceTo(other.min), box.max.distanceTo(other.max))
      : Infinity;
    if (!(off <= tol)) {
      failed += 1;
      console.error(`${file}: part "${name}" is ${off} away from the plain file's (tolerance ${tol})`);
    }
  }
}
console.log(`three.js GLTFLoader: ${images} embedded PNG images decoded`);
console.log(`three.js GLTFLoader: ${compared} compact files placed like their plain ones`);
console.log(`three.js GLTFLoader: ${files.length} files, ${parts} parts, ${cameras} cameras, ${failed} failed`);
process.exit(failed > 0 ? 1 : 0);
