// @ts-check
// The page's shared state (main thread): the worker client, the photos, the generator specs
// and the model editor, with their types. Every page module imports what it needs from here;
// main.js wires the steps together.
import { WorkerClient } from './client.js';
import { REQUESTS } from './protocol.js';

/**
 * How a generator is fitted, shown and exported: its spec's capabilities (the core's
 * `generators::Capabilities`, see `gen/specs` in protocol.js). The page decides nothing by a
 * generator's name.
 * @typedef {object} GeneratorSpec
 * @property {string} name machine name
 * @property {string} label
 * @property {number} version
 * @property {boolean} differentiable
 * @property {'gradients' | 'tree_ga' | null} fit how it is fitted; null: not at all
 * @property {string} display_name what the generator choice shows
 * @property {number} fitted_lod the least level of detail (0..3) a fitted model opens at
 * @property {'none' | 'windows' | 'tree_labels'} mask_extra the mask tools its fit reads
 * @property {number} outline_smoothing how smooth its automatic masks' outlines are cut
 * @property {{ name: string, label: string, group: string, unit: string, min: number, max: number, default: number, kind: string, choices: string[] }[]} params
 * @property {{ name: string, label: string, values: number[] }[]} presets
 */

/**
 * A photo's mask as the worker gives it (protocol.js `mask/*`), with the person's don't-care
 * strokes kept beside it.
 * @typedef {object} PhotoMask
 * @property {number} width working pixels
 * @property {number} height
 * @property {Uint8Array} codes object 255, background 0, don't care 128
 * @property {number[]} bbox
 * @property {number} confidence
 * @property {boolean} low_confidence
 * @property {string[]} warnings
 * @property {number} [outline_smoothing] how smooth the cut's outline is (the kind's it was cut
 *   for; absent in masks saved by an older page)
 * @property {OffscreenCanvas} dontCare the don't-care strokes (alpha > 0: ignored by the fit)
 */

/**
 * A mask correction kept with the photo, replayed into a new worker session.
 * @typedef {{ rect: number[] } | { rect?: undefined, object: boolean, points: number[], radius: number }} MaskEdit
 */

/**
 * A wall- or windows-brush stroke in working pixels (`points`: x, y, …).
 * @typedef {{ window?: boolean, points: number[], radius: number }} WindowStroke
 */

/**
 * Window labels (0 background, 1 façade, 2 window, 255 don't care) with the strokes they came
 * from (`strokes`, empty when found automatically) and the wall strokes that erased automatic
 * ones (`erased`, applied again when they are found again).
 * @typedef {{ codes: Uint8Array, strokes: WindowStroke[], erased: WindowStroke[] }} WindowLabels
 */

/**
 * One photo of the session. Written by photos.js (what it is), masking.js (its mask, windows
 * and tree labels) and the page's steps (their progress).
 * @typedef {object} Photo
 * @property {number} id
 * @property {string} name
 * @property {number} width
 * @property {number} height
 * @property {ImageBitmap} bitmap
 * @property {Blob} blob the downscaled JPEG kept for storage
 * @property {number | null} [focal35mm] EXIF 35 mm-equivalent focal length of the original file
 * @property {PhotoMask} [mask]
 * @property {'working' | 'ready' | 'failed'} [maskState]
 * @property {string} [maskError]
 * @property {MaskEdit[]} [edits] the corrections since the automatic mask
 * @property {string} [maskFor] the object kind (generator name) the automatic mask was cut for;
 *   none: the default cut (the kind was left to the fit)
 * @property {Promise<void>} [reviving] the worker session being made again
 * @property {WindowLabels | null} [windows]
 * @property {string} [windowsNote] what the last mask correction did to the windows
 * @property {object | null} [treeColors] its colour rules (ColorThresholds' camelCase fields)
 * @property {Uint8Array | null} [treeLabels] 0 background, 1 branch, 2 leaf, 255 don't care
 * @property {Uint8Array} [treeLabelsFor] the mask codes the labels were made for
 * @property {string} [treeLabelsColors] the colour rules they were made with (JSON)
 * @property {boolean} [treeLabelsPending]
 * @property {string | null} [treeError]
 */

/**
 * @typedef {object} PageState
 * @property {Photo[]} photos
 * @property {number | null} selected the id of the photo shown
 * @property {GeneratorSpec[]} specs
 * @property {import('./editor.js').Editor | null} editor
 * @property {import('./viewer.js').Viewer | null} viewer
 * @property {string | null} presetName the preset shown, 'custom' (an opened file) or 'fitted'
 * @property {string | null} [step] the step the person works in
 * @property {boolean} [clearing] set while the session is cleared (no save may follow)
 */

/**
 * The element with this id. Typed loosely on purpose: the ids are the page's (index.html) and
 * the browser tests exercise every one; a cast at each use would say nothing more.
 * @param {string} id
 * @returns {any}
 */
export const $ = (id) => document.getElementById(id);

export const client = new WorkerClient();

/** @type {PageState} */
export const state = { photos: [], selected: null, specs: [], editor: null, viewer: null, presetName: null };

// A handle for the browser tests and the curious: the page's worker client and protocol.
window.procfit = { client, REQUESTS, state };

/** The photo shown, if any. */
export function selectedPhoto() {
  return state.photos.find((p) => p.id === state.selected);
}

/**
 * The spec of the generator called `name` (undefined for 'auto' or an unknown name).
 * @param {string} name
 */
export function specOf(name) {
  return state.specs.find((g) => g.name === name);
}

/** The generator chosen for the fit: a name, or 'auto'. */
export function fitGenerator() {
  return /** @type {HTMLInputElement | null} */ (document.querySelector('input[name="generator"]:checked'))?.value ?? 'auto';
}
