// The wasm worker: the only place procfit's wasm runs. It loads the module, starts the rayon
// pool (wasm-bindgen-rayon must never be awaited on the main thread) and answers the requests
// of www/protocol.js. A panic inside wasm traps the instance: the worker reports it with the
// panic message and declares itself poisoned, and the page starts a fresh worker.
import { REQUESTS } from './protocol.js';

const early = [];
let wasm = null;
// Set before any await, so that no message sent during start-up is lost.
self.onmessage = (e) => (wasm ? dispatch(e.data) : early.push(e.data));

const handlers = {
  [REQUESTS.PING]: () => ({
    version: wasm.version(),
    threads: wasm.threaded() ? navigator.hardwareConcurrency : 1,
    threaded: wasm.threaded(),
  }),
  [REQUESTS.THREAD_PROBE]: ({ jobs = 64 } = {}) => ({ threads: wasm.threadProbe(jobs) }),
  [REQUESTS.DEBUG_PANIC]: () => wasm.debugPanic(),
  [REQUESTS.GENERATOR_SPECS]: () => wasm.generatorSpecs(),
  [REQUESTS.GENERATE_GLB]: ({ generator, params, lod }) => {
    const t0 = performance.now();
    const bytes = wasm.generateGlb(generator, Float64Array.from(params), lod);
    const ms = performance.now() - t0;
    // wasm-bindgen returns a fresh copy, so its buffer can be handed over without another copy.
    return new Transfer({ glb: bytes.buffer, ms }, [bytes.buffer]);
  },
  [REQUESTS.PARAMS_JSON]: ({ generator, params, lod }) => ({
    text: wasm.paramsJson(generator, Float64Array.from(params), lod),
  }),
  [REQUESTS.OPEN_MODEL]: ({ bytes }) => wasm.openModel(new Uint8Array(bytes)),
};

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
    const mod = await import('../pkg/procfit.js');
    await mod.default();
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
