// @ts-check
// The model step: the generator choice (one per spec, by its display name, then Automatic),
// presets, the live editor with its 3D view, level of detail, wireframe, part colours,
// undo/redo/reset (also from the keyboard), and opening a GLB or params JSON to edit.
import { REQUESTS } from './protocol.js';
import { el, say } from './ui.js';
import { Viewer } from './viewer.js';
import { Editor, LODS } from './editor.js';
import { $, client, state } from './page.js';
import { persist } from './persistence.js';
import { renderWindowTools } from './windows-ui.js';
import { renderTreeLabels } from './tree-colors-ui.js';
import { updateFitButton } from './fit-step.js';
import { recutForKind } from './mask-step.js';

const modelMessage = $('model-message');
const outMessage = $('out-message');

/** One choice per generator, by the name its spec gives it, then Automatic. */
export function buildGeneratorChoices() {
  const box = $('generators');
  for (const spec of state.specs) {
    const input = el('input', { type: 'radio', name: 'generator', value: spec.name, id: `gen-${spec.name}` });
    input.addEventListener('change', () => chooseGenerator(spec.name));
    box.append(el('label', { class: 'choice', for: `gen-${spec.name}` }, [input, ' ', spec.display_name]));
  }
  const auto = el('input', { type: 'radio', name: 'generator', value: 'auto', id: 'gen-auto' });
  auto.addEventListener('change', () => {
    renderWindowTools();
    renderTreeLabels();
    updateFitButton();
  });
  box.append(el('label', { class: 'choice', for: 'gen-auto' }, [auto, ' Automatic ', el('span', { class: 'muted' }, ['(the fit picks)'])]));
}

/**
 * The preset choice of `spec`, with `selected` chosen.
 * @param {import("./page.js").GeneratorSpec} spec
 * @param {string} selected
 */
function fillPresets(spec, selected) {
  const select = $('preset');
  select.replaceChildren(
    el('option', { value: '' }, ['Defaults']),
    ...spec.presets.map((p) => el('option', { value: p.name }, [p.label])),
  );
  if (selected === 'custom') select.append(el('option', { value: 'custom' }, ['Opened file']));
  if (selected === 'fitted') select.append(el('option', { value: 'fitted' }, ['Fitted to the photos']));
  select.value = selected ?? '';
}

/**
 * Switches to `name` with its first preset (or defaults), or with the given parameters.
 * @param {string} name
 * `carveId`: a tree fit's carving of the leaves by its photo (the worker's `carve_id`).
 * @param {{ params?: number[] | null, lod?: number | null, preset?: string, cameras?: number[], colors?: Record<string, number[]> | null, carveId?: number | null }} [o]
 */
export function chooseGenerator(name, { params = null, lod = null, preset = undefined, cameras = [], colors = null, carveId = null } = {}) {
  const spec = state.specs.find((g) => g.name === name);
  if (!spec) return;
  $(`gen-${name}`).checked = true;
  const first = preset === undefined ? spec.presets[0] : null;
  fillPresets(spec, preset ?? first?.name ?? '');
  state.presetName = preset ?? first?.name ?? null;
  state.editor.open(name, params ?? first?.values ?? null, lod ?? state.editor.lod, cameras, colors, carveId);
  showPhotoColors();
  $('lod').value = String(state.editor.lod);
  renderWindowTools();
  renderTreeLabels();
  updateFitButton();
  // Automatic masks are cut for the object kind (a building's outline is cut closer).
  recutForKind();
}

$('preset').addEventListener('change', (e) => {
  const spec = state.editor.spec;
  const preset = spec.presets.find((p) => p.name === e.target.value);
  state.presetName = preset?.name ?? null;
  // A preset is a new starting point: reset returns to it; undo still goes back.
  state.editor.setAll(preset ? preset.values : spec.params.map((p) => p.default));
  state.editor.base = state.editor.params.slice();
});

function updateButtons() {
  const ed = state.editor;
  $('undo').disabled = !ed.undoStack.length;
  $('redo').disabled = !ed.redoStack.length;
}

/**
 * The "Colours from the photo" toggle: shown when the model has colours from photos, checked
 * when they are used.
 */
export function showPhotoColors() {
  const ed = state.editor;
  $('photo-colors-label').hidden = !ed.colors;
  /** @type {HTMLInputElement} */ ($('photo-colors')).checked = ed.useColors;
  $('carve-leaves-label').hidden = !ed.carveId;
  /** @type {HTMLInputElement} */ ($('carve-leaves')).checked = ed.useCarve;
}

/** @param {File} file */
export async function openModelFile(file) {
  say(outMessage, '');
  try {
    const bytes = await file.arrayBuffer();
    const m = await client.call(REQUESTS.OPEN_MODEL, { bytes }, { transfer: [bytes] });
    chooseGenerator(m.generator, { params: m.params, lod: m.lod, preset: 'custom', colors: m.colors });
    say(outMessage, `Opened “${file.name}”. Edit it above.`, 'info');
    $('step-model').scrollIntoView({ behavior: 'smooth', block: 'start' });
  } catch (err) {
    say(outMessage, `Could not open “${file.name}”: ${err.message}. procfit opens the GLB and JSON files it saved itself.`);
  }
}

/** The model step: its viewer, its editor and their controls. */
export function setUpModelStep() {
  const viewer = new Viewer($('viewer'));
  const editor = new Editor({ client, viewer, specs: state.specs, root: $('sliders') });
  state.viewer = viewer;
  state.editor = editor;
  window.procfit.viewer = viewer;
  window.procfit.editor = editor;

  const lod = $('lod');
  LODS.forEach((name, i) => lod.append(el('option', { value: i }, [name])));
  lod.value = String(editor.lod);
  lod.addEventListener('change', () => editor.setLod(Number(lod.value)));

  $('wireframe').addEventListener('change', (e) => viewer.setWireframe(e.target.checked));
  $('part-colors').addEventListener('change', (e) => {
    viewer.setPartColors(e.target.checked);
    renderLegend();
  });
  $('photo-colors').addEventListener('change', (e) => editor.setUseColors(e.target.checked));
  $('carve-leaves').addEventListener('change', (e) => editor.setUseCarve(e.target.checked));
  $('reframe').addEventListener('click', () => viewer.frame());
  $('undo').addEventListener('click', () => editor.undo());
  $('redo').addEventListener('click', () => editor.redo());
  $('reset').addEventListener('click', () => editor.reset());

  editor.addEventListener('change', () => {
    updateButtons();
    persist();
  });
  editor.addEventListener('generated', (/** @type {CustomEvent} */ e) => {
    const d = e.detail;
    say(modelMessage, '');
    $('download-glb').disabled = false;
    $('download-json').disabled = false;
    const latency = d.latency === null ? '' : ` · updated in ${Math.round(d.latency)} ms`;
    // A carving the worker no longer has (a fresh worker, a later tree fit): the toggle goes.
    if (editor.carveId && editor.useCarve && !d.carved) {
      editor.carveId = null;
      showPhotoColors();
    }
    const carved = d.carved ? ' · carved by the photo' : '';
    $('viewer-info').textContent = `${d.parts.length} part${d.parts.length === 1 ? '' : 's'} · ${d.triangles.toLocaleString('en')} triangles · ${(d.bytes / 1024).toFixed(0)} KB${latency}${carved}`;
    renderLegend();
    updateButtons();
    // Every shown model is worth keeping (a drag fires no change event until it ends).
    persist();
  });
  editor.addEventListener('error', (/** @type {CustomEvent} */ e) => {
    say(modelMessage, `The model could not be built: ${e.detail.message}`);
  });

  function renderLegend() {
    const legend = $('legend');
    legend.replaceChildren();
    if (!viewer.partColors) return;
    viewer.parts.forEach((name, i) =>
      legend.append(el('span', { class: 'swatch' }, [el('i', { style: `background:${viewer.partColor(i)}` }), name])),
    );
  }

  // Undo/redo from the keyboard, except where the key means something to a text field.
  window.addEventListener('keydown', (e) => {
    if (!(e.ctrlKey || e.metaKey) || e.altKey) return;
    const t = e.target;
    if (t instanceof HTMLInputElement && !['range', 'checkbox', 'radio', 'button'].includes(t.type)) return;
    if (t instanceof HTMLTextAreaElement) return;
    const key = e.key.toLowerCase();
    if (key === 'z' && !e.shiftKey) {
      e.preventDefault();
      editor.undo();
    } else if ((key === 'z' && e.shiftKey) || key === 'y') {
      e.preventDefault();
      editor.redo();
    }
  });
}
