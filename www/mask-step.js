// @ts-check
// The mask step's wiring: the mask editor over the shown photo, the automatic mask of each new
// photo (and the windows that follow it), the mask's state line and the correction tools.
import { REQUESTS } from './protocol.js';
import { say } from './ui.js';
import { MaskEditor, autoMask, recutMask, reviveMask } from './masking.js';
import { windowsAfterMask } from './window-labels.js';
import { $, client, state, selectedPhoto, specOf, fitGenerator } from './page.js';
import { persist } from './persistence.js';
import { renderWindowTools } from './windows-ui.js';
import { renderTreeLabels } from './tree-colors-ui.js';
import { updateFitButton } from './fit-step.js';

const photosMessage = $('photos-message');

export const maskEditor = new MaskEditor({
  overlay: $('mask-canvas'),
  client,
  onChange: () => {
    renderMaskState();
    persist();
  },
  onError: (message) => say(photosMessage, message),
});
window.procfit.maskEditor = maskEditor;

/**
 * The object kind chosen (a generator's name), which automatic masks are cut for; `undefined`
 * when the fit is to pick it (the default cut).
 */
const chosenKind = () => specOf(fitGenerator())?.name;

/**
 * Whether `photo`'s mask was cut otherwise than the chosen kind cuts it. With the kind left to
 * the fit, or a mask saved by an older page (which does not say how it was cut), the mask stays.
 */
const cutForAnotherKind = (/** @type {import('./page.js').Photo} */ photo) => {
  const wanted = specOf(fitGenerator())?.outline_smoothing;
  const had = photo.mask?.outline_smoothing;
  return wanted != null && had != null && had !== wanted;
};

/**
 * Runs the automatic mask for `photo` (cut for the chosen kind), keeping the page told. With
 * `recut`, the photo's corrections are replayed on the new cut (the kind changed) instead of
 * being dropped (the person asked for the automatic mask again).
 * @param {import('./page.js').Photo} photo
 * @param {{ recut?: boolean }} [o]
 */
export async function findMask(photo, { recut = false } = {}) {
  photo.maskState = 'working';
  renderMaskState();
  try {
    await photo.reviving;
    // The kind may change while the worker cuts: then the photo is cut again for the new one.
    do {
      const kind = chosenKind();
      await (recut ? recutMask(client, photo, kind) : autoMask(client, photo, { generator: kind }));
    } while (cutForAnotherKind(photo) && state.photos.includes(photo));
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
 * After the object kind changed: each photo whose mask was cut for a kind with another outline
 * smoothing is cut again for this one, its corrections replayed (a mask being cut now checks
 * the kind itself when it is done).
 */
export function recutForKind() {
  for (const p of state.photos) {
    if (p.mask && p.maskState !== 'working' && cutForAnotherKind(p)) findMask(p, { recut: true });
  }
}

/**
 * Worker sessions for masks the page already has (after a restore or a worker restart), with
 * the photo's corrections replayed so the next one builds on them.
 */
export function reviveMasks() {
  for (const p of state.photos) {
    if (p.mask) {
      p.reviving = reviveMask(client, p).catch(() => {});
    }
  }
}

/** The mask's state line (found, to check, failed) and the tools that go with it. */
export function renderMaskState() {
  const box = $('mask-state');
  const photo = selectedPhoto();
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

document.querySelectorAll('input[name="tool"]').forEach((r) => {
  const radio = /** @type {HTMLInputElement} */ (r);
  radio.addEventListener('change', () => radio.checked && maskEditor.setTool(radio.value));
});
$('brush').addEventListener('input', (e) => (maskEditor.brush = Number(e.target.value)));
$('mask-show').addEventListener('change', (e) => {
  maskEditor.show = e.target.checked;
  maskEditor.draw();
});
$('mask-auto').addEventListener('click', () => {
  const photo = selectedPhoto();
  if (photo) findMask(photo);
});
