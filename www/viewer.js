// @ts-check
// The 3D view of the result step: a three.js scene that shows the very GLB the page would
// download (bytes from the worker, parsed with GLTFLoader), with orbit/zoom, a wireframe toggle
// and colours per part. It renders on demand (after a load or a camera move), not in a loop, so
// an idle page costs nothing and "the frame after a slider moved" is a well-defined moment.
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

/** Distinct, calm colours for "colour by part" (sRGB hex). */
const PART_PALETTE = [0x4e79a7, 0xf28e2b, 0x59a14f, 0xe15759, 0x76b7b2, 0xedc948, 0xb07aa1, 0x9c755f];

export class Viewer extends EventTarget {
  /** `canvas` is the element to draw into; its CSS size decides the drawing size. */
  constructor(canvas) {
    super();
    this.canvas = canvas;
    this.renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, 2));
    this.renderer.outputColorSpace = THREE.SRGBColorSpace;
    this.scene = new THREE.Scene();
    this.scene.background = new THREE.Color(0xeeece7);
    this.camera = new THREE.PerspectiveCamera(35, 1, 0.005, 100);
    this.camera.position.set(0.6, 0.45, 0.9);
    this.controls = new OrbitControls(this.camera, canvas);
    this.controls.enableDamping = false;
    this.controls.addEventListener('change', () => this.requestRender());
    // Keyboard orbit: arrows rotate when the canvas has focus (it is tabbable).
    this.controls.listenToKeyEvents(canvas);
    this.controls.keyRotateSpeed = 1.0;

    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x8d877c, 1.6));
    const sun = new THREE.DirectionalLight(0xffffff, 2.2);
    sun.position.set(1.5, 2.5, 2);
    this.scene.add(sun);
    const fill = new THREE.DirectionalLight(0xffffff, 0.6);
    fill.position.set(-2, 1, -1.5);
    this.scene.add(fill);
    this.grid = new THREE.GridHelper(2, 20, 0xc9c5bc, 0xdcd8cf);
    this.scene.add(this.grid);

    this.loader = new GLTFLoader();
    this.model = null;
    this.wireframe = false;
    this.partColors = false;
    this.framed = false;
    this.pendingRender = false;
    this.frameWaiters = [];
    this.parts = [];

    new ResizeObserver(() => this.resize()).observe(canvas);
    this.resize();
  }

  resize() {
    const w = Math.max(1, this.canvas.clientWidth);
    const h = Math.max(1, this.canvas.clientHeight);
    this.renderer.setSize(w, h, false);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    this.requestRender();
  }

  /** Schedules one render on the next animation frame (many requests → one frame). */
  requestRender() {
    if (this.pendingRender) return;
    this.pendingRender = true;
    requestAnimationFrame(() => {
      this.pendingRender = false;
      this.renderer.render(this.scene, this.camera);
      const waiters = this.frameWaiters.splice(0);
      const now = performance.now();
      waiters.forEach((w) => w(now));
      this.dispatchEvent(new CustomEvent('frame', { detail: { at: now } }));
    });
  }

  /** Resolves with the time of the next rendered frame. */
  nextFrame() {
    return new Promise((resolve) => {
      this.frameWaiters.push(resolve);
      this.requestRender();
    });
  }

  /**
   * Replaces the shown model with the GLB in `buffer` (an ArrayBuffer). Resolves with the part
   * names and counts; rejects with a readable error when three.js cannot read it. `reframe`
   * points the camera at the new model (on a new generator or file, not on every slider move).
   */
  async load(buffer, { reframe = false } = {}) {
    const gltf = await new Promise((resolve, reject) =>
      this.loader.parse(buffer, '', resolve, (e) => reject(new Error(`the 3D view could not read the model: ${e.message || e}`))),
    );
    const root = gltf.scene;
    if (this.model) {
      this.scene.remove(this.model);
      disposeTree(this.model);
    }
    this.model = root;
    this.parts = [];
    let triangles = 0;
    root.traverse((o) => {
      if (!o.isMesh) return;
      o.userData.fileMaterial = o.material;
      this.parts.push(o.name || `part ${this.parts.length + 1}`);
      const index = o.geometry.index;
      triangles += (index ? index.count : o.geometry.attributes.position.count) / 3;
    });
    this.scene.add(root);
    this.applyLook();
    if (reframe || !this.framed) this.frame();
    this.requestRender();
    return { parts: this.parts.slice(), triangles };
  }

  /** Points the camera at the model from a three-quarter view, keeping the object in frame. */
  frame() {
    if (!this.model) return;
    const box = new THREE.Box3().setFromObject(this.model);
    if (box.isEmpty()) return;
    const size = box.getSize(new THREE.Vector3());
    const center = box.getCenter(new THREE.Vector3());
    const radius = Math.max(size.length() / 2, 1e-3);
    const dist = radius / Math.sin(THREE.MathUtils.degToRad(this.camera.fov / 2)) * 1.1;
    const dir = new THREE.Vector3(0.55, 0.45, 1).normalize();
    this.camera.position.copy(center).addScaledVector(dir, dist);
    this.camera.near = dist / 100;
    this.camera.far = dist * 100;
    this.camera.updateProjectionMatrix();
    this.controls.target.copy(center);
    this.controls.update();
    // The grid sits under the object, scaled to it.
    this.grid.position.set(center.x, box.min.y, center.z);
    this.grid.scale.setScalar(Math.max(radius * 2, 0.05));
    this.framed = true;
    this.requestRender();
  }

  setWireframe(on) {
    this.wireframe = on;
    this.applyLook();
    this.requestRender();
  }

  setPartColors(on) {
    this.partColors = on;
    this.applyLook();
    this.requestRender();
  }

  /** The CSS colour a part is drawn in when colouring by part (for the legend). */
  partColor(i) {
    return `#${PART_PALETTE[i % PART_PALETTE.length].toString(16).padStart(6, '0')}`;
  }

  applyLook() {
    if (!this.model) return;
    let i = 0;
    this.model.traverse((o) => {
      if (!o.isMesh) return;
      if (this.partColors) {
        if (!o.userData.partMaterial) {
          o.userData.partMaterial = new THREE.MeshStandardMaterial({
            color: PART_PALETTE[i % PART_PALETTE.length],
            roughness: 0.6,
            side: THREE.DoubleSide,
          });
        }
        o.material = o.userData.partMaterial;
      } else {
        o.material = o.userData.fileMaterial;
      }
      o.material.wireframe = this.wireframe;
      i += 1;
    });
  }
}

function disposeTree(root) {
  root.traverse((o) => {
    if (!o.isMesh) return;
    o.geometry.dispose();
    for (const m of [o.userData.fileMaterial, o.userData.partMaterial]) m?.dispose();
  });
}
