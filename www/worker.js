// @ts-check
// The wasm worker: the only place procfit's wasm runs. It loads the module, starts the rayon
// pool (wasm-bindgen-rayon must never be awaited on the main thread) and answers the requests
// of www/protocol.js. A panic inside wasm traps the instance: the worker reports it with the
// panic message and declares itself poisoned, and the page starts a fresh worker.
import { REQUESTS, PROTOCOL_VERSION } from './protocol.js';

const early = [];
let wasm = null;
// Set before any await, so that no message sent during start-up is lost.
self.onmessage = (e) => (wasm ? dispatch(e.data) : early.push(e.data));

const handlers = {
  [REQUESTS.PING]: () => ({
    version: wasm.version(),
    // Checked by the page (client.js): a worker of another protocol is refused.
    protocol: PROTOCOL_VERSION,
    threads: wasm.threaded() ? navigator.hardwareConcurrency : 1,
    threaded: wasm.threaded(),
    // The tree colour rules the page starts from (the core's ColorThresholds::default()).
    treeColors: wasm.treeColorDefaults(),
  }),
  [REQUESTS.THREAD_PROBE]: ({ jobs = 64 } = {}) => ({ threads: wasm.threadProbe(jobs) }),
  [REQUESTS.DEBUG_PANIC]: () => wasm.debugPanic(),
  [REQUESTS.GENERATOR_SPECS]: () => wasm.generatorSpecs(),
  [REQUESTS.GENERATE_GLB]: ({ generator, params, lod, cameras = [], colors = null, useColors = true, carveId = null }) => {
    const t0 = performance.now();
    const carve = carveOf(carveId);
    const args = [generator, Float64Array.from(params), lod, Float32Array.from(cameras), partColors(colors, useColors)];
    const bytes = carve ? wasm.generateCarvedGlb(...args, carve) : wasm.generateGlb(...args);
    const ms = performance.now() - t0;
    // wasm-bindgen returns a fresh copy, so its buffer can be handed over without another copy.
    return new Transfer({ glb: bytes.buffer, ms, carved: !!carve }, [bytes.buffer]);
  },
  [REQUESTS.EXPORT_FILES]: ({ generator, params, lod, cameras = [], colors = null, useColors = true, format, compact = false, fileName, carveId = null }) => {
    const carve = carveOf(carveId);
    const args = [generator, Float64Array.from(params), lod, Float32Array.from(cameras), partColors(colors, useColors), format, compact, fileName];
    const files = (carve ? wasm.exportCarvedFiles(...args, carve) : wasm.exportFiles(...args)).map((bytes) => bytes.buffer);
    return new Transfer({ files }, files);
  },
  [REQUESTS.IOU64]: ({ a, b, lod = 1, side = 128 }) => ({
    iou: wasm.iou64Models(a.generator, Float64Array.from(a.params), b.generator, Float64Array.from(b.params), lod, side),
  }),
  [REQUESTS.PARAMS_JSON]: ({ generator, params, lod, colors = null, useColors = true }) => ({
    text: wasm.paramsJson(generator, Float64Array.from(params), lod, partColors(colors, useColors)),
  }),
  [REQUESTS.OPEN_MODEL]: ({ bytes }) => wasm.openModel(new Uint8Array(bytes)),
  [REQUESTS.MASK_AUTO]: ({ key, width, height, rgba, generator }) => {
    masks.get(key)?.free();
    masks.delete(key);
    const session = new wasm.MaskSession(width, height, new Uint8Array(rgba), generator ?? undefined);
    masks.set(key, session);
    return maskOut(session);
  },
  [REQUESTS.MASK_RECT]: ({ key, rect }) => {
    const session = maskSession(key);
    session.setRect(...rect.map((v) => Math.max(0, Math.round(v))));
    return maskOut(session);
  },
  [REQUESTS.MASK_STROKE]: ({ key, object, points, radius }) => {
    const session = maskSession(key);
    session.addStroke(!!object, Float32Array.from(points), radius);
    return maskOut(session);
  },
  [REQUESTS.MASK_DROP]: ({ key }) => {
    masks.get(key)?.free();
    masks.delete(key);
    return {};
  },
  [REQUESTS.MASK_WINDOWS_AUTO]: ({ key }) => windowsOut(maskSession(key), maskSession(key).detectWindows()),
  [REQUESTS.MASK_WINDOWS_STROKES]: ({ key, strokes = [] }) => {
    const session = maskSession(key);
    const labels = session.windowsFromStrokes(
      Uint8Array.from(strokes.map((s) => (s.window ? 1 : 0))),
      Uint32Array.from(strokes.map((s) => s.points.length / 2)),
      Float32Array.from(strokes.flatMap((s) => s.points)),
      Float32Array.from(strokes.map((s) => s.radius)),
    );
    return windowsOut(session, labels);
  },
  [REQUESTS.MASK_WINDOWS_CLIP]: ({ key, codes }) => {
    const session = maskSession(key);
    return windowsOut(session, session.clipWindows(new Uint8Array(codes)));
  },
  [REQUESTS.MASK_WINDOWS_ERASE]: ({ key, codes, erased = [] }) => {
    const session = maskSession(key);
    const labels = session.eraseWindows(
      new Uint8Array(codes),
      Uint32Array.from(erased.map((s) => s.points.length / 2)),
      Float32Array.from(erased.flatMap((s) => s.points)),
      Float32Array.from(erased.map((s) => s.radius)),
    );
    return windowsOut(session, labels);
  },
  [REQUESTS.PHOTO_FOCAL]: ({ bytes }) => {
    const f = wasm.focal35mmFromFile(new Uint8Array(bytes));
    return { focal_35mm: f > 0 ? f : null };
  },
  [REQUESTS.FIT_RUN]: (payload, emit) => runFit(payload, emit),
  [REQUESTS.TREE_LABELS]: ({ width, height, rgba, codes, colors }) => {
    const labels = wasm.treeLabels(width, height, new Uint8Array(rgba), new Uint8Array(codes ?? 0), colors ?? undefined);
    return new Transfer({ width, height, labels: labels.buffer }, [labels.buffer]);
  },
  [REQUESTS.TREE_RUN]: (payload, emit) => runTreeFit(payload, emit),
  [REQUESTS.FIT_CANCEL]: ({ fitId }) => {
    const found = fits.has(fitId);
    if (found) fits.get(fitId).cancelled = true;
    return { found };
  },
};

/**
 * The part colours a model is written with: the photos' colours (`{ part: [r, g, b] }`) unless
 * the page's "Colours from the photo" is off, else null (the generator's defaults).
 */
function partColors(colors, useColors) {
  return useColors !== false && colors ? colors : null;
}

/** Mask sessions by the page's photo key; fits in progress by id. */
const masks = new Map();
const fits = new Map();

function maskSession(key) {
  const s = masks.get(key);
  if (!s) throw new Error('this photo has no mask yet; add it again');
  return s;
}

function maskOut(session) {
  const codes = session.codes();
  return new Transfer({ ...session.info(), codes: codes.buffer }, [codes.buffer]);
}

function windowsOut(session, labels) {
  const { width, height } = session.info();
  return new Transfer({ width, height, codes: labels.buffer }, [labels.buffer]);
}

/** Yields to the worker's message loop (a cancel or a slider's request gets in), unclamped. */
const tick = (() => {
  const ch = new MessageChannel();
  const waiting = [];
  ch.port1.onmessage = () => waiting.shift()?.();
  return () => new Promise((resolve) => {
    waiting.push(resolve);
    ch.port2.postMessage(0);
  });
})();

/** Progress frames at most this often (plus stage changes and the end). */
const PROGRESS_MS = 100;

async function runFit({ fitId, generator, seed = 1, quality = 1, start = [], masks: views }, emit) {
  if (!views?.length) throw new Error('no masks to fit: add a photo first');
  // One buffer per view, `size(m)` bytes each, concatenated in the views' order.
  const joined = (of, list, size) => {
    const out = new Uint8Array(list.reduce((n, m) => n + size(m), 0));
    let at = 0;
    for (const m of list) {
      out.set(new Uint8Array(of(m)), at);
      at += size(m);
    }
    return out;
  };
  const pixels = (m) => m.width * m.height;
  const codes = joined((m) => m.codes, views, pixels);
  // Window labels of the views that have them, concatenated (see FitSession::new).
  const withWindows = views.filter((m) => m.windows);
  const windowCodes = joined((m) => m.windows, withWindows, pixels);
  const windowFlags = withWindows.length ? Uint8Array.from(views.map((m) => (m.windows ? 1 : 0))) : new Uint8Array(0);
  // The photos' pixels (one per view, at its mask's size), when sent: the fit reads the rim's
  // edge in them, and the part colours are measured in them.
  const withPhotos = views.every((m) => m.rgba && m.rgba.byteLength === 4 * m.width * m.height);
  const rgba = joined((m) => m.rgba, withPhotos ? views : [], (m) => 4 * pixels(m));
  const session = new wasm.FitSession(
    generator,
    seed,
    quality,
    Uint32Array.from(views.map((m) => m.width)),
    Uint32Array.from(views.map((m) => m.height)),
    codes,
    // 0: no focal length known for that view (the core's default field of view).
    Float64Array.from(views.map((m) => (m.focal_35mm > 0 ? wasm.fovFromFocal35mm(m.focal_35mm, m.width, m.height) : 0))),
    Float64Array.from(start),
    windowFlags,
    windowCodes,
    rgba,
  );
  const colorsOf = () => (withPhotos ? session.partColors(rgba) : null);
  return stepFit(fitId, session, emit, (due) => {
    // The silhouette preview of the best model so far (0..255 coverage), with each progress.
    const w = due ? session.previewWidth() : 0;
    if (!w) return [null, []];
    const coverage = session.previewCoverage();
    return [{ width: w, height: session.previewHeight(), coverage: coverage.buffer }, [coverage.buffer]];
  }, colorsOf);
}

/**
 * The photo that carves the last tree fit's leaves (a wasm TreeCarve) and its id: one at a time,
 * since it holds the photo's labels; a model carries the id while it shows that fit's tree.
 */
let treeCarve = null;
// Random, so that an id saved with a model before a reload names no carving of a later worker.
let treeCarveId = Math.floor(Math.random() * 2 ** 30);

/** The carving a request names by `carveId`, or null (none, or not the last tree fit's). */
function carveOf(carveId) {
  return carveId && carveId === treeCarveId ? treeCarve : null;
}

/**
 * Steps a fit session (FitSession or TreeFitSession) in slices until it is done or cancelled,
 * emitting progress at stage changes, at least every PROGRESS_MS and whenever `preview(due)`
 * returns a picture ([picture, transfer]; `due` says progress goes out anyway); `finish(result)`
 * adds to the result before the session is freed at the end.
 */
async function stepFit(fitId, session, emit, preview, colorsOf = () => null, finish = (/** @type {any} */ _result) => {}) {
  const job = { cancelled: false };
  fits.set(fitId, job);
  try {
    let last = 0;
    let stage = 0;
    for (;;) {
      const p = session.step();
      const now = performance.now();
      const due = p.done || p.stage !== stage || now - last >= PROGRESS_MS;
      const [picture, transfer] = preview(due);
      if (picture || due) {
        last = now;
        stage = p.stage;
        emit('progress', { ...p, preview: picture }, transfer);
      }
      if (p.done || job.cancelled) break;
      await tick();
      if (job.cancelled) break;
    }
    const result = session.result();
    // The part colours of the model the fit ends with (also when cancelled: it is shown).
    const colors = colorsOf();
    if (colors) Object.assign(result, { colors: colors.colors, colorParts: colors.parts, colorNote: colors.note });
    finish(result);
    return { cancelled: job.cancelled, result };
  } finally {
    fits.delete(fitId);
    session.free();
  }
}

/** A tree fit, stepped in slices like runFit; the core turns `quality` into its budget. */
async function runTreeFit({ fitId, seed = 1, quality = 1, width, height, rgba, codes, start = [], colors, focal_35mm = null }, emit) {
  // The photo's labels under its colour rules: exactly what the mask step shows.
  const labels = wasm.treeLabels(width, height, new Uint8Array(rgba), new Uint8Array(codes ?? 0), colors ?? undefined);
  const session = wasm.TreeFitSession.fromLabels(
    width,
    height,
    labels,
    seed,
    quality,
    // Empty: from scratch; else the tree to refit from ("Refit from here").
    Float64Array.from(start ?? []),
    // The photo's field of view from its EXIF focal length, as for the silhouette fits; 0: unknown.
    focal_35mm && focal_35mm > 0 ? wasm.fovFromFocal35mm(focal_35mm, width, height) : 0,
  );
  return stepFit(fitId, session, emit, () => {
    // A preview comes only with the step that changed the best tree: always pass it on.
    const w = session.previewWidth();
    if (!w) return [null, []];
    const labels = session.previewLabels();
    return [{ width: w, height: session.previewHeight(), labels: labels.buffer }, [labels.buffer]];
  }, () => session.partColors(width, height, labels, new Uint8Array(rgba)), (result) => {
    // The fitted tree's leaves are carved by its photo: the model names this carving.
    treeCarve?.free();
    treeCarve = session.carve();
    treeCarveId += 1;
    result.carve_id = treeCarveId;
  });
}

/** A handler's result whose buffers move to the page instead of being copied. */
class Transfer {
  constructor(result, buffers) {
    this.result = result;
    this.buffers = buffers;
  }
}

function errorOf(err) {
  if (err instanceof WebAssembly.RuntimeError) {
    let message = null;
    try {
      message = wasm.takePanicMessage();
    } catch {
      // The instance may be too broken to answer; the trap's own text is all we have.
    }
    return { message: message ? `internal error: ${message}` : `internal error: ${err.message}`, panic: true };
  }
  return { message: err && err.message ? err.message : String(err), panic: false };
}

async function dispatch(msg) {
  const { id, type, payload } = msg || {};
  const handler = handlers[type];
  if (!handler) {
    self.postMessage({ id, ok: false, error: { message: `unknown request type ${type}`, panic: false } });
    return;
  }
  const emit = (event, data, transfer = []) => self.postMessage({ id, event, data }, transfer);
  try {
    const result = await handler(payload, emit);
    if (result instanceof Transfer) self.postMessage({ id, ok: true, result: result.result }, result.buffers);
    else self.postMessage({ id, ok: true, result });
  } catch (err) {
    const error = errorOf(err);
    self.postMessage({ id, ok: false, error });
    if (error.panic) {
      self.postMessage({ type: 'sys/poisoned', error });
      self.onmessage = null;
    }
  }
}

async function boot() {
  try {
    // Threads need SharedArrayBuffer, which needs a cross-origin isolated page (COOP/COEP);
    // served without those headers, the single-threaded build runs instead.
    const dir = self.crossOriginIsolated ? '../pkg/' : '../pkg-st/';
    const mod = await import(`${dir}procfit.js`);
    // One options object: wasm-bindgen warns about the old positional parameters.
    await mod.default({ module_or_path: new URL(`${dir}procfit_bg.wasm`, import.meta.url) });
    if (mod.threaded()) {
      if (!self.crossOriginIsolated) {
        throw new Error('this build needs a cross-origin isolated page (COOP/COEP headers)');
      }
      await mod.initThreadPool(navigator.hardwareConcurrency);
    }
    wasm = mod;
    self.postMessage({ type: 'sys/ready', result: handlers[REQUESTS.PING]() });
    early.splice(0).forEach(dispatch);
  } catch (err) {
    self.postMessage({ type: 'sys/boot-failed', error: { message: String(err && err.message || err), panic: false } });
  }
}

boot();
