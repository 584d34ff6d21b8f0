// The page's entry point (main thread): draws and listens, never runs wasm. All work goes to
// the worker through WorkerClient. This file wires the steps together: photos in (drop, pick,
// paste, camera, samples) → generator → the live model editor → download / open.
import { WorkerClient } from './client.js';
import { REQUESTS } from './protocol.js';
import { el, say, download, stem } from './ui.js';
import { loadPhoto, isModelFile, MAX_PHOTOS, reserveIds } from './photos.js';
import * as store from './store.js';
import { CameraCapture } from './camera.js';
import { Viewer } from './viewer.js';
import { Editor, LODS } from './editor.js';
import { MaskEditor, autoMask, reviveMask, detectWindows, windowsAfterMask, treeLabels, treeColors, AUTUMN_CHANGE, WINDOW } from './masking.js';
import { FitRunner } from './fitting.js';
import { initDownloadMenu } from './download.js';

const $ = (id) => document.getElementById(id);
const client = new WorkerClient();
const status = $('status');
const state = { photos: [], selected: null, specs: [], editor: null, viewer: null, presetName: null };

// A handle for the browser tests and the curious: the page's worker client and protocol.
window.procfit = { client, REQUESTS, state };

client.addEventListener('status', (e) => {
  const d = e.detail;
  status.dataset.state = d.state;
  if (d.state === 'ready') {
    status.textContent = `ready — ${d.threads} thread${d.threads === 1 ? '' : 's'}`;
    const notice = $('notice');
    notice.hidden = d.threaded;
    notice.textContent = d.threaded
      ? ''
      : 'procfit is running on one thread: this page is served without cross-origin isolation (COOP/COEP headers), so it cannot use all your cores. Everything works; fits take longer.';
    // After a crash the worker is new but the session lives here: show the model again and
    // give each mask a worker session for corrections.
    if (client.restarts > 0) {
      state.editor?.schedule();
      reviveMasks();
    }
  } else if (d.state === 'starting') {
    status.textContent = 'starting…';
  } else if (d.state === 'crashed') {
    status.textContent = `restarting after an error: ${d.error.message}`;
  } else if (d.state === 'failed') {
    status.textContent = `could not start: ${d.error.message}`;
  }
});

// ---- Photos -------------------------------------------------------------------------------

const photosMessage = $('photos-message');

/** Takes files from any source: photos join the list, a GLB/JSON opens as a model. */
async function addFiles(files, source = 'file') {
  say(photosMessage, '');
  const list = [...files];
  if (!list.length) {
    say(photosMessage, source === 'paste' ? 'The clipboard holds no image. Copy a photo, then paste again.' : 'No file came through. Try again, or use “Choose photos…”.');
    return;
  }
  const problems = [];
  for (const file of list) {
    if (isModelFile(file)) {
      await openModelFile(file);
      continue;
    }
    if (state.photos.length >= MAX_PHOTOS) {
      problems.push(`procfit takes up to ${MAX_PHOTOS} photos; remove one to add “${file.name}”.`);
      continue;
    }
    try {
      addPhoto(await photoOf(file, file.name || `pasted ${state.photos.length + 1}.png`));
    } catch (err) {
      problems.push(err.message);
    }
  }
  if (problems.length) say(photosMessage, problems.join(' '));
}

/** A photo from `file`, with the EXIF focal length of the original file (downscaling drops it). */
async function photoOf(file, name) {
  const photo = await loadPhoto(file, name);
  photo.focal35mm = null;
  try {
    const bytes = await file.arrayBuffer();
    photo.focal35mm = (await client.call(REQUESTS.PHOTO_FOCAL, { bytes }, { transfer: [bytes] })).focal_35mm;
  } catch {
    // No focal length: the fit uses its default field of view, as for a photo without EXIF.
  }
  return photo;
}

function addPhoto(photo) {
  state.photos.push(photo);
  selectPhoto(photo.id);
  findMask(photo);
  persist();
}

/**
 * Worker sessions for masks the page already has (after a restore or a worker restart), with
 * the photo's corrections replayed so the next one builds on them.
 */
function reviveMasks() {
  for (const p of state.photos) {
    if (p.mask) {
      p.reviving = reviveMask(client, p).catch(() => {});
    }
  }
}

// ---- Persistence ----------------------------------------------------------------------------

let persistTimer = null;
/** Saves the session to IndexedDB a moment after the last change (many changes → one write). */
function persist() {
  clearTimeout(persistTimer);
  persistTimer = setTimeout(async () => {
    if (!state.editor?.state || state.clearing) return;
    // For the browser tests: when the last save that finished had started.
    const started = Date.now();
    try {
      await store.save({
        photos: await Promise.all(state.photos.map(store.photoRecord)),
        selected: state.selected,
        step: state.step ?? null,
        model: { ...state.editor.state, base: state.editor.base, presetName: state.presetName },
      });
      document.body.dataset.saved = String(started);
    } catch (err) {
      say($('notice'), `Your work could not be saved on this device (${err.message}); it stays until you close the page.`, 'info');
    }
  }, 400);
}

/** Restores the saved session, if any; says so with a way to start over. */
async function restore() {
  const rec = await store.load();
  if (!rec) return false;
  const photos = [];
  for (const r of rec.photos ?? []) {
    try {
      photos.push(await store.photoFromRecord(r));
    } catch {
      // A photo that cannot be decoded any more is dropped; the rest of the session stays.
    }
  }
  photos.forEach((p) => reserveIds(p.id));
  state.photos = photos;
  state.selected = photos.some((p) => p.id === rec.selected) ? rec.selected : photos[0]?.id ?? null;
  renderPhotos();
  reviveMasks();
  // Photos saved before their mask was ready get one now.
  photos.filter((p) => !p.mask).forEach(findMask);
  const m = rec.model;
  if (m && state.specs.some((g) => g.name === m.generator)) {
    chooseGenerator(m.generator, { params: m.params, lod: m.lod, preset: m.presetName ?? 'custom', cameras: m.cameras ?? [] });
    if (Array.isArray(m.base) && m.base.length === m.params.length) state.editor.base = m.base;
  }
  // Back to the step the person was working in.
  const step = rec.step && document.getElementById(rec.step);
  if (step?.classList.contains('step')) {
    state.step = rec.step;
    step.scrollIntoView({ block: 'start' });
  }
  $('restored-text').textContent = `Restored your last session${photos.length ? ` (${photos.length} photo${photos.length === 1 ? '' : 's'})` : ''}.`;
  $('restored').hidden = false;
  return true;
}

// The step a person works in is the last one they touched (kept with the session).
for (const type of ['pointerdown', 'focusin']) {
  document.addEventListener(type, (e) => {
    const step = e.target instanceof Element ? e.target.closest('section.step') : null;
    if (step && step.id !== state.step) {
      state.step = step.id;
      persist();
    }
  });
}

$('start-over').addEventListener('click', async () => {
  // No save may follow the clear (IndexedDB runs a store's transactions in order, so one
  // already in flight lands before it).
  state.clearing = true;
  clearTimeout(persistTimer);
  await store.clear().catch(() => {});
  location.reload();
});

/** Runs the automatic mask for `photo`, keeping the page told. */
async function findMask(photo) {
  photo.maskState = 'working';
  renderMaskState();
  try {
    await autoMask(client, photo);
    // A new mask: windows found automatically are found again, painted ones clipped to it.
    await windowsAfterMask(client, photo);
    photo.maskState = 'ready';
  } catch (err) {
    photo.maskState = 'failed';
    photo.maskError = err.message;
  }
  if (!state.photos.includes(photo)) {
    client.call(REQUESTS.MASK_DROP, { key: String(photo.id) }).catch(() => {});
    return;
  }
  if (state.selected === photo.id) maskEditor.setPhoto(photo);
  renderMaskState();
  persist();
}

/**
 * The windows tools: shown for buildings, with how much of the building is marked as window and
 * what the last mask correction did to the windows (found again, or painted ones clipped).
 */
function renderWindowTools() {
  const photo = state.photos.find((p) => p.id === state.selected);
  const building = fitGenerator() === 'building';
  const tools = $('window-tools');
  tools.hidden = !building || !photo?.mask;
  if (tools.hidden && ['window', 'wall'].includes(maskEditor.tool)) {
    document.querySelector('input[name="tool"][value="none"]').checked = true;
    maskEditor.setTool('none');
  }
  if (maskEditor.showWindows !== building) {
    maskEditor.showWindows = building;
    maskEditor.draw();
  }
  const codes = photo?.windows?.codes;
  $('windows-clear').disabled = !codes;
  const note = photo?.windowsNote ? ` ${photo.windowsNote}` : '';
  if (!codes) {
    $('windows-state').textContent = `No windows marked yet.${note}`;
    return;
  }
  let win = 0;
  let inside = 0;
  for (const c of codes) {
    if (c === WINDOW) win += 1;
    if (c === 1 || c === WINDOW) inside += 1;
  }
  $('windows-state').textContent = `${
    win
      ? `Windows marked in teal: ${Math.round((100 * win) / Math.max(1, inside))} % of the building.`
      : 'No windows found: paint a few with the windows brush.'
  }${note}`;
}

/**
 * For trees: the branch / leaf labels the fit will see, over the photo, with their shares. They
 * are made again when the photo or its mask changes.
 */
function renderTreeLabels() {
  const photo = state.photos.find((p) => p.id === state.selected);
  const tree = fitGenerator() === 'tree';
  const line = $('tree-state');
  line.hidden = !tree || !photo?.mask;
  $('tree-colors').hidden = line.hidden;
  if (maskEditor.showTree !== tree) {
    maskEditor.showTree = tree;
    maskEditor.draw();
  }
  if (line.hidden) return;
  showTreeColors(photo);
  const labels = photo.treeLabels;
  const colorsKey = JSON.stringify(treeColors(client, photo));
  // Made again when the mask or the colours change (an error counts as an answer too).
  if (photo.treeLabelsFor !== photo.mask.codes || photo.treeLabelsColors !== colorsKey) {
    line.textContent = 'Sorting branches from leaves…';
    // One request at a time; the last one's answer is checked against the photo's colours
    // and mask again, so quick slider moves end with the labels of the final values.
    if (photo.treeLabelsPending) return;
    photo.treeLabelsPending = true;
    const codes = photo.mask.codes;
    treeLabels(client, photo)
      .then(() => {
        photo.treeError = null;
      })
      .catch((err) => {
        photo.treeLabels = null;
        photo.treeError = err.message;
      })
      .finally(() => {
        photo.treeLabelsFor = codes;
        photo.treeLabelsColors = colorsKey;
        photo.treeLabelsPending = false;
        if (state.selected !== photo.id) return;
        maskEditor.draw();
        renderTreeLabels();
      });
    return;
  }
  if (photo.treeError) {
    line.textContent = `The tree fit cannot use this photo: ${photo.treeError}`;
    return;
  }
  let branch = 0;
  let leaf = 0;
  for (const l of labels) {
    if (l === 1) branch += 1;
    else if (l === 2) leaf += 1;
  }
  const all = Math.max(1, branch + leaf);
  const missing = !leaf ? 'No leaves found by their colour: if they are not green, open "Adjust the colours" (autumn leaves, say). ' : !branch ? 'No trunk or branches found by their colour: open "Adjust the colours" (or count everything else inside the mask as branches). ' : '';
  line.textContent = `${missing}What the tree fit sees, by colour: branches in brown (${Math.round((100 * branch) / all)} %), leaves in green (${Math.round((100 * leaf) / all)} %). Trees are fitted to one photo, the first.`;
}

/** The "Adjust the colours" controls show `photo`'s colour rules. */
function showTreeColors(photo) {
  const c = treeColors(client, photo);
  const set = (id, v, text) => {
    $(id).value = String(v);
    $(`${id}-out`).textContent = text;
  };
  set('leaf-hue-from', c.leafHue[0], `${c.leafHue[0]}°`);
  set('leaf-hue-to', c.leafHue[1], `${c.leafHue[1]}°`);
  set('leaf-min-value', c.leafMinValue, c.leafMinValue.toFixed(2));
  set('leaf-min-saturation', c.leafMinSaturation, c.leafMinSaturation.toFixed(2));
  set('bark-max-value', c.barkValue[1], c.barkValue[1].toFixed(2));
  $('rest-as-branch').checked = c.restAsBranch;
  // The hue strip: the chosen leaf hues bright, the rest faded (a range may wrap through red).
  const strip = $('leaf-hue-strip');
  const ctx = strip.getContext('2d');
  const [lo, hi] = c.leafHue;
  for (let h = 0; h < 360; h += 1) {
    const on = lo <= hi ? h >= lo && h <= hi : h >= lo || h <= hi;
    ctx.fillStyle = `hsl(${h} ${on ? 75 : 18}% ${on ? 45 : 80}%)`;
    ctx.fillRect(h, 0, 1, strip.height);
  }
}

/** Changes the selected photo's colour rules and sorts its pixels again. */
function changeTreeColors(change) {
  const photo = state.photos.find((p) => p.id === state.selected);
  if (!photo) return;
  photo.treeColors = change === null ? null : { ...treeColors(client, photo), ...change };
  renderTreeLabels();
  persist();
}

for (const [id, field] of [['leaf-min-value', 'leafMinValue'], ['leaf-min-saturation', 'leafMinSaturation']]) {
  $(id).addEventListener('input', (e) => changeTreeColors({ [field]: Number(e.target.value) }));
}
$('leaf-hue-from').addEventListener('input', (e) => changeTreeColors({ leafHue: [Number(e.target.value), Number($('leaf-hue-to').value)] }));
$('leaf-hue-to').addEventListener('input', (e) => changeTreeColors({ leafHue: [Number($('leaf-hue-from').value), Number(e.target.value)] }));
$('bark-max-value').addEventListener('input', (e) => changeTreeColors({ barkValue: [client.info.treeColors.barkValue[0], Number(e.target.value)] }));
$('rest-as-branch').addEventListener('change', (e) => changeTreeColors({ restAsBranch: e.target.checked }));
$('colors-autumn').addEventListener('click', () => changeTreeColors({ ...client.info.treeColors, ...AUTUMN_CHANGE }));
$('colors-reset').addEventListener('click', () => changeTreeColors(null));

function renderMaskState() {
  const box = $('mask-state');
  const photo = state.photos.find((p) => p.id === state.selected);
  $('mask-tools').hidden = !photo?.mask;
  renderWindowTools();
  renderTreeLabels();
  box.dataset.kind = '';
  if (!photo) box.textContent = '';
  else if (photo.maskState === 'working') box.textContent = 'Finding the object…';
  else if (photo.maskState === 'failed') {
    box.textContent = `No object found: ${photo.maskError}. Try a photo with the object in the middle against a plain background, or draw a box around it.`;
    box.dataset.kind = 'warn';
  } else if (photo.mask) {
    const m = photo.mask;
    const pct = Math.round(100 * m.confidence);
    if (m.low_confidence) {
      box.dataset.kind = 'warn';
      box.textContent = `Please check the mask (confidence ${pct} %)${m.warnings.length ? ': ' + m.warnings.join('; ') : ''}. Blue is the object, dark is background, amber is ignored. If it is wrong, draw a box around the object or paint it with the object brush — or use a photo with a plainer background.`;
    } else {
      box.textContent = `Object found (confidence ${pct} %). Blue is the object, dark is background, amber is ignored. Correct it with the tools below if needed.`;
    }
  }
  updateFitButton();
}

function selectPhoto(id) {
  state.selected = id;
  renderPhotos();
  persist();
}

function removePhoto(id) {
  const i = state.photos.findIndex((p) => p.id === id);
  if (i < 0) return;
  state.photos[i].bitmap.close();
  state.photos.splice(i, 1);
  client.call(REQUESTS.MASK_DROP, { key: String(id) }).catch(() => {});
  persist();
  if (state.selected === id) state.selected = state.photos[Math.max(0, i - 1)]?.id ?? null;
  renderPhotos();
}

function renderPhotos() {
  const thumbs = $('thumbs');
  thumbs.replaceChildren();
  for (const [k, p] of state.photos.entries()) {
    const c = el('canvas', { width: 96, height: Math.round((96 * p.height) / p.width) });
    c.getContext('2d').drawImage(p.bitmap, 0, 0, c.width, c.height);
    const pick = el('button', { type: 'button', class: 'thumb', 'aria-pressed': p.id === state.selected, 'aria-label': `Show photo ${k + 1}: ${p.name}` }, [c]);
    pick.addEventListener('click', () => selectPhoto(p.id));
    const remove = el('button', { type: 'button', class: 'remove', 'aria-label': `Remove photo ${k + 1}: ${p.name}` }, ['×']);
    remove.addEventListener('click', () => removePhoto(p.id));
    thumbs.append(el('li', {}, [pick, remove]));
  }
  const photo = state.photos.find((p) => p.id === state.selected);
  $('photo-view').hidden = !photo;
  $('mask-empty').hidden = !!photo;
  maskEditor.setPhoto(photo ?? null);
  renderMaskState();
  if (!photo) return;
  const canvas = $('photo-canvas');
  canvas.width = photo.width;
  canvas.height = photo.height;
  canvas.getContext('2d').drawImage(photo.bitmap, 0, 0);
  // Portrait photos stay within the screen's height; the mask overlay follows the photo.
  document.querySelector('#photo-view .stack').style.maxWidth = `calc(75vh * ${photo.width / photo.height})`;
  $('photo-caption').textContent = `${photo.name} — ${photo.width}×${photo.height} px${photo.focal35mm ? ` · fov from EXIF: ${Math.round(photo.focal35mm)} mm` : ''}${state.photos.length > 1 ? ` · photo ${state.photos.indexOf(photo) + 1} of ${state.photos.length}` : ''}`;
}

$('file').addEventListener('change', async (e) => {
  await addFiles(e.target.files);
  e.target.value = '';
});

// Drag and drop anywhere on the page; the overlay says what a drop will do.
let dragDepth = 0;
const overlay = $('drop-overlay');
const carriesFiles = (e) => [...(e.dataTransfer?.types || [])].includes('Files');
window.addEventListener('dragenter', (e) => {
  if (!carriesFiles(e)) return;
  e.preventDefault();
  dragDepth += 1;
  overlay.hidden = false;
});
window.addEventListener('dragover', (e) => {
  if (!carriesFiles(e)) return;
  e.preventDefault();
  e.dataTransfer.dropEffect = 'copy';
});
window.addEventListener('dragleave', () => {
  dragDepth = Math.max(0, dragDepth - 1);
  if (!dragDepth) overlay.hidden = true;
});
window.addEventListener('drop', (e) => {
  e.preventDefault();
  dragDepth = 0;
  overlay.hidden = true;
  addFiles(e.dataTransfer?.files || []);
});
window.addEventListener('paste', (e) => {
  const files = [...(e.clipboardData?.files || [])];
  // A paste into a text field is the field's business unless it carries an image.
  if (!files.length && e.target instanceof HTMLInputElement) return;
  e.preventDefault();
  addFiles(files, 'paste');
});

const camera = new CameraCapture({
  onShot: async (blob, name) => {
    try {
      addPhoto(await photoOf(blob, name));
    } catch (err) {
      say(photosMessage, err.message);
    }
  },
  onError: (message) => say(photosMessage, message),
});
const maskEditor = new MaskEditor({
  overlay: $('mask-canvas'),
  client,
  onChange: () => {
    renderMaskState();
    persist();
  },
  onError: (message) => say(photosMessage, message),
});
document.querySelectorAll('input[name="tool"]').forEach((r) =>
  r.addEventListener('change', () => r.checked && maskEditor.setTool(r.value)),
);
$('brush').addEventListener('input', (e) => (maskEditor.brush = Number(e.target.value)));
$('mask-show').addEventListener('change', (e) => {
  maskEditor.show = e.target.checked;
  maskEditor.draw();
});
$('mask-auto').addEventListener('click', () => {
  const photo = state.photos.find((p) => p.id === state.selected);
  if (photo) findMask(photo);
});
$('windows-auto').addEventListener('click', async () => {
  const photo = state.photos.find((p) => p.id === state.selected);
  if (!photo?.mask) return;
  say(photosMessage, '');
  $('windows-state').textContent = 'Looking for windows…';
  try {
    await photo.reviving;
    await detectWindows(client, photo);
  } catch (err) {
    say(photosMessage, `No windows found: ${err.message}. Paint a few with the windows brush.`);
  }
  maskEditor.draw();
  renderWindowTools();
  persist();
});
$('windows-clear').addEventListener('click', () => {
  const photo = state.photos.find((p) => p.id === state.selected);
  if (!photo) return;
  photo.windows = null;
  photo.windowsNote = '';
  maskEditor.draw();
  renderWindowTools();
  persist();
});
window.procfit.maskEditor = maskEditor;

$('camera-open').addEventListener('click', () => {
  say(photosMessage, '');
  camera.open();
});

/** The bundled samples (www/samples/index.json): a photo and the generator it shows. */
async function loadSamples() {
  const box = $('samples');
  let list;
  try {
    const res = await fetch('www/samples/index.json');
    if (!res.ok) throw new Error(res.statusText);
    list = (await res.json()).samples;
  } catch {
    box.hidden = true;
    return;
  }
  for (const s of list) {
    const b = el('button', { type: 'button', class: 'sample', 'data-sample': s.name }, [
      el('img', { src: `www/samples/${s.thumb || s.file}`, alt: '', width: 48, height: 48 }),
      s.label,
    ]);
    b.addEventListener('click', () => openSample(s));
    box.append(b);
  }
}

async function openSample(s) {
  say(photosMessage, '');
  try {
    const res = await fetch(`www/samples/${s.file}`);
    if (!res.ok) throw new Error(`the sample is missing (${res.status})`);
    addPhoto(await photoOf(await res.blob(), s.file));
    if (state.specs.some((g) => g.name === s.generator)) chooseGenerator(s.generator);
  } catch (err) {
    say(photosMessage, `Could not open the sample: ${err.message}`);
  }
}

// ---- Generator, model, download ---------------------------------------------------------------

const modelMessage = $('model-message');
const outMessage = $('out-message');

/** Every generator the issue names; those this build lacks are shown, disabled. */
const KNOWN = [
  ['dish', 'Cup, mug or bowl'],
  ['building', 'Building'],
  ['tree', 'Tree'],
];

function buildGeneratorChoices() {
  const box = $('generators');
  for (const [name, label] of KNOWN) {
    const spec = state.specs.find((g) => g.name === name);
    const input = el('input', { type: 'radio', name: 'generator', value: name, id: `gen-${name}`, disabled: !spec });
    input.addEventListener('change', () => chooseGenerator(name));
    box.append(el('label', { class: 'choice', for: `gen-${name}` }, [input, ' ', spec ? label : `${label} `, spec ? '' : el('span', { class: 'muted' }, ['(not in this build yet)'])]));
  }
  const auto = el('input', { type: 'radio', name: 'generator', value: 'auto', id: 'gen-auto' });
  auto.addEventListener('change', () => {
    renderWindowTools();
    renderTreeLabels();
    updateFitButton();
  });
  box.append(el('label', { class: 'choice', for: 'gen-auto' }, [auto, ' Automatic ', el('span', { class: 'muted' }, ['(the fit picks)'])]));
  for (const spec of state.specs.filter((g) => !KNOWN.some(([n]) => n === g.name))) {
    const input = el('input', { type: 'radio', name: 'generator', value: spec.name, id: `gen-${spec.name}` });
    input.addEventListener('change', () => chooseGenerator(spec.name));
    box.append(el('label', { class: 'choice', for: `gen-${spec.name}` }, [input, ' ', spec.label]));
  }
}

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

/** Switches to `name` with its first preset (or defaults). */
function chooseGenerator(name, { params = null, lod = null, preset = undefined, cameras = [] } = {}) {
  const spec = state.specs.find((g) => g.name === name);
  if (!spec) return;
  $(`gen-${name}`).checked = true;
  const first = preset === undefined ? spec.presets[0] : null;
  fillPresets(spec, preset ?? first?.name ?? '');
  state.presetName = preset ?? first?.name ?? null;
  state.editor.open(name, params ?? first?.values ?? null, lod ?? state.editor.lod, cameras);
  $('lod').value = String(state.editor.lod);
  renderWindowTools();
  renderTreeLabels();
  updateFitButton();
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

async function openModelFile(file) {
  say(outMessage, '');
  try {
    const bytes = await file.arrayBuffer();
    const m = await client.call(REQUESTS.OPEN_MODEL, { bytes }, { transfer: [bytes] });
    chooseGenerator(m.generator, { params: m.params, lod: m.lod, preset: 'custom' });
    say(outMessage, `Opened “${file.name}”. Edit it above.`, 'info');
    $('step-model').scrollIntoView({ behavior: 'smooth', block: 'start' });
  } catch (err) {
    say(outMessage, `Could not open “${file.name}”: ${err.message}. procfit opens the GLB and JSON files it saved itself.`);
  }
}

function fileStem() {
  const st = state.editor.state;
  return stem(`${st.generator}${state.presetName && !['custom', 'fitted'].includes(state.presetName) ? '-' + state.presetName : ''}-${LODS[st.lod].toLowerCase()}`);
}

$('download-glb').addEventListener('click', async () => {
  await state.editor.settled();
  const glb = state.editor.glb;
  if (!glb) return;
  download(glb.bytes, `${fileStem()}.glb`, 'model/gltf-binary');
});

initDownloadMenu({ client, editor: () => state.editor, fileStem, onError: (m) => say(outMessage, m) });

$('download-json').addEventListener('click', async () => {
  try {
    const { text } = await client.call(REQUESTS.PARAMS_JSON, state.editor.state);
    download(text, `${fileStem()}.json`, 'application/json');
  } catch (err) {
    say(outMessage, `Could not save the parameters: ${err.message}`);
  }
});

$('open-model').addEventListener('change', async (e) => {
  const file = e.target.files[0];
  e.target.value = '';
  if (file) await openModelFile(file);
});

function setUpModelStep() {
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
  $('reframe').addEventListener('click', () => viewer.frame());
  $('undo').addEventListener('click', () => editor.undo());
  $('redo').addEventListener('click', () => editor.redo());
  $('reset').addEventListener('click', () => editor.reset());

  editor.addEventListener('change', () => {
    updateButtons();
    persist();
  });
  editor.addEventListener('generated', (e) => {
    const d = e.detail;
    say(modelMessage, '');
    $('download-glb').disabled = false;
    $('download-json').disabled = false;
    const latency = d.latency === null ? '' : ` · updated in ${Math.round(d.latency)} ms`;
    $('viewer-info').textContent = `${d.parts.length} part${d.parts.length === 1 ? '' : 's'} · ${d.triangles.toLocaleString('en')} triangles · ${(d.bytes / 1024).toFixed(0)} KB${latency}`;
    renderLegend();
    updateButtons();
    // Every shown model is worth keeping (a drag fires no change event until it ends).
    persist();
  });
  editor.addEventListener('error', (e) => {
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

// ---- Fit ------------------------------------------------------------------------------------

const fitMessage = $('fit-message');
const fitter = new FitRunner({
  client,
  els: { stage: $('fit-stage'), eta: $('fit-eta'), bar: $('fit-bar'), preview: $('fit-preview'), curve: $('fit-curve'), box: $('fit-progress'), caption: $('fit-preview-caption') },
});
window.procfit.fitter = fitter;

function fitGenerator() {
  return document.querySelector('input[name="generator"]:checked')?.value ?? 'auto';
}

function updateFitButton() {
  const ready = state.photos.length > 0 && state.photos.every((p) => p.mask);
  const button = $('fit-start');
  button.disabled = !ready || !!fitter.running || !state.editor;
  button.title = ready ? '' : 'Add a photo and wait for its mask first';
  const refit = $('refit');
  // Trees are not differentiable but have their own fit, which can start from a tree too.
  const tree = state.editor?.spec?.name === 'tree';
  const fittable = !!state.editor?.spec?.differentiable || tree;
  refit.disabled = button.disabled || !fittable;
  refit.title = !ready
    ? button.title
    : !fittable
      ? 'This generator cannot be fitted in this build'
      : tree
        ? 'Fit again, starting from the tree above (its seed, so its branches, stay)'
        : 'Fit again, starting from the values above';
}

$('fit-start').addEventListener('click', () => {
  const generator = fitGenerator();
  const spec = state.specs.find((g) => g.name === generator);
  // Trees have their own fit (a genetic search over the tree generator, paper §3.5).
  if (spec && !spec.differentiable && generator !== 'tree') {
    say(fitMessage, `The ${spec.label.toLowerCase()} generator cannot be fitted in this build; choose another or Automatic.`);
    return;
  }
  runFit({ generator });
});

// "Refit from here": the edited model (say, a handle fixed by hand) joins the fit's starting
// population, so the fit polishes it against the photos instead of starting over. A tree's fit
// keeps the tree's seed and never returns a tree less like the photo than the edited one.
$('refit').addEventListener('click', () => {
  const editor = state.editor;
  if (!editor?.spec) return;
  runFit({ generator: editor.spec.name, start: editor.params.slice() });
});

/** A tree refit's similarity to the photo, before → after (its result says both); else ''. */
function similarityChange(r) {
  if (typeof r.start_similarity !== 'number' || typeof r.similarity !== 'number') return '';
  return `, similarity to the photo ${r.start_similarity.toFixed(3)} → ${r.similarity.toFixed(3)}`;
}

/** Runs a fit and hands its model to the editor; `start`: parameters to start from. */
async function runFit({ generator, start = null }) {
  say(fitMessage, '');
  $('fit-cancel').hidden = false;
  $('fit-start').disabled = true;
  $('refit').disabled = true;
  $('fit-cancel').focus();
  let outcome = 'failed';
  try {
    const out = await fitter.run({ generator, photos: state.photos.slice(), quality: Number($('fit-quality').value), start });
    const r = out.result;
    // A refit that found nothing better gives back the very values it started from: say so,
    // rather than let "Fitted" suggest the model changed.
    // (Up to rounding: a tree's values go through the fit's [0, 1] genes and back.)
    const kept =
      start &&
      r.generator === generator &&
      r.params.length === start.length &&
      r.params.every((v, i) => Math.abs(v - start[i]) <= 1e-9 * Math.max(1, Math.abs(start[i])));
    // A building's windows are glass from HIGH detail up (MEDIUM shows them as recessed
    // bands), so a fitted building opens at HIGH at least: the windows the photo shows.
    const lod = r.generator === 'building' ? Math.max(state.editor.lod, 2) : state.editor.lod;
    chooseGenerator(r.generator, { params: r.params, lod, preset: 'fitted', cameras: r.cameras });
    say(
      fitMessage,
      out.cancelled
        ? `Stopped after ${out.seconds.toFixed(1)} s; the best model so far is below.`
        : kept
          ? `Refitted in ${out.seconds.toFixed(1)} s (${r.evaluations.toLocaleString('en')} evaluations): nothing closer to the photos than your model was found, so it is kept.`
          : `${start ? 'Refitted' : 'Fitted'} in ${out.seconds.toFixed(1)} s (${r.evaluations.toLocaleString('en')} evaluations)${similarityChange(r)}. Edit the model below; Reset returns to the fitted values.`,
      'info',
    );
    outcome = out.cancelled ? 'cancelled' : 'done';
  } catch (err) {
    const hint = /same size/.test(err.message)
      ? 'Use photos of the same shape and size (all from the same camera, all landscape or all portrait).'
      : 'Check the masks above (the object must be inside the photo, not touching every edge), then try again.';
    say(fitMessage, `The fit failed: ${err.message}. ${hint}`);
    outcome = 'failed';
    // Nothing to show from a fit that never ran.
    if (!fitter.curves?.[1]?.length) $('fit-progress').hidden = true;
  } finally {
    $('fit-cancel').hidden = true;
    updateFitButton();
    // For the browser tests: the fit's outcome, set once the page is back to rest.
    document.body.dataset.fitted = outcome;
  }
}
$('fit-cancel').addEventListener('click', () => fitter.cancel());

async function boot() {
  loadSamples();
  try {
    await client.ready;
    state.specs = await client.call(REQUESTS.GENERATOR_SPECS);
  } catch (err) {
    say(modelMessage, `The model editor could not start: ${err.message}. Reload the page to try again.`);
    return;
  }
  if (!state.specs.length) {
    say(modelMessage, 'This build has no generators.');
    return;
  }
  setUpModelStep();
  buildGeneratorChoices();
  if (!(await restore())) chooseGenerator(state.specs[0].name);
  updateFitButton();
  document.body.dataset.ready = 'true';
}

boot();
