// @ts-check
// Window labels for buildings (a generator whose spec's `mask_extra` is 'windows'), kept with
// each photo (`photo.windows`): found automatically or painted with the windows / wall brushes
// (labelled in the worker), the wall brush's erasures applied by the core. They follow the
// mask: after each correction, windows found automatically are found again (with the erasures
// made on them applied again), and windows painted by hand are kept but clipped to it
// (`windowsAfterMask`); `photo.windowsNote` says which happened, for the windows line.
import { REQUESTS } from './protocol.js';

/** Window label codes (segment::windows). */
export const WINDOW = 2;

/** The window labels for the fit (0 background, 1 façade, 2 window, 255 don't care), or null. */
export function fitWindows(photo) {
  const w = photo.windows;
  if (!w?.codes || !photo.mask || w.codes.length !== photo.mask.codes.length) return null;
  const out = w.codes.slice();
  const { width, height, dontCare } = photo.mask;
  const paint = dontCare.getContext('2d').getImageData(0, 0, width, height).data;
  for (let i = 0; i < out.length; i += 1) if (paint[4 * i + 3] > 0) out[i] = 255;
  return out;
}

/**
 * Finds windows automatically inside `photo`'s mask; stores and returns them. `photo.windows`
 * is { codes, strokes, erased }: `strokes` the windows / wall brush strokes the labels came
 * from (empty when found automatically), `erased` the wall-brush strokes that took windows out
 * of automatic ones (applied again when they are found again).
 */
export async function detectWindows(client, photo) {
  const w = await client.call(REQUESTS.MASK_WINDOWS_AUTO, { key: String(photo.id) });
  photo.windows = { codes: new Uint8Array(w.codes), strokes: [], erased: [] };
  photo.windowsNote = '';
  return photo.windows;
}

/** Whether `photo`'s windows were painted by hand (windows brush), not found automatically. */
export function paintedWindows(photo) {
  return !!photo.windows?.strokes?.some((s) => s.window);
}

/**
 * `codes` (window labels) with the windows under the wall-brush strokes `erased` made façade,
 * by the core (segment::windows::erase_windows).
 * @param {import('./client.js').WorkerClient} client
 * @param {import('./page.js').Photo} photo
 * @param {Uint8Array} codes
 * @param {import('./page.js').WindowStroke[]} erased
 */
export async function eraseWindows(client, photo, codes, erased) {
  const copy = codes.slice();
  const out = await client.call(REQUESTS.MASK_WINDOWS_ERASE, { key: String(photo.id), codes: copy.buffer, erased }, { transfer: [copy.buffer] });
  return new Uint8Array(out.codes);
}

/**
 * Makes `photo`'s window labels fit its mask again after the mask changed: windows found
 * automatically are found again (and the wall-brush erasures made on them applied again);
 * painted ones are kept, clipped to the new object. Sets `photo.windowsNote` to say so; when
 * that fails, the windows are cleared and the note says why. Does nothing without windows.
 */
export async function windowsAfterMask(client, photo) {
  const w = photo.windows;
  if (!w?.codes || !photo.mask) return;
  const key = String(photo.id);
  try {
    if (paintedWindows(photo)) {
      const codes = w.codes.slice();
      const out = await client.call(REQUESTS.MASK_WINDOWS_CLIP, { key, codes: codes.buffer }, { transfer: [codes.buffer] });
      photo.windows = { ...w, codes: new Uint8Array(out.codes) };
      photo.windowsNote = 'Your painted windows are kept, cut to the corrected mask.';
    } else {
      const out = await client.call(REQUESTS.MASK_WINDOWS_AUTO, { key });
      const erased = w.erased ?? [];
      const found = new Uint8Array(out.codes);
      const codes = erased.length ? await eraseWindows(client, photo, found, erased) : found;
      photo.windows = { codes, strokes: [], erased };
      photo.windowsNote = 'Windows found again in the corrected mask.';
    }
  } catch (err) {
    photo.windows = null;
    photo.windowsNote = `The windows were cleared with the mask correction: ${err.message}.`;
  }
}
