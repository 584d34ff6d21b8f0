// The mask step: each photo's mask (from the worker's GrabCut session) drawn over the photo,
// and the tools to correct it — a box around the object, object / background brushes (both
// re-cut in the worker) and a "don't care" brush (pixels the fit must ignore, kept here and
// merged into the mask codes when the fit starts).
import { REQUESTS } from './protocol.js';

/** Overlay colours (RGBA) by mask code: background dimmed, object tinted, unsure in amber. */
const TINT = { bg: [20, 20, 30, 120], obj: [40, 110, 255, 70], unsure: [255, 190, 0, 150] };

/**
 * Asks the worker for `photo`'s automatic mask; stores it on the photo. With `keep`, a mask the
 * photo already has (restored from storage) is kept and only the worker's session is made, so
 * later corrections have something to re-cut.
 */
export async function autoMask(client, photo, { keep = false } = {}) {
  const c = new OffscreenCanvas(photo.width, photo.height);
  const ctx = c.getContext('2d');
  ctx.drawImage(photo.bitmap, 0, 0);
  const rgba = ctx.getImageData(0, 0, photo.width, photo.height).data.buffer;
  const m = await client.call(
    REQUESTS.MASK_AUTO,
    { key: String(photo.id), width: photo.width, height: photo.height, rgba },
    { transfer: [rgba] },
  );
  if (!(keep && photo.mask)) setMask(photo, m);
  return photo.mask;
}

function setMask(photo, m) {
  const dontCare = photo.mask && photo.mask.width === m.width && photo.mask.height === m.height ? photo.mask.dontCare : null;
  photo.mask = { ...m, codes: new Uint8Array(m.codes), dontCare: dontCare ?? blankCanvas(m.width, m.height) };
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
        ctx.lineWidth = 2 * this.radius();
        ctx.lineCap = ctx.lineJoin = 'round';
        ctx.beginPath();
        drag.points.forEach(([x, y], i) => (i ? ctx.lineTo(x, y) : ctx.moveTo(x, y)));
        if (drag.points.length === 1) ctx.lineTo(drag.points[0][0] + 0.01, drag.points[0][1]);
        ctx.stroke();
        this.draw();
        this.onChange(photo);
        return;
      }
      this.busy = true;
      let m;
      if (this.tool === 'rect') {
        const [[x0, y0], [x1, y1]] = [drag.start, drag.points.at(-1)];
        const rect = [Math.min(x0, x1), Math.min(y0, y1), Math.max(x0, x1), Math.max(y0, y1)];
        const { width, height } = photo.mask;
        const clamped = [Math.max(0, rect[0]), Math.max(0, rect[1]), Math.min(width, rect[2]), Math.min(height, rect[3])];
        if (clamped[2] - clamped[0] < 4 || clamped[3] - clamped[1] < 4) {
          this.onError('Drag a box around the whole object.');
          return;
        }
        m = await this.client.call(REQUESTS.MASK_RECT, { key: String(photo.id), rect: clamped });
      } else {
        m = await this.client.call(REQUESTS.MASK_STROKE, {
          key: String(photo.id),
          object: this.tool === 'object',
          points: drag.points.flat(),
          radius: this.radius(),
        });
      }
      setMask(photo, m);
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
      for (let i = 0; i < codes.length; i += 1) {
        const t = codes[i] === 128 ? TINT.unsure : codes[i] > 128 ? TINT.obj : TINT.bg;
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
        ctx.strokeStyle = { object: 'rgba(40,110,255,0.9)', background: 'rgba(20,20,30,0.8)', dontcare: 'rgba(255,190,0,0.9)' }[this.tool];
        ctx.lineWidth = 2 * this.radius();
        ctx.lineCap = ctx.lineJoin = 'round';
        ctx.beginPath();
        drag.points.forEach(([x, y], i) => (i ? ctx.lineTo(x, y) : ctx.moveTo(x, y)));
        ctx.stroke();
      }
    }
  }
}
