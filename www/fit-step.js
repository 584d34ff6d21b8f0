// @ts-check
// The fit step's wiring: Fit (the generator chosen, or Automatic), "Refit from here" (from the
// edited model), cancel, and the fitted model handed to the editor with a sentence on how it
// went. How a generator is fitted is its spec's `fit`; FitRunner (fitting.js) runs it.
import { say } from './ui.js';
import { FitRunner } from './fitting.js';
import { $, client, state, specOf, fitGenerator } from './page.js';
import { chooseGenerator } from './model-step.js';

const fitMessage = $('fit-message');
const fitMatch = $('fit-match');
const fitter = new FitRunner({
  client,
  els: { stage: $('fit-stage'), eta: $('fit-eta'), bar: $('fit-bar'), preview: $('fit-preview'), curve: $('fit-curve'), box: $('fit-progress'), caption: $('fit-preview-caption') },
});
window.procfit.fitter = fitter;

/**
 * Fit and Refit are enabled when every photo has its mask (not being cut again for another
 * kind of object) and the generator can be fitted.
 */
export function updateFitButton() {
  const ready = state.photos.length > 0 && state.photos.every((p) => p.mask && p.maskState !== 'working');
  const button = $('fit-start');
  button.disabled = !ready || !!fitter.running || !state.editor;
  button.title = ready ? '' : 'Add a photo and wait for its mask first';
  const refit = $('refit');
  // A generator fitted by the tree GA starts from a tree too (its seed kept).
  const tree = state.editor?.spec?.fit === 'tree_ga';
  const fittable = !!state.editor?.spec?.fit;
  refit.disabled = button.disabled || !fittable;
  refit.title = !ready
    ? button.title
    : !fittable
      ? 'This generator cannot be fitted in this build'
      : tree
        ? 'Fit again, starting from the tree above (its seed, so its branches, stay)'
        : 'Fit again, starting from the values above';
}

$('fit-start').addEventListener('click', () => {
  const generator = fitGenerator();
  const spec = specOf(generator);
  // How a generator is fitted is its spec's `fit` (gradients, or the tree GA of paper §3.5).
  if (spec && !spec.fit) {
    say(fitMessage, `The ${spec.label.toLowerCase()} generator cannot be fitted in this build; choose another or Automatic.`);
    return;
  }
  runFit({ generator });
});

// "Refit from here": the edited model (say, a handle fixed by hand) joins the fit's starting
// population, so the fit polishes it against the photos instead of starting over. A tree's fit
// keeps the tree's seed and never returns a tree less like the photo than the edited one.
$('refit').addEventListener('click', () => {
  const editor = state.editor;
  if (!editor?.spec) return;
  runFit({ generator: editor.spec.name, start: editor.params.slice() });
});

/**
 * A tree fit's similarity to the photo (the photo-view IoU is said beside it, by showMatch); a
 * refit's before → after (its result says both); '' for a fit without one (silhouette fits).
 * @param {{ start_similarity?: number, similarity?: number }} r
 */
function similarityChange(r) {
  if (typeof r.similarity !== 'number') return '';
  if (typeof r.start_similarity !== 'number') return `, similarity to the photo ${r.similarity.toFixed(3)}`;
  return `, similarity to the photo ${r.start_similarity.toFixed(3)} → ${r.similarity.toFixed(3)}`;
}

/**
 * What the page says about the part colours a fit measured: nothing when every part was seen,
 * else which parts borrowed a neighbour's colour or kept the default.
 * @param {{ colors?: Record<string, number[]>, colorNote?: string | null }} r
 */
function colorNote(r) {
  if (!r.colors) return '';
  return r.colorNote ? ` Colours from the photos; ${r.colorNote}.` : ' Colours from the photos.';
}

/**
 * Says how well the fitted model matches each photo: its photo-view IoU (the model through
 * the photo's fitted camera against the photo's mask, don't-care excluded), and, below the
 * core's level, that it does not match and what to do (the core's sentence); then, when other
 * fits matched the photos as well but differ in 3D (the core's agreement below its level),
 * that the photos do not fix the shape; when the windows found were left out, that they
 * were and why (the core's sentence); and what one photo cannot tell about the fitted shape
 * (the core's caveat, not a warning). Empty without numbers.
 * @param {{ photo_ious?: number[], match_level?: number, match_warning?: string | null, agreement_warning?: string | null, windows_note?: string | null, caveat?: string | null, carved_photo_iou?: number }} r
 */
export function showMatch(r) {
  const ious = r.photo_ious ?? [];
  fitMatch.dataset.agreement = r.agreement_warning ? 'ambiguous' : '';
  fitMatch.dataset.windows = r.windows_note ? 'left-out' : '';
  fitMatch.dataset.caveat = r.caveat ? 'one-view' : '';
  if (!ious.length) {
    say(fitMatch, '');
    fitMatch.dataset.match = '';
    return;
  }
  const sentence = (/** @type {string | null | undefined} */ t) => t ? ` ${t.charAt(0).toUpperCase()}${t.slice(1)}.` : '';
  const ambiguity = sentence(r.agreement_warning) + sentence(r.windows_note);
  // What one photo cannot tell (a mug's handle): said, not a warning.
  const caveat = sentence(r.caveat);
  const each = ious.map((v, i) => `${ious.length > 1 ? `photo ${i + 1} ` : ''}${v.toFixed(2)}`).join(', ');
  const level = typeof r.match_level === 'number' ? r.match_level.toFixed(2) : '';
  // A tree's leaves are then carved where the photo sees through its crown: its overlap as shown.
  const carved = typeof r.carved_photo_iou === 'number' ? ` Carved by the photo, pixel by pixel: ${r.carved_photo_iou.toFixed(2)}.` : '';
  const numbers = `How well the fitted model matches ${ious.length > 1 ? 'each photo' : 'the photo'} (outline overlap, 1 = exact): ${each}.${carved}`;
  if (r.match_warning) {
    const why = r.match_warning.charAt(0).toUpperCase() + r.match_warning.slice(1);
    say(fitMatch, `${numbers} ${why}.${ambiguity}${caveat}`, 'warn');
    fitMatch.dataset.match = 'poor';
  } else {
    say(fitMatch, `${numbers} That is a match (${level} or better).${ambiguity}${caveat}`, ambiguity ? 'warn' : 'info');
    fitMatch.dataset.match = 'good';
  }
}

/**
 * Runs a fit and hands its model to the editor; `start`: parameters to start from.
 * @param {{ generator: string, start?: number[] | null }} o
 */
async function runFit({ generator, start = null }) {
  say(fitMessage, '');
  showMatch({});
  $('fit-cancel').hidden = false;
  $('fit-start').disabled = true;
  $('refit').disabled = true;
  $('fit-cancel').focus();
  let outcome = 'failed';
  try {
    const out = await fitter.run({ generator, specs: state.specs, photos: state.photos.slice(), quality: Number($('fit-quality').value), start });
    const r = out.result;
    // A refit that found nothing better gives back the very values it started from: say so,
    // rather than let "Fitted" suggest the model changed.
    // (Up to rounding: a tree's values go through the fit's [0, 1] genes and back.)
    const kept =
      start &&
      r.generator === generator &&
      r.params.length === start.length &&
      r.params.every((v, i) => Math.abs(v - start[i]) <= 1e-9 * Math.max(1, Math.abs(start[i])));
    // A fitted model opens at its generator's export detail at least (a building's windows
    // are glass from HIGH up: the windows the photo shows), the detail its photo-view IoU was
    // measured at (`r.lod`).
    const lod = Math.max(state.editor.lod, r.lod ?? 0, specOf(r.generator)?.fitted_lod ?? 0);
    // A refit that kept the model keeps its colours too; a new fit brings the photos' colours.
    const colors = r.colors ?? (kept ? state.editor.colors : null);
    chooseGenerator(r.generator, { params: r.params, lod, preset: 'fitted', cameras: r.cameras, colors, carveId: r.carve_id ?? null });
    say(
      fitMessage,
      out.cancelled
        ? `Stopped after ${out.seconds.toFixed(1)} s; the best model so far is below.`
        : kept
          ? `Refitted in ${out.seconds.toFixed(1)} s (${r.evaluations.toLocaleString('en')} evaluations): nothing closer to the photos than your model was found, so it is kept.`
          : `${start ? 'Refitted' : 'Fitted'} in ${out.seconds.toFixed(1)} s (${r.evaluations.toLocaleString('en')} evaluations)${similarityChange(r)}. Edit the model below; Reset returns to the fitted values.${colorNote(r)}`,
      'info',
    );
    showMatch(r);
    outcome = out.cancelled ? 'cancelled' : 'done';
  } catch (err) {
    const hint = /same size/.test(err.message)
      ? 'Use photos of the same shape and size (all from the same camera, all landscape or all portrait).'
      : 'Check the masks above (the object must be inside the photo, not touching every edge), then try again.';
    say(fitMessage, `The fit failed: ${err.message}. ${hint}`);
    outcome = 'failed';
    // Nothing to show from a fit that never ran.
    if (!fitter.curves?.[1]?.length) $('fit-progress').hidden = true;
  } finally {
    $('fit-cancel').hidden = true;
    updateFitButton();
    // For the browser tests: the fit's outcome, set once the page is back to rest.
    document.body.dataset.fitted = outcome;
  }
}
$('fit-cancel').addEventListener('click', () => fitter.cancel());
