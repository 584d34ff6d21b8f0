// @ts-check
// The photos step: photos in from anywhere (picker, drag and drop, paste, the camera, the
// bundled samples), the thumbnails to choose and remove them, and the photo shown. A GLB or
// params JSON given the same way opens as a model instead.
import { REQUESTS } from './protocol.js';
import { el, say } from './ui.js';
import { loadPhoto, isModelFile, MAX_PHOTOS } from './photos.js';
import { CameraCapture } from './camera.js';
import { $, client, state, selectedPhoto } from './page.js';
import { persist } from './persistence.js';
import { maskEditor, findMask, renderMaskState } from './mask-step.js';
import { chooseGenerator, openModelFile } from './model-step.js';

const photosMessage = $('photos-message');

/**
 * Takes files from any source: photos join the list, a GLB/JSON opens as a model.
 * @param {Iterable<File>} files
 * @param {'file' | 'paste'} [source]
 */
export async function addFiles(files, source = 'file') {
  say(photosMessage, '');
  const list = [...files];
  if (!list.length) {
    say(photosMessage, source === 'paste' ? 'The clipboard holds no image. Copy a photo, then paste again.' : 'No file came through. Try again, or use “Choose photos…”.');
    return;
  }
  const problems = [];
  /** @type {string[]} */
  const refused = [];
  for (const file of list) {
    if (isModelFile(file)) {
      await openModelFile(file);
      continue;
    }
    const name = file.name || `pasted ${state.photos.length + 1}.png`;
    if (isFull()) {
      refused.push(name);
      continue;
    }
    try {
      addPhoto(await photoOf(file, name));
    } catch (err) {
      problems.push(err.message);
    }
  }
  if (refused.length) problems.push(limitMessage(refused));
  if (problems.length) say(photosMessage, problems.join(' '));
}

/** Whether the photo list is at its limit ({@link MAX_PHOTOS}). */
function isFull() {
  return state.photos.length >= MAX_PHOTOS;
}

/**
 * The one message for photos refused at the limit, however many and by whichever path.
 * @param {string[]} names
 */
function limitMessage(names) {
  const which = names.length === 1 ? `“${names[0]}” was not added` : `${names.length} photos were not added (${names.map((n) => `“${n}”`).join(', ')})`;
  return `procfit takes up to ${MAX_PHOTOS} photos: ${which}. Remove a photo to add another.`;
}

/**
 * A photo from `file`, with the EXIF focal length of the original file (downscaling drops it).
 * @param {Blob} file
 * @param {string} name
 */
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

/** @param {import('./page.js').Photo} photo */
function addPhoto(photo) {
  state.photos.push(photo);
  selectPhoto(photo.id);
  findMask(photo);
  persist();
}

/** @param {number} id */
function selectPhoto(id) {
  state.selected = id;
  renderPhotos();
  persist();
}

/** @param {number} id */
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

/** The thumbnails and the photo shown, with its mask. */
export function renderPhotos() {
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
  const photo = selectedPhoto();
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
  /** @type {HTMLElement} */ (document.querySelector('#photo-view .stack')).style.maxWidth = `calc(75vh * ${photo.width / photo.height})`;
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
    if (isFull()) {
      say(photosMessage, limitMessage([name]));
      return;
    }
    try {
      addPhoto(await photoOf(blob, name));
    } catch (err) {
      say(photosMessage, err.message);
    }
  },
  onError: (message) => say(photosMessage, message),
});

$('camera-open').addEventListener('click', () => {
  say(photosMessage, '');
  camera.open();
});

/** The bundled samples (www/samples/index.json): a photo and the generator it shows. */
export async function loadSamples() {
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

/** @param {{ name: string, label: string, file: string, thumb?: string, generator: string }} s */
async function openSample(s) {
  say(photosMessage, '');
  if (isFull()) {
    say(photosMessage, limitMessage([s.label]));
    return;
  }
  try {
    const res = await fetch(`www/samples/${s.file}`);
    if (!res.ok) throw new Error(`the sample is missing (${res.status})`);
    const photo = await photoOf(await res.blob(), s.file);
    // The kind first: the sample's mask is then cut for it.
    if (state.specs.some((g) => g.name === s.generator)) chooseGenerator(s.generator);
    addPhoto(photo);
  } catch (err) {
    say(photosMessage, `Could not open the sample: ${err.message}`);
  }
}

