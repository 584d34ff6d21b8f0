// The page's entry point (main thread): draws and listens, never runs wasm. All work goes to
// the worker through WorkerClient.
import { WorkerClient } from './client.js';
import { REQUESTS } from './protocol.js';

const client = new WorkerClient();
const status = document.getElementById('status');

client.addEventListener('status', (e) => {
  const d = e.detail;
  status.dataset.state = d.state;
  if (d.state === 'ready') {
    status.textContent = `ready — ${d.threads} thread${d.threads === 1 ? '' : 's'}`;
  } else if (d.state === 'starting') {
    status.textContent = 'starting…';
  } else if (d.state === 'crashed') {
    status.textContent = `restarting after an error: ${d.error.message}`;
  } else if (d.state === 'failed') {
    status.textContent = `could not start: ${d.error.message}`;
  }
});

// A handle for the browser tests and the curious: the page's worker client and protocol.
window.procfit = { client, REQUESTS };
