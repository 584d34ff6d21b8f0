// @ts-check
// The one message protocol between the page (main thread) and the wasm worker.
//
// Page → worker (a request):   { id, type, payload }
// Worker → page (its answer):  { id, ok: true, result }  or  { id, ok: false, error }
// Worker → page (on the way):  { id, event, data }        progress frames of request `id`
// Worker → page (unprompted):  { type: 'sys/ready', result }      wasm loaded, pool started
//                              { type: 'sys/boot-failed', error } wasm could not start
//                              { type: 'sys/poisoned', error }    a panic trapped the instance;
//                                                                 the page restarts the worker
// `error` is always { message, panic: bool }. Request types are namespaced `room/verb`; the
// list below is the whole protocol. Binary payloads travel as transferred ArrayBuffers (the
// sender gives up its copy), never as arrays of numbers.
export const REQUESTS = Object.freeze({
  PING: 'sys/ping', //             → ReadyInfo
  THREAD_PROBE: 'sys/threadProbe', // { jobs } → { threads } distinct pool threads that ran jobs
  DEBUG_PANIC: 'sys/debugPanic', // → never answers ok: panics inside wasm, for the error test
  // → [{ name, label, version, differentiable, fit: 'gradients' | 'tree_ga' | null, display_name,
  //      fitted_lod: 0..3, mask_extra: 'none' | 'windows' | 'tree_labels', params, presets }]
  GENERATOR_SPECS: 'gen/specs',
  // { generator, params: number[], lod: 0..3, cameras?: number[], carveId?: number | null }
  // → { glb: ArrayBuffer, ms, carved }:
  // the model's mesh as the very GLB the page downloads (the viewer loads these bytes), with one
  // camera node per photo (`cameras`: 18 numbers each — yfov, aspect, camera-to-world matrix
  // column-major — as a fit's result gives them); `ms` is the worker's time. `carveId`: a tree
  // fit's `carve_id`: the tree's leaves are carved by that fit's photo (`carved` says whether
  // they were: only the last tree fit's carving is kept, and a fresh worker has none).
  GENERATE_GLB: 'gen/glb',
  // { a: { generator, params }, b: { generator, params }, lod, side } → { iou }: the paper's
  // IoU-64 between two models (for the benchmark).
  IOU64: 'eval/iou64',
  // { generator, params, lod, cameras, format: 'glb'|'obj'|'stl', compact, fileName, carveId? } →
  // { files: ArrayBuffer[] }: the model as the download menu saves it ([obj, mtl] for OBJ).
  EXPORT_FILES: 'gen/export',
  // { generator, params, lod } → { text }: the params JSON of the model.
  PARAMS_JSON: 'model/json',
  // { bytes: ArrayBuffer } (a procfit GLB or params JSON) → { generator, params, lod, seed }.
  OPEN_MODEL: 'model/open',
  // Masks, one session per photo `key` (a string the page chooses). Each answers
  // { width, height, bbox, confidence, low_confidence, warnings, codes: ArrayBuffer } with the
  // mask in working pixels: object 255, background 0, don't care 128.
  MASK_AUTO: 'mask/auto', //   { key, width, height, rgba: ArrayBuffer, generator? } → mask (automatic, cut for that kind)
  MASK_RECT: 'mask/rect', //   { key, rect: [x0, y0, x1, y1] } → mask (start over from a box)
  MASK_STROKE: 'mask/stroke', // { key, object: bool, points: [x, y, …], radius } → mask
  MASK_DROP: 'mask/drop', //   { key } → {} (the photo was removed)
  // Window labels for buildings, inside the photo's current mask: { width, height, codes:
  // ArrayBuffer } with 0 background, 1 façade, 2 window, 255 don't care (working pixels).
  MASK_WINDOWS_AUTO: 'mask/windowsAuto', // { key } → labels (darker rectangles, automatic)
  // { key, strokes: [{ window: bool, points: [x, y, …], radius }] } → labels (from the user's
  // window and wall strokes; at least one window stroke).
  MASK_WINDOWS_STROKES: 'mask/windowsStrokes',
  // { key, codes: ArrayBuffer } (labels as above, made for an earlier mask) → labels fitted to
  // the current mask: windows outside the object dropped, the rest kept (painted windows after
  // a mask correction; automatic ones are found again with MASK_WINDOWS_AUTO instead).
  MASK_WINDOWS_CLIP: 'mask/windowsClip',
  // { key, codes: ArrayBuffer, erased: [{ points: [x, y, …], radius }] } (labels as above) →
  // labels with the windows under those wall-brush strokes made façade (the core's
  // segment::windows::erase_windows), for windows found automatically.
  MASK_WINDOWS_ERASE: 'mask/windowsErase',
  // { bytes: ArrayBuffer } (the original photo file) → { focal_35mm: number | null }: the
  // EXIF 35 mm-equivalent focal length, read before the page's downscaling drops the EXIF.
  PHOTO_FOCAL: 'photo/focal',
  // { fitId, generator ('auto' or a name), seed, quality, start?: number[],
  //   masks: [{ width, height, codes, windows?: ArrayBuffer | null, focal_35mm?: number | null }] }
  // → { cancelled, result: { generator, params, lod, seed, loss, evaluations, cameras,
  //   photo_ious: number[] (one a photo), match_level, match_warning?: string,
  //   agreement?: number, agreement_warning?: string, windows_note?: string, caveat?: string } }
  // `agreement`: the 3D agreement of the runs that matched the photos as well (null before the
  // end, with one run, or when no other run did); `agreement_warning`: a sentence below the level.
  // `windows_note`: a sentence when the masks' window labels were left out (a model fitted to them
  // matched the outline less well than one fitted to the outline alone). `caveat`: what one photo
  // cannot tell about the fitted shape (a mug's handle), after a fit from one photo. `lod`: the
  // detail `photo_ious` were measured at, the least the page opens the fitted model at.
  // `start`: the named generator's parameters to start from ("Refit from here"); a mask's
  // `focal_35mm` (from PHOTO_FOCAL) sets that view's field of view, else the default is used;
  // a mask's `windows` (labels as MASK_WINDOWS_* give them) adds the window term of a building.
  // (`cameras` as GENERATE_GLB takes them). On the way:
  // event 'progress' { stage, generator, iteration, evaluations, work_done, work_total,
  // best_loss, params, run, runs, rescue_runs (of `runs`, those added from other shapes because
  // the first runs' best did not match a photo), done,
  // preview: { width, height, coverage: ArrayBuffer } | null }.
  FIT_RUN: 'fit/run',
  FIT_CANCEL: 'fit/cancel', // { fitId } → { found }: the running fit (or tree fit) stops after its slice
  // Trees (paper §3.5), from one photo's colours inside its mask. `rgba`: the photo at the mask's
  // size (width × height × 4 bytes); `codes`: its mask codes (or empty: the whole photo).
  // { width, height, rgba, codes } → { width, height, labels: ArrayBuffer } (0 background,
  // 1 branch, 2 leaf, 255 don't care), for the preview over the photo.
  TREE_LABELS: 'tree/labels',
  // { fitId, seed, quality, width, height, rgba, codes, start?: number[], focal_35mm?: number | null }
  // → { cancelled,
  // result: { generator (the tree generator's name), params, lod, seed, similarity, start_similarity, evaluations,
  // cameras, photo_ious: [number], match_level, match_warning?: string, carved_photo_iou,
  // carve_id } } (`start_similarity`: the start's, undefined without one; `match_warning`: a
  // sentence when below the level; `carve_id`: for GENERATE_GLB's `carveId`, the photo that
  // carves the tree's leaves; `carved_photo_iou`: the photo-view IoU of the tree so carved).
  // `start`: the tree generator's parameters to refit from ("Refit from here"): the fit keeps
  // its `seed` parameter and never returns a tree less similar to the photo. On the way: event
  // 'progress'
  // { stage (1 GA, 2 seed trials, 3 local search), generation, evaluations, total_evaluations,
  // best_similarity, params, done, preview: { width, height, labels: ArrayBuffer } | null } (the
  // best tree's labels in the fit's square frame). Cancelled by FIT_CANCEL. `focal_35mm` (from
  // PHOTO_FOCAL) sets the fit's field of view, as for FIT_RUN's views.
  TREE_RUN: 'tree/run',
});

/**
 * The protocol's version, bumped when a message changes shape. The worker reports its own in
 * 'sys/ready' (`protocol`), and the page refuses a worker that speaks another one (an old
 * worker.js from a cache, say) with a message that says to reload.
 */
export const PROTOCOL_VERSION = 12;

/**
 * An error as it crosses the protocol: `panic` when a trap poisoned the worker.
 * @typedef {{ message: string, panic: boolean }} WorkerError
 */

/**
 * What the worker reports when it is ready (and answers to PING).
 * @typedef {object} ReadyInfo
 * @property {string} version the wasm crate's version
 * @property {number} protocol the worker's PROTOCOL_VERSION
 * @property {number} threads
 * @property {boolean} threaded
 * @property {Record<string, unknown>} treeColors the core's default tree colour rules
 */

/**
 * A request, page → worker.
 * @typedef {{ id: number, type: string, payload?: unknown }} Request
 */

/**
 * A message worker → page: an answer to request `id`, a progress frame of it, or unprompted.
 * @typedef {{ id: number, ok: true, result: any }
 *   | { id: number, ok: false, error: WorkerError }
 *   | { id: number, event: string, data: any }
 *   | { type: 'sys/ready', result: ReadyInfo }
 *   | { type: 'sys/boot-failed', error: WorkerError }
 *   | { type: 'sys/poisoned', error: WorkerError }} WorkerMessage
 */
