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
  PING: 'sys/ping', //             → { version, threads, threaded }
  THREAD_PROBE: 'sys/threadProbe', // { jobs } → { threads } distinct pool threads that ran jobs
  DEBUG_PANIC: 'sys/debugPanic', // → never answers ok: panics inside wasm, for the error test
  GENERATOR_SPECS: 'gen/specs', // → [{ name, label, version, differentiable, params, presets }]
  // { generator, params: number[], lod: 0..3 } → { glb: ArrayBuffer, ms }: the model's mesh as
  // the very GLB the page downloads (the viewer loads these bytes); `ms` is the worker's time.
  GENERATE_GLB: 'gen/glb',
  // { generator, params, lod } → { text }: the params JSON of the model.
  PARAMS_JSON: 'model/json',
  // { bytes: ArrayBuffer } (a procfit GLB or params JSON) → { generator, params, lod, seed }.
  OPEN_MODEL: 'model/open',
});

export const PROTOCOL_VERSION = 2;
