// @ts-check
// The fit step: sends the photos' masks to the worker's fit, shows its progress (stage names,
// a progress bar with an ETA, the best outline so far over the first photo, the loss curve)
// and a cancel button, and hands the fitted model to the editor. The worker runs the fit in
// slices, so the page — and the sliders — stay responsive meanwhile.
import { REQUESTS } from './protocol.js';
import { fitCodes, photoPixels } from './masking.js';
import { fitWindows } from './window-labels.js';
import { treeColors } from './tree-labels.js';

/** What each stage does, in words (see reconstruct::session). */
export const STAGES = {
  1: 'Stage 1 of 3: searching shapes and camera (coarse)',
  2: 'Stage 2 of 3: refining the outline',
  3: 'Stage 3 of 3: polishing at full detail',
};

/** The tree fit's stages (tree::impostor::TreeSession). */
export const TREE_STAGES = {
  1: 'Stage 1 of 3: growing trees (genetic search)',
  2: 'Stage 2 of 3: trying the best trees with other seeds',
  3: 'Stage 3 of 3: polishing the best tree',
};

/** A tree refit's stages: it keeps the start tree's seed, so it tries no others. */
export const TREE_REFIT_STAGES = {
  ...TREE_STAGES,
  2: "Stage 2 of 3: keeping your tree's seed (no other seeds tried)",
};

/** Preview colours of tree labels: branch brown, leaf green. */
const TREE_TINT = { 1: [120, 78, 40, 255], 2: [60, 150, 60, 255] };

let nextFit = 1;

export class FitRunner extends EventTarget {
  /** `els`: { stage, eta, bar, preview, curve, box }; `client`: the WorkerClient. */
  constructor({ client, els }) {
    super();
    this.client = client;
    this.els = els;
    this.running = null;
  }

  /**
   * Fits `generator` ('auto' or a name) to `photos` (each with a mask), from the parameters
   * `start` when given (a named generator's; "Refit from here"). Resolves with
   * { cancelled, result, seconds }; rejects with a readable error.
   */
  async run({ generator, specs, photos, quality, start = null }) {
    if (this.running) throw new Error('a fit is already running');
    const spec = specs.find((g) => g.name === generator);
    if (spec?.fit === 'tree_ga') return this.runTree({ generator, photo: photos[0], quality, start });
    // Window labels only mean something to a generator that reads them (or to Automatic,
    // when one of the generators it tries does).
    const readsWindows = (g) => g.mask_extra === 'windows';
    const useWindows = spec ? readsWindows(spec) : specs.some((g) => g.fit === 'gradients' && readsWindows(g));
    const masks = photos.map((p) => {
      const codes = fitCodes(p);
      const windows = useWindows ? fitWindows(p) : null;
      // The photo's pixels at the mask's size: the fitted model's part colours are measured in them.
      const rgba = photoPixels(p);
      return { width: p.mask.width, height: p.mask.height, codes: codes.buffer, windows: windows?.buffer ?? null, rgba, focal_35mm: p.focal35mm ?? null };
    });
    const fitId = nextFit++;
    const t0 = performance.now();
    this.running = { fitId };
    this.curves = { 1: [], 2: [], 3: [] };
    this.lastRun = undefined;
    this.photo = photos[0];
    this.tree = false;
    if (this.els.caption) this.els.caption.textContent = 'Best outline so far (orange) over photo 1';
    this.els.box.hidden = false;
    this.els.bar.value = 0;
    this.els.stage.textContent = 'Starting…';
    this.els.eta.textContent = '';
    this.drawPreview(null);
    this.drawCurve();
    try {
      const out = await this.client.call(
        REQUESTS.FIT_RUN,
        { fitId, generator, seed: 1, quality, masks, ...(start ? { start } : {}) },
        { transfer: masks.flatMap((m) => (m.windows ? [m.codes, m.windows, m.rgba] : [m.codes, m.rgba])), onEvent: (event, data) => event === 'progress' && this.progress(data, t0) },
      );
      return { ...out, seconds: (performance.now() - t0) / 1000 };
    } finally {
      this.running = null;
    }
  }

  /**
   * Fits `generator` (fitted by the tree GA) to `photo`'s colours inside its mask (trees fit one photo), from the
   * tree `start` when given (its seed is kept). Resolves like run().
   */
  async runTree({ generator, photo, quality, start = null }) {
    const { width, height } = photo.mask;
    const rgba = photoPixels(photo);
    const codes = fitCodes(photo).buffer;
    const fitId = nextFit++;
    const t0 = performance.now();
    this.running = { fitId };
    this.curves = { 1: [], 2: [], 3: [] };
    this.photo = photo;
    this.tree = start ? TREE_REFIT_STAGES : TREE_STAGES;
    this.lastTree = null;
    this.els.box.hidden = false;
    this.els.bar.value = 0;
    this.els.stage.textContent = 'Starting…';
    this.els.eta.textContent = '';
    if (this.els.caption) this.els.caption.textContent = 'Best tree so far: its branches (brown) and leaves (green)';
    this.drawPreview(null);
    this.drawCurve();
    try {
      const out = await this.client.call(
        REQUESTS.TREE_RUN,
        {
          fitId,
          seed: 1,
          quality,
          width,
          height,
          rgba,
          codes,
          colors: treeColors(this.client, photo),
          focal_35mm: photo.focal35mm ?? null,
          ...(start ? { start } : {}),
        },
        {
          transfer: [rgba, codes],
          onEvent: (event, data) => {
            if (event !== 'progress') return;
            // The same shape as a silhouette fit's progress, so one drawing path serves both.
            this.progress(
              { ...data, work_done: data.evaluations, work_total: data.total_evaluations, best_loss: 1 - data.best_similarity, generator },
              t0,
            );
          },
        },
      );
      return { ...out, seconds: (performance.now() - t0) / 1000 };
    } finally {
      this.running = null;
    }
  }

  cancel() {
    if (!this.running) return;
    this.client.call(REQUESTS.FIT_CANCEL, { fitId: this.running.fitId }).catch(() => {});
  }

  progress(p, t0) {
    const frac = p.work_total > 0 ? Math.min(1, p.work_done / p.work_total) : 0;
    this.els.bar.value = frac;
    // `this.tree`: the tree fit's stage names (a refit's differ), or false.
    const names = this.tree || STAGES;
    // A fit makes a few runs from different seeds side by side and keeps the best: say so.
    // The stage and curve are the first unfinished run's; when it changes, its curves start
    // afresh (the outline shown is the best finished run's once there is one).
    // When the first fits' best did not match the photo, the core adds fits from other shapes.
    const added = p.rescue_runs > 0 ? `, ${p.rescue_runs} added from other shapes because the best did not match the photo` : '';
    const tries = p.runs > 1 ? ` (best of ${p.runs} fits run side by side${added})` : '';
    if (p.run !== undefined && p.run !== this.lastRun) {
      this.lastRun = p.run;
      this.curves = { 1: [], 2: [], 3: [] };
    }
    this.els.stage.textContent = `${names[p.stage] ?? `Stage ${p.stage}`}${p.generator ? ` — ${p.generator}` : ''}${tries}`;
    const elapsed = (performance.now() - t0) / 1000;
    if (p.done) this.els.eta.textContent = `done in ${elapsed.toFixed(1)} s`;
    else if (frac > 0.02) this.els.eta.textContent = `about ${formatSeconds((elapsed * (1 - frac)) / frac)} left`;
    else this.els.eta.textContent = 'estimating time…';
    if (p.best_loss !== null && p.best_loss !== undefined) this.curves[p.stage]?.push(p.best_loss);
    this.drawCurve();
    if (p.preview) this.drawPreview(p.preview);
    this.dispatchEvent(new CustomEvent('progress', { detail: p }));
  }

  /** The first photo, dimmed, with the best silhouette's outline over it. */
  drawPreview(preview) {
    const c = this.els.preview;
    const photo = this.photo;
    if (!photo) return;
    const w = Math.min(480, photo.width);
    const h = Math.round((w * photo.height) / photo.width);
    c.width = w;
    c.height = h;
    const ctx = c.getContext('2d');
    ctx.drawImage(photo.bitmap, 0, 0, w, h);
    ctx.fillStyle = 'rgba(255,255,255,0.35)';
    ctx.fillRect(0, 0, w, h);
    if (this.tree) {
      // The tree's labels are in the fit's own square frame, not the photo's: drawn whole,
      // centred on white, once one arrives.
      if (!preview && this.lastTree) preview = this.lastTree;
      if (!preview) return;
      this.lastTree = preview;
      const labels = new Uint8Array(preview.labels);
      const img = new ImageData(preview.width, preview.height);
      for (let i = 0; i < labels.length; i += 1) img.data.set(TREE_TINT[labels[i]] ?? [255, 255, 255, 255], 4 * i);
      const tile = new OffscreenCanvas(preview.width, preview.height);
      tile.getContext('2d').putImageData(img, 0, 0);
      ctx.fillStyle = '#fff';
      ctx.fillRect(0, 0, w, h);
      const side = Math.min(w, h);
      ctx.imageSmoothingEnabled = false;
      ctx.drawImage(tile, (w - side) / 2, (h - side) / 2, side, side);
      return;
    }
    if (!preview) return;
    const cov = new Uint8Array(preview.coverage);
    const sil = new OffscreenCanvas(preview.width, preview.height);
    const sctx = sil.getContext('2d');
    const img = sctx.createImageData(preview.width, preview.height);
    for (let i = 0; i < cov.length; i += 1) img.data.set([255, 120, 0, Math.round(cov[i] * 0.6)], 4 * i);
    sctx.putImageData(img, 0, 0);
    ctx.imageSmoothingEnabled = true;
    ctx.drawImage(sil, 0, 0, w, h);
  }

  /** One polyline per stage (losses of different stages do not compare), each on its own scale. */
  drawCurve() {
    const c = this.els.curve;
    const ctx = c.getContext('2d');
    const { width: W, height: H } = c;
    ctx.clearRect(0, 0, W, H);
    const colours = { 1: '#2456c8', 2: '#c8561f', 3: '#2e8b57' };
    const slot = W / 3;
    for (const s of [1, 2, 3]) {
      const ys = this.curves?.[s] ?? [];
      const x0 = (s - 1) * slot;
      ctx.fillStyle = '#66666b';
      ctx.font = '12px system-ui, sans-serif';
      ctx.fillText(`stage ${s}`, x0 + 6, 14);
      if (s > 1) {
        ctx.strokeStyle = '#d6d3cc';
        ctx.beginPath();
        ctx.moveTo(x0, 0);
        ctx.lineTo(x0, H);
        ctx.stroke();
      }
      if (ys.length < 1) continue;
      if (ys.length === 1) {
        // A stage of one step (the tree fit's seed trials) is a dot, not an empty slot.
        ctx.fillStyle = colours[s];
        ctx.beginPath();
        ctx.arc(x0 + slot / 2, 24 + (H - 32) / 2, 3, 0, 2 * Math.PI);
        ctx.fill();
        continue;
      }
      const lo = Math.min(...ys);
      const hi = Math.max(...ys);
      const span = hi - lo || 1;
      ctx.strokeStyle = colours[s];
      ctx.lineWidth = 2;
      ctx.beginPath();
      ys.forEach((y, i) => {
        const px = x0 + 6 + ((slot - 12) * i) / Math.max(1, ys.length - 1);
        const py = 24 + (H - 32) * ((hi - y) / span);
        if (i) ctx.lineTo(px, py);
        else ctx.moveTo(px, py);
      });
      ctx.stroke();
    }
  }
}

function formatSeconds(s) {
  if (s < 60) return `${Math.max(1, Math.round(s))} s`;
  return `${Math.floor(s / 60)} min ${Math.round(s % 60)} s`;
}
