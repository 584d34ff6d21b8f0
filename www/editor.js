// @ts-check
// The model editor of the result step: the current generator, parameters and level of detail;
// sliders grouped as the generator's spec groups them; undo/redo; reset; and the regeneration
// pump that keeps the 3D view live while a slider moves.
//
// The pump sends at most one generate request at a time and always the newest parameters: while
// the worker builds one GLB, slider moves only mark the state dirty, and the next request starts
// as soon as the previous frame is on screen. So a fast drag never queues stale work, and the
// latency it reports (input → new frame on screen) is what a person feels.
import { REQUESTS } from './protocol.js';
import { el } from './ui.js';

/** Level-of-detail labels, index = the generator's Lod. */
export const LODS = ['Low', 'Medium', 'High', 'Ultra'];

/** Groups with more parameters than this start folded, so the page stays calm. */
const FOLD_ABOVE = 12;
/** Undo history depth. */
const HISTORY = 200;

export class Editor extends EventTarget {
  /**
   * `client`: the WorkerClient; `viewer`: the Viewer; `specs`: the generator specs from the
   * worker; `root`: the element the sliders go in.
   */
  constructor({ client, viewer, specs, root }) {
    super();
    this.client = client;
    this.viewer = viewer;
    this.specs = new Map(specs.map((s) => [s.name, s]));
    this.root = root;
    this.spec = null;
    this.params = [];
    this.base = [];
    this.lod = 1;
    this.undoStack = [];
    this.redoStack = [];
    this.inputs = [];
    this.busy = false;
    this.dirty = false;
    this.dirtySince = null;
    this.reframe = false;
    this.glb = null;
    this.latencies = [];
    this.timings = [];
    this.cameras = [];
    /** @type {Record<string, number[]> | null} part colours from the photos (linear RGB) */
    this.colors = null;
    /** Whether the model shows `colors` (the "Colours from the photo" toggle) or the defaults. */
    this.useColors = true;
    /** A tree fit's carving of the leaves by its photo (the worker's id), or null. */
    this.carveId = null;
    /** Whether the leaves are carved (the "Carved by the photo" toggle). */
    this.useCarve = true;
  }

  /**
   * The state worth saving: generator, params, lod, cameras, the photos' part colours and
   * whether they are used. The worker writes `colors` into the model only when `useColors`.
   */
  get state() {
    return this.spec
      ? { generator: this.spec.name, params: this.params.slice(), lod: this.lod, cameras: this.cameras.slice(), colors: this.colors, useColors: this.useColors, carveId: this.useCarve ? this.carveId : null }
      : null;
  }

  /** Carves a fitted tree's leaves by its photo (true) or shows them all (false). */
  setUseCarve(on) {
    this.useCarve = on;
    this.schedule();
    this.emitChange();
  }

  /** Shows the photos' part colours (true) or the generator's defaults (false). */
  setUseColors(on) {
    this.useColors = on;
    this.schedule();
    this.emitChange();
  }

  /**
   * Shows `generator` with `params` (default: its defaults) as the new base ("reset" returns
   * here); clears the history. Throws for an unknown generator.
   */
  open(generator, params = null, lod = this.lod, cameras = [], colors = null, carveId = null) {
    const spec = this.specs.get(generator);
    if (!spec) throw new Error(`this build has no generator called “${generator}”`);
    const changedGenerator = this.spec?.name !== generator;
    this.spec = spec;
    this.params = params ? params.slice() : spec.params.map((p) => p.default);
    this.base = this.params.slice();
    this.lod = lod;
    // The photos' cameras from a fit go into every GLB of this model.
    this.cameras = cameras.slice();
    // Part colours belong to the model they were measured on: a new model keeps none.
    this.colors = colors && Object.keys(colors).length ? colors : null;
    this.useColors = true;
    // So does a tree fit's carving: it belongs to that fit's tree (edits keep it).
    this.carveId = carveId;
    this.useCarve = true;
    this.undoStack = [];
    this.redoStack = [];
    if (changedGenerator) this.buildSliders();
    this.syncInputs();
    this.reframe = true;
    this.schedule();
    this.emitChange();
  }

  /** Sets the level of detail and regenerates. */
  setLod(lod) {
    this.lod = lod;
    this.schedule();
    this.emitChange();
  }

  /** Records the current params for undo (call before a change that should be undoable). */
  remember() {
    this.undoStack.push(this.params.slice());
    if (this.undoStack.length > HISTORY) this.undoStack.shift();
    this.redoStack = [];
  }

  /** Replaces every parameter (a preset, reset): one undoable step. */
  setAll(values) {
    this.remember();
    this.params = values.slice();
    this.syncInputs();
    this.schedule();
    this.emitChange();
  }

  reset() {
    this.setAll(this.base);
  }

  undo() {
    if (!this.undoStack.length) return;
    this.redoStack.push(this.params.slice());
    this.params = this.undoStack.pop();
    this.syncInputs();
    this.schedule();
    this.emitChange();
  }

  redo() {
    if (!this.redoStack.length) return;
    this.undoStack.push(this.params.slice());
    this.params = this.redoStack.pop();
    this.syncInputs();
    this.schedule();
    this.emitChange();
  }

  emitChange() {
    this.dispatchEvent(new CustomEvent('change', { detail: this.state }));
  }

  /** One <details> per spec group, one labelled control per parameter. */
  buildSliders() {
    this.root.replaceChildren();
    this.inputs = [];
    const groups = new Map();
    this.spec.params.forEach((p, i) => {
      if (!groups.has(p.group)) groups.set(p.group, []);
      groups.get(p.group).push([p, i]);
    });
    for (const [group, items] of groups) {
      const body = el('div', { class: 'params' });
      const details = el('details', { class: 'group', open: items.length <= FOLD_ABOVE }, [
        el('summary', {}, [`${group} `, el('span', { class: 'muted' }, [`(${items.length})`])]),
        body,
      ]);
      for (const [p, i] of items) body.append(this.control(p, i));
      this.root.append(details);
    }
  }

  control(p, i) {
    const id = `param-${p.name}`;
    let input;
    const output = el('output', { for: id, class: 'value' });
    if (p.kind === 'boolean') {
      input = el('input', { type: 'checkbox', id, name: p.name });
    } else if (p.kind === 'categorical') {
      input = el('select', { id, name: p.name }, p.choices.map((c, k) => el('option', { value: k }, [c])));
    } else {
      const step = p.kind === 'integer' ? 1 : niceStep(p.max - p.min);
      input = el('input', { type: 'range', id, name: p.name, min: p.min, max: p.max, step });
    }
    input.dataset.index = i;
    const show = () => {
      if (p.kind === 'boolean') output.textContent = input.checked ? 'yes' : 'no';
      else if (p.kind === 'categorical') output.textContent = '';
      else output.textContent = formatValue(this.params[i], p);
    };
    const read = () =>
      p.kind === 'boolean' ? (input.checked ? 1 : 0) : Number(input.value);
    // `input` fires while dragging (live preview); the undo step is taken once per gesture.
    let gesture = false;
    input.addEventListener('input', () => {
      if (!gesture) {
        this.remember();
        gesture = true;
      }
      this.params[i] = read();
      show();
      this.schedule(performance.now());
    });
    input.addEventListener('change', () => {
      // A keyboard step fires input then change with the same value: one regeneration only.
      const v = read();
      if (!gesture) this.remember();
      gesture = false;
      if (v !== this.params[i]) {
        this.params[i] = v;
        show();
        this.schedule(performance.now());
      }
      this.emitChange();
    });
    this.inputs[i] = { input, show, p };
    const row = el('div', { class: `param param-${p.kind}` }, [
      el('label', { for: id }, [p.label, p.unit ? el('span', { class: 'muted' }, [` (${p.unit})`]) : '']),
      input,
      output,
    ]);
    return row;
  }

  syncInputs() {
    this.inputs.forEach(({ input, show, p }, i) => {
      if (p.kind === 'boolean') input.checked = this.params[i] >= 0.5;
      else input.value = String(this.params[i]);
      show();
    });
  }

  /** Marks the model dirty; `since` is when the user acted (for the latency measurement). */
  schedule(since = null) {
    this.dirty = true;
    if (since !== null && this.dirtySince === null) this.dirtySince = since;
    this.pump();
  }

  async pump() {
    if (this.busy || !this.dirty || !this.spec) return;
    this.busy = true;
    this.dirty = false;
    const since = this.dirtySince;
    this.dirtySince = null;
    const reframe = this.reframe;
    this.reframe = false;
    const request = this.state;
    try {
      const t0 = performance.now();
      const { glb, ms, carved } = await this.client.call(REQUESTS.GENERATE_GLB, request);
      const t1 = performance.now();
      // Keep a copy: GLTFLoader may hold on to the buffer, and the download must be these bytes.
      this.glb = { bytes: new Uint8Array(glb.slice(0)), ...request };
      const info = await this.viewer.load(glb, { reframe });
      const t2 = performance.now();
      const shownAt = await this.viewer.nextFrame();
      const latency = since === null ? null : shownAt - since;
      if (latency !== null) {
        // Where the time went: waiting for the pump, the worker (generate + GLB), the message
        // round trip, GLTFLoader, and the wait for the next frame.
        this.latencies.push(latency);
        this.timings.push({ lod: request.lod, latency, queued: t0 - since, worker: ms, trip: t1 - t0 - ms, parse: t2 - t1, frame: shownAt - t2 });
        if (this.latencies.length > 100) this.latencies.shift();
        if (this.timings.length > 100) this.timings.shift();
      }
      this.dispatchEvent(
        new CustomEvent('generated', { detail: { ...info, workerMs: ms, latency, bytes: this.glb.bytes.length, carved } }),
      );
    } catch (err) {
      this.dispatchEvent(new CustomEvent('error', { detail: err }));
    } finally {
      this.busy = false;
    }
    if (this.dirty) this.pump();
    else this.dispatchEvent(new CustomEvent('idle'));
  }

  /** Resolves once every scheduled change is on screen. */
  settled() {
    if (!this.busy && !this.dirty) return Promise.resolve();
    return /** @type {Promise<void>} */ (new Promise((resolve) => this.addEventListener('idle', () => resolve(), { once: true })));
  }
}

/** A decimal step near span/1000 (1, 2 or 5 × 10^k), so slider values stay short decimals. */
function niceStep(span) {
  const raw = span / 1000;
  const k = Math.pow(10, Math.floor(Math.log10(raw)));
  const m = raw / k;
  const step = (m < 2 ? 1 : m < 5 ? 2 : 5) * k;
  // Round away binary noise such as 0.00020000000000000001.
  return Number(step.toPrecision(1));
}

function formatValue(v, p) {
  if (p.kind === 'integer') return String(Math.round(v));
  const span = Math.abs(p.max - p.min);
  const digits = span >= 100 ? 0 : span >= 10 ? 1 : span >= 1 ? 2 : 3;
  return `${v.toFixed(digits)}${p.unit && p.unit !== '°' ? ' ' + p.unit : p.unit}`;
}
