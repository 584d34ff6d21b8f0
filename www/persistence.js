// @ts-check
// The session kept on this device (store.js, IndexedDB): saved a moment after each change,
// restored when the page opens again, cleared by "Start over". The step a person works in is
// kept too, so a reload returns to it.
import * as store from './store.js';
import { reserveIds } from './photos.js';
import { say } from './ui.js';
import { $, state } from './page.js';

/** @type {ReturnType<typeof setTimeout> | undefined} */
let persistTimer;

/** Saves the session to IndexedDB a moment after the last change (many changes → one write). */
export function persist() {
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

/**
 * Restores the saved session, if any, and says so with a way to start over. `show` puts the
 * restored photos and model on the page.
 * @param {{ photosRestored: () => void, openModel: (generator: string, o: { params: number[], lod: number, preset: string, cameras: number[], colors?: Record<string, number[]> | null }) => void }} show
 */
export async function restore(show) {
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
  show.photosRestored();
  const m = rec.model;
  if (m && state.specs.some((g) => g.name === m.generator)) {
    show.openModel(m.generator, { params: m.params, lod: m.lod, preset: m.presetName ?? 'custom', cameras: m.cameras ?? [], colors: m.colors ?? null });
    if (Array.isArray(m.base) && m.base.length === m.params.length) state.editor.base = m.base;
    if (m.useColors === false && state.editor.colors) {
      state.editor.setUseColors(false);
      /** @type {HTMLInputElement} */ ($('photo-colors')).checked = false;
    }
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
