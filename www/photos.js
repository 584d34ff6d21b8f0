// @ts-check
// The photos step's data: files from anywhere (picker, drop, paste, camera, samples) become
// downscaled photos. Decoding and downscaling happen in the browser (createImageBitmap, which
// applies the EXIF orientation), so wasm only ever sees a modest, upright RGBA image.

/** Longest side of a photo after downscaling; the fit works at a fraction of this. */
export const MAX_SIDE = 1024;
/** How many photos one session takes (multi-view). */
export const MAX_PHOTOS = 8;
/** Files larger than this are refused before decoding (a phone photo is ~3–12 MB). */
export const MAX_BYTES = 50 * 1024 * 1024;

let nextId = 1;

/** Makes sure new photos get ids above `id` (photos restored from storage keep theirs). */
export function reserveIds(id) {
  nextId = Math.max(nextId, id + 1);
}

/**
 * Decodes `file` (a File or Blob) and downscales it. Resolves with a photo
 * `{ id, name, width, height, bitmap, blob }` (`blob`: the downscaled JPEG kept for storage);
 * rejects with an Error whose message a person can act on.
 */
export async function loadPhoto(file, name = file.name || 'photo') {
  if (file.size > MAX_BYTES) {
    throw new Error(`“${name}” is ${(file.size / 1e6).toFixed(0)} MB; procfit takes photos up to ${MAX_BYTES / 1e6} MB.`);
  }
  if (file.type && !file.type.startsWith('image/')) {
    throw new Error(`“${name}” is not a photo (it is ${file.type}). Use a JPEG, PNG or WebP image.`);
  }
  let full;
  try {
    full = await createImageBitmap(file, { imageOrientation: 'from-image' });
  } catch {
    throw new Error(`“${name}” could not be read as an image. Use a JPEG, PNG or WebP photo.`);
  }
  if (full.width < 16 || full.height < 16) {
    full.close();
    throw new Error(`“${name}” is only ${full.width}×${full.height} pixels; use a larger photo.`);
  }
  const scale = Math.min(1, MAX_SIDE / Math.max(full.width, full.height));
  const width = Math.max(1, Math.round(full.width * scale));
  const height = Math.max(1, Math.round(full.height * scale));
  const canvas = new OffscreenCanvas(width, height);
  const ctx = canvas.getContext('2d');
  ctx.imageSmoothingQuality = 'high';
  ctx.drawImage(full, 0, 0, width, height);
  full.close();
  const blob = await canvas.convertToBlob({ type: 'image/jpeg', quality: 0.9 });
  const bitmap = canvas.transferToImageBitmap();
  return { id: nextId++, name, width, height, bitmap, blob };
}

/** True when a file looks like a model to open rather than a photo (by name or type). */
export function isModelFile(file) {
  return /\.(glb|json)$/i.test(file.name || '') || file.type === 'model/gltf-binary' || file.type === 'application/json';
}
