// @ts-check
// The page's side of the worker protocol (www/protocol.js): requests with ids and promises,
// progress events, and recovery — a worker that fails to boot, crashes or is poisoned by a
// panic is replaced by a fresh one, and pending requests fail with a readable error instead of
// hanging.

import { PROTOCOL_VERSION } from './protocol.js';

const WORKER_URL = new URL('./worker.js', import.meta.url);

/**
 * Why the page refuses a worker of another protocol version, or null when it speaks this one.
 * @param {import('./protocol.js').ReadyInfo} info
 */
export function protocolMismatch(info) {
  if (info?.protocol === PROTOCOL_VERSION) return null;
  return `the worker speaks protocol ${info?.protocol ?? 'unknown'} but this page speaks ${PROTOCOL_VERSION} (an old copy of one of them may be cached): reload the page`;
}

export class WorkerClient extends EventTarget {
  constructor() {
    super();
    this.nextId = 1;
    /** @type {Map<number, { resolve: (v: any) => void, reject: (e: Error) => void, onEvent?: (event: string, data: any) => void }>} */
    this.pending = new Map();
    this.restarts = 0;
    /** @type {import('./protocol.js').ReadyInfo | null} */
    this.info = null;
    /** @type {Worker | undefined} */
    this.worker = undefined;
    this.start();
  }

  /** Starts (or restarts) the worker; `ready` resolves with { version, threads, threaded }. */
  start() {
    this.worker?.terminate();
    this.worker = new Worker(WORKER_URL, { type: 'module' });
    /** @type {Promise<import('./protocol.js').ReadyInfo>} */
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

  /** @param {import('./protocol.js').WorkerMessage} msg */
  onMessage(msg) {
    if ('type' in msg && msg.type === 'sys/ready') {
      const mismatch = protocolMismatch(msg.result);
      if (mismatch) {
        // Not restarted: a new worker would be the same file.
        this.worker?.terminate();
        this.rejectReady(new Error(mismatch));
        this.dispatchEvent(new CustomEvent('status', { detail: { state: 'failed', error: { message: mismatch, panic: false } } }));
        return;
      }
      this.info = msg.result;
      this.resolveReady(msg.result);
      this.dispatchEvent(new CustomEvent('status', { detail: { state: 'ready', ...msg.result } }));
      return;
    }
    if ('type' in msg && msg.type === 'sys/boot-failed') {
      this.rejectReady(new Error(msg.error.message));
      this.dispatchEvent(new CustomEvent('status', { detail: { state: 'failed', error: msg.error } }));
      return;
    }
    if ('type' in msg && msg.type === 'sys/poisoned') {
      this.fail(msg.error);
      return;
    }
    if (!('id' in msg)) return;
    const req = this.pending.get(msg.id);
    if (!req) return;
    if ('event' in msg) {
      req.onEvent?.(msg.event, msg.data);
      return;
    }
    this.pending.delete(msg.id);
    if ('ok' in msg && msg.ok) req.resolve(msg.result);
    else if ('error' in msg) req.reject(Object.assign(new Error(msg.error.message), { panic: msg.error.panic }));
  }

  /**
   * Fails every pending request with `error` and starts a fresh worker.
   * @param {import('./protocol.js').WorkerError} error
   */
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

  /**
   * Sends a request; resolves with its result, calls `onEvent(event, data)` for progress.
   * @param {string} type one of protocol.js's REQUESTS
   * @param {unknown} [payload]
   * @param {{ onEvent?: (event: string, data: any) => void, transfer?: Transferable[] }} [options]
   * @returns {Promise<any>}
   */
  async call(type, payload, { onEvent, transfer = [] } = {}) {
    await this.ready;
    const id = this.nextId++;
    return new Promise((resolve, reject) => {
      this.pending.set(id, { resolve, reject, onEvent });
      this.worker.postMessage({ id, type, payload }, transfer);
    });
  }
}
