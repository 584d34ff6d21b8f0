// @ts-check
// The mask step: each photo's mask (from the worker's GrabCut session) drawn over the photo,
// and the tools to correct it — a box around the object, object / background brushes (both
// re-cut in the worker) and a "don't care" brush (pixels the fit must ignore, kept here and
// merged into the mask codes when the fit starts). For buildings, window labels: found
// automatically or from window / wall brushes (labelled in the worker), drawn in teal; for
// trees, the branch (brown) and leaf (green) labels the tree fit will see.
//
// Corrections are kept with the photo (`photo.edits`: the box and strokes since the last
// automatic mask) so that a worker session made again — after a reload or a worker restart —
// can replay them; the next correction then builds on all earlier ones.
//
// The window labels themselves live in window-labels.js, the tree labels in tree-labels.js.
import { REQUESTS } from './protocol.js';
import { WINDOW, eraseWindows, windowsAfterMask } from './window-labels.js';

/** Overlay colours (RGBA) by mask code: background dimmed, object tinted, unsure in amber. */
const TINT = {
  bg: [20, 20, 30, 120],
  obj: [40, 110, 255, 70],
  unsure: [255, 190, 0, 150],
  window: [0, 215, 190, 170],
  branch: [150, 90, 40, 200],
  leaf: [40, 200, 60, 170],
};

/**
 * Asks the worker for `photo`'s automatic mask, cut for the object kind `generator` (a
 * generator's name: a building's outline follows the photo further into corners than a
 * dish's); stores it on the photo with the kind (`photo.maskFor`). With `keep`, a mask the
 * photo already has (restored from storage) is kept and only the worker's session is made, so
 * later corrections have something to re-cut.
 * @param {any} client
 * @param {import('./page.js').Photo} photo
 * @param {{ keep?: boolean, generator?: string }} [o]
 */
export async function autoMask(client, photo, { keep = false, generator } = {}) {
  const c = new OffscreenCanvas(photo.width, photo.height);
  const ctx = c.getContext('2d');
  ctx.drawImage(photo.bitmap, 0, 0);
  const rgba = ctx.getImageData(0, 0, photo.width, photo.height).data.buffer;
  const m = await client.call(
    REQUESTS.MASK_AUTO,
    { key: String(photo.id), width: photo.width, height: photo.height, rgba, generator },
    { transfer: [rgba] },
  );
  if (!(keep && photo.mask)) {
    setMask(photo, m);
    photo.edits = [];
    photo.maskFor = generator;
  }
  return photo.mask;
}

/** The worker requests that replay `photo`'s corrections, back to back; the last gives the mask. */
function replayEdits(client, photo) {
  const key = String(photo.id);
  return (photo.edits ?? []).map((e) =>
    e.rect
      ? client.call(REQUESTS.MASK_RECT, { key, rect: e.rect })
      : client.call(REQUESTS.MASK_STROKE, { key, object: e.object, points: e.points, radius: e.radius }),
  );
}

/**
 * Gives `photo` a worker session again and replays its corrections into it (after a reload or
 * a worker restart). The requests go out back to back, so any correction the person makes
 * meanwhile queues behind them in the worker. The photo's mask stays as stored (the replay
 * gives the same one: the session is cut for the kind the mask was, `photo.maskFor`).
 */
export async function reviveMask(client, photo) {
  const auto = autoMask(client, photo, { keep: true, generator: photo.maskFor });
  await Promise.all([auto, ...replayEdits(client, photo)]);
}

/**
 * Cuts `photo`'s mask again for the object kind `generator` and replays its corrections on the
 * new cut (the person's box and strokes still say what they said). Don't-care strokes stay.
 * @param {any} client
 * @param {import('./page.js').Photo} photo
 * @param {string} generator
 */
export async function recutMask(client, photo, generator) {
  const edits = photo.edits ?? [];
  await autoMask(client, photo, { generator });
  photo.edits = edits;
  const replies = await Promise.all(replayEdits(client, photo));
  if (replies.length) setMask(photo, replies[replies.length - 1]);
  return photo.mask;
}

/** `photo`'s RGBA pixels at its mask's (working) size, as an ArrayBuffer. */
export function photoPixels(photo) {
  const { width, height } = photo.mask;
  const ctx = new OffscreenCanvas(width, height).getContext('2d');
  ctx.drawImage(photo.bitmap, 0, 0, width, height);
  return ctx.getImageData(0, 0, width, height).data.buffer;
}

function setMask(photo, m) {
  const dontCare = photo.mask && photo.mask.width === m.width && photo.mask.height === m.height ? photo.mask.dontCare : null;
  photo.mask = { ...m, codes: new Uint8Array(m.codes), dontCare: dontCare ?? blankCanvas(m.width, m.height) };
}

/**
 * Paints a round-capped brush stroke along `points` (working pixels) in the context's current
 * stroke style: the one way a brush is drawn, for the don't-care strokes and the stroke in
 * progress alike. A single point paints a dot.
 * @param {CanvasRenderingContext2D | OffscreenCanvasRenderingContext2D} ctx
 * @param {number[][]} points
 * @param {number} radius
 */
function paintStroke(ctx, points, radius) {
  ctx.lineWidth = 2 * radius;
  ctx.lineCap = ctx.lineJoin = 'round';
  ctx.beginPath();
  points.forEach(([x, y], i) => (i ? ctx.lineTo(x, y) : ctx.moveTo(x, y)));
  if (points.length === 1) ctx.lineTo(points[0][0] + 0.01, points[0][1]);
  ctx.stroke();
}

/** A transparent canvas with its 2D context made (convertToBlob refuses a context-less one). */
function blankCanvas(width, height) {
  const c = new OffscreenCanvas(width, height);
  c.getContext('2d');
  return c;
}

/** The codes the fit uses: the worker's mask with the user's don't-care strokes on top. */
export function fitCodes(photo) {
  const { width, height, codes, dontCare } = photo.mask;
  const out = codes.slice();
  const paint = dontCare.getContext('2d').getImageData(0, 0, width, height).data;
  for (let i = 0; i < out.length; i += 1) if (paint[4 * i + 3] > 0) out[i] = 128;
  return out;
}

export class MaskEditor {
  /** `overlay`: the canvas over the photo; `client`: the WorkerClient; `onChange(photo)`. */
  constructor({ overlay, client, onChange, onError }) {
    this.overlay = overlay;
    this.client = client;
    this.onChange = onChange;
    this.onError = onError;
    this.photo = null;
    this.tool = 'none';
    this.brush = 10;
    this.show = true;
    // Window labels are drawn while the generator is a building, tree labels for a tree.
    this.showWindows = false;
    this.showTree = false;
    this.drag = null;
    this.busy = false;
    overlay.dataset.tool = 'none';
    overlay.addEventListener('pointerdown', (e) => this.down(e));
    overlay.addEventListener('pointermove', (e) => this.move(e));
    overlay.addEventListener('pointerup', (e) => this.up(e));
    overlay.addEventListener('pointercancel', () => {
      this.drag = null;
      this.draw();
    });
  }

  setTool(tool) {
    this.tool = tool;
    this.overlay.dataset.tool = tool;
  }

  /** Whether `tool` paints window labels rather than the mask. */
  static isWindowTool(tool) {
    return tool === 'window' || tool === 'wall';
  }

  setPhoto(photo) {
    this.photo = photo;
    this.draw();
  }

  /** Working-image pixel under a pointer event. */
  at(e) {
    const r = this.overlay.getBoundingClientRect();
    const { width, height } = this.photo.mask;
    return [((e.clientX - r.left) / r.width) * width, ((e.clientY - r.top) / r.height) * height];
  }

  /** Brush radius in working pixels (the size slider is in screen pixels). */
  radius() {
    const r = this.overlay.getBoundingClientRect();
    return Math.max(1, (this.brush * this.photo.mask.width) / Math.max(1, r.width));
  }

  down(e) {
    if (this.tool === 'none' || !this.photo?.mask || this.busy) return;
    e.preventDefault();
    this.overlay.setPointerCapture(e.pointerId);
    this.drag = { start: this.at(e), points: [this.at(e)] };
    this.draw();
  }

  move(e) {
    if (!this.drag) return;
    this.drag.points.push(this.at(e));
    this.draw();
  }

  async up(e) {
    if (!this.drag) return;
    const drag = this.drag;
    drag.points.push(this.at(e));
    this.drag = null;
    const photo = this.photo;
    try {
      if (this.tool === 'dontcare') {
        const ctx = photo.mask.dontCare.getContext('2d');
        ctx.strokeStyle = '#000';
        paintStroke(ctx, drag.points, this.radius());
        this.draw();
        this.onChange(photo);
        return;
      }
      this.busy = true;
      if (MaskEditor.isWindowTool(this.tool)) {
        const stroke = { window: this.tool === 'window', points: drag.points.flat(), radius: this.radius() };
        const strokes = [...(photo.windows?.strokes ?? []), stroke];
        if (!strokes.some((s) => s.window)) {
          if (!photo.windows?.codes) {
            this.onError('Paint over a window first (windows brush), or find windows automatically.');
            return;
          }
          // Windows found automatically: the wall brush erases them where it paints (and
          // again when they are found again after a mask correction).
          const erase = { points: stroke.points, radius: stroke.radius };
          const codes = await eraseWindows(this.client, photo, photo.windows.codes, [erase]);
          photo.windows = { codes, strokes: [], erased: [...(photo.windows.erased ?? []), erase] };
          photo.windowsNote = '';
          this.onChange(photo);
          return;
        }
        const w = await this.client.call(REQUESTS.MASK_WINDOWS_STROKES, { key: String(photo.id), strokes });
        photo.windows = { codes: new Uint8Array(w.codes), strokes, erased: [] };
        photo.windowsNote = '';
        this.onChange(photo);
        return;
      }
      let m;
      let edit;
      if (this.tool === 'rect') {
        const [[x0, y0], [x1, y1]] = [drag.start, drag.points.at(-1)];
        const rect = [Math.min(x0, x1), Math.min(y0, y1), Math.max(x0, x1), Math.max(y0, y1)];
        const { width, height } = photo.mask;
        const clamped = [Math.max(0, rect[0]), Math.max(0, rect[1]), Math.min(width, rect[2]), Math.min(height, rect[3])];
        if (clamped[2] - clamped[0] < 4 || clamped[3] - clamped[1] < 4) {
          this.onError('Drag a box around the whole object.');
          return;
        }
        edit = { rect: clamped };
        m = await this.client.call(REQUESTS.MASK_RECT, { key: String(photo.id), rect: clamped });
      } else {
        edit = { object: this.tool === 'object', points: drag.points.flat(), radius: this.radius() };
        m = await this.client.call(REQUESTS.MASK_STROKE, { key: String(photo.id), ...edit });
      }
      setMask(photo, m);
      // A box starts the worker's session over; a stroke adds to it.
      photo.edits = edit.rect ? [edit] : [...(photo.edits ?? []), edit];
      // Still busy: the windows follow the new mask before the next correction can start.
      await windowsAfterMask(this.client, photo);
      this.onChange(photo);
    } catch (err) {
      this.onError(`The correction did not work: ${err.message}`);
    } finally {
      this.busy = false;
      this.draw();
    }
  }

  /** Redraws the overlay: the tinted mask, don't-care strokes, and the stroke in progress. */
  draw() {
    const c = this.overlay;
    const photo = this.photo;
    if (!photo?.mask) {
      c.width = 1;
      c.height = 1;
      return;
    }
    const { width, height, codes, dontCare } = photo.mask;
    if (c.width !== width || c.height !== height) {
      c.width = width;
      c.height = height;
    }
    const ctx = c.getContext('2d');
    ctx.clearRect(0, 0, width, height);
    if (this.show) {
      const img = ctx.createImageData(width, height);
      const d = img.data;
      const win = this.showWindows && photo.windows?.codes?.length === codes.length ? photo.windows.codes : null;
      // For trees, what the fit will see: branches brown, leaves green (tree::labels).
      const tree = this.showTree && photo.treeLabels?.length === codes.length ? photo.treeLabels : null;
      for (let i = 0; i < codes.length; i += 1) {
        let t = codes[i] === 128 ? TINT.unsure : codes[i] > 128 ? TINT.obj : TINT.bg;
        if (win && win[i] === WINDOW) t = TINT.window;
        else if (tree && tree[i] === 1) t = TINT.branch;
        else if (tree && tree[i] === 2) t = TINT.leaf;
        d.set(t, 4 * i);
      }
      ctx.putImageData(img, 0, 0);
      ctx.globalAlpha = 0.75;
      ctx.globalCompositeOperation = 'source-over';
      // The user's don't-care strokes, in amber.
      const tmp = new OffscreenCanvas(width, height);
      const tctx = tmp.getContext('2d');
      tctx.drawImage(dontCare, 0, 0);
      tctx.globalCompositeOperation = 'source-in';
      tctx.fillStyle = 'rgb(255,190,0)';
      tctx.fillRect(0, 0, width, height);
      ctx.drawImage(tmp, 0, 0);
      ctx.globalAlpha = 1;
    }
    const drag = this.drag;
    if (drag) {
      ctx.lineWidth = Math.max(1, width / 300);
      if (this.tool === 'rect') {
        const [[x0, y0], [x1, y1]] = [drag.start, drag.points.at(-1)];
        ctx.strokeStyle = '#fff';
        ctx.setLineDash([6, 4]);
        ctx.strokeRect(Math.min(x0, x1), Math.min(y0, y1), Math.abs(x1 - x0), Math.abs(y1 - y0));
        ctx.setLineDash([]);
      } else {
        ctx.strokeStyle = { object: 'rgba(40,110,255,0.9)', background: 'rgba(20,20,30,0.8)', dontcare: 'rgba(255,190,0,0.9)', window: 'rgba(0,215,190,0.9)', wall: 'rgba(230,220,200,0.9)' }[this.tool];
        paintStroke(ctx, drag.points, this.radius());
      }
    }
  }
}
