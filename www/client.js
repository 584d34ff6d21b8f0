// The page's side of the worker protocol (www/protocol.js): requests with ids and promises,
// progress events, and recovery — a worker that fails to boot, crashes or is poisoned by a
// panic is replaced by a fresh one, and pending requests fail with a readable error instead of
// hanging.

const WORKER_URL = new URL('./worker.js', import.meta.url);

export class WorkerClient extends EventTarget {
  constructor() {
    super();
    this.nextId = 1;
    this.pending = new Map();
    this.restarts = 0;
    this.info = null;
    this.start();
  }

  /** Starts (or restarts) the worker; `ready` resolves with { version, threads, threaded }. */
  start() {
    this.worker?.terminate();
    this.worker = new Worker(WORKER_URL, { type: 'module' });
    this.ready = new Promise((resolve, reject) => {
      this.resolveReady = resolve;
      this.rejectReady = reject;
    });
    this.ready.catch(() => {}); // reported through the 'status' event; avoid unhandled noise
    this.worker.onmessage = (e) => this.onMessage(e.data);
    this.worker.onerror = (e) => {
      e.preventDefault();
      this.fail({ message: `the worker failed: ${e.message || 'could not load'}`, panic: false });
    };
    this.dispatchEvent(new CustomEvent('status', { detail: { state: 'starting' } }));
  }

  onMessage(msg) {
    if (msg.type === 'sys/ready') {
      this.info = msg.result;
      this.resolveReady(msg.result);
      this.dispatchEvent(new CustomEvent('status', { detail: { state: 'ready', ...msg.result } }));
      return;
    }
    if (msg.type === 'sys/boot-failed') {
      this.rejectReady(new Error(msg.error.message));
      this.dispatchEvent(new CustomEvent('status', { detail: { state: 'failed', error: msg.error } }));
      return;
    }
    if (msg.type === 'sys/poisoned') {
      this.fail(msg.error);
      return;
    }
    const req = this.pending.get(msg.id);
    if (!req) return;
    if ('event' in msg) {
      req.onEvent?.(msg.event, msg.data);
      return;
    }
    this.pending.delete(msg.id);
    if (msg.ok) req.resolve(msg.result);
    else req.reject(Object.assign(new Error(msg.error.message), { panic: msg.error.panic }));
  }

  /** Fails every pending request with `error` and starts a fresh worker. */
  fail(error) {
    for (const req of this.pending.values()) {
      req.reject(Object.assign(new Error(error.message), { panic: error.panic }));
    }
    this.pending.clear();
    this.rejectReady(new Error(error.message));
    this.dispatchEvent(new CustomEvent('status', { detail: { state: 'crashed', error } }));
    this.restarts += 1;
    // Back off a little when restarts pile up, so a worker that cannot boot does not spin.
    setTimeout(() => this.start(), Math.min(5000, 100 * 2 ** Math.min(this.restarts, 6)));
  }

  /** Sends a request; resolves with its result, calls `onEvent(event, data)` for progress. */
  async call(type, payload, { onEvent, transfer = [] } = {}) {
    await this.ready;
    const id = this.nextId++;
    return new Promise((resolve, reject) => {
      this.pending.set(id, { resolve, reject, onEvent });
      this.worker.postMessage({ id, type, payload }, transfer);
    });
  }
}
