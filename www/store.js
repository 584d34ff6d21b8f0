// @ts-check
// Work is not lost: the session (downscaled photos with their EXIF focal lengths, their masks,
// the box and strokes that corrected them, don't-care strokes, window labels and tree colours, the model's generator, parameters, level of detail and starting
// point) is kept in IndexedDB on this device and restored when the page is opened again.
// Nothing here leaves the device.

const DB = 'procfit';
const STORE = 'session';
const KEY = 'current';
/** Bumped when the saved shape changes; older records are ignored, not misread. */
export const STORE_VERSION = 1;

function open() {
  return new Promise((resolve, reject) => {
    const req = indexedDB.open(DB, 1);
    req.onupgradeneeded = () => req.result.createObjectStore(STORE);
    req.onsuccess = () => resolve(req.result);
    req.onerror = () => reject(req.error);
  });
}

async function tx(mode, fn) {
  const db = await open();
  try {
    return await new Promise((resolve, reject) => {
      const t = db.transaction(STORE, mode);
      const req = fn(t.objectStore(STORE));
      t.oncomplete = () => resolve(req?.result);
      t.onerror = () => reject(t.error);
      t.onabort = () => reject(t.error || new Error('storage aborted'));
    });
  } finally {
    db.close();
  }
}

/** The saved session, or null (none, unreadable or from another version). */
export async function load() {
  try {
    const rec = await tx('readonly', (s) => s.get(KEY));
    return rec && rec.version === STORE_VERSION ? rec : null;
  } catch {
    return null;
  }
}

/** Saves `record` (structured-cloneable: Blobs and typed arrays are fine). */
export function save(record) {
  return tx('readwrite', (s) => s.put({ ...record, version: STORE_VERSION }, KEY));
}

export function clear() {
  return tx('readwrite', (s) => s.delete(KEY));
}

/** Serialises a photo for storage: the downscaled JPEG and its mask with don't-care strokes. */
export async function photoRecord(p) {
  const rec = {
    id: p.id,
    name: p.name,
    width: p.width,
    height: p.height,
    blob: p.blob,
    focal35mm: p.focal35mm ?? null,
    mask: null,
    // Corrections since the automatic mask, replayed into the worker's session on restore,
    // which is cut for the same object kind as the automatic mask was.
    edits: p.edits ?? [],
    maskFor: p.maskFor ?? null,
    // Window labels (buildings), the strokes they came from and the wall strokes that erased
    // windows found automatically (applied again when a mask correction finds them again).
    windows: p.windows ? { codes: p.windows.codes, strokes: p.windows.strokes ?? [], erased: p.windows.erased ?? [] } : null,
    // Trees: the photo's colour rules for leaves and branches, when the user changed them.
    treeColors: p.treeColors ?? null,
  };
  if (p.mask) {
    const { codes, dontCare, ...info } = p.mask;
    rec.mask = { ...info, codes, dontCare: await dontCare.convertToBlob({ type: 'image/png' }) };
  }
  return rec;
}

/** Rebuilds a photo from its record (the inverse of photoRecord). */
export async function photoFromRecord(rec) {
  const bitmap = await createImageBitmap(rec.blob);
  const photo = {
    id: rec.id,
    name: rec.name,
    width: rec.width,
    height: rec.height,
    bitmap,
    blob: rec.blob,
    focal35mm: rec.focal35mm ?? null,
    edits: Array.isArray(rec.edits) ? rec.edits : [],
    maskFor: typeof rec.maskFor === 'string' ? rec.maskFor : undefined,
    windows: rec.windows?.codes
      ? { codes: new Uint8Array(rec.windows.codes), strokes: rec.windows.strokes ?? [], erased: Array.isArray(rec.windows.erased) ? rec.windows.erased : [] }
      : null,
    treeColors: rec.treeColors && typeof rec.treeColors === 'object' ? rec.treeColors : null,
  };
  if (rec.mask) {
    const { dontCare, ...mask } = rec.mask;
    const canvas = new OffscreenCanvas(mask.width, mask.height);
    const strokes = await createImageBitmap(dontCare);
    canvas.getContext('2d').drawImage(strokes, 0, 0);
    strokes.close();
    photo.mask = { ...mask, dontCare: canvas };
    photo.maskState = 'ready';
  }
  return photo;
}
