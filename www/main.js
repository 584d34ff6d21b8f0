// @ts-check
// The page's entry point (main thread): draws and listens, never runs wasm. All work goes to
// the worker through WorkerClient (page.js). Each step lives in its own module — photos
// (photo-step.js), mask tools (mask-step.js), windows (windows-ui.js), tree colours
// (tree-colors-ui.js), fit (fit-step.js), model (model-step.js), download (download.js),
// persistence (persistence.js) — and this file starts them: the worker's status line, then
// the generator specs, the model step and the saved session.
import { REQUESTS } from './protocol.js';
import { say } from './ui.js';
import { $, client, state } from './page.js';
import { restore } from './persistence.js';
import { loadSamples, renderPhotos } from './photo-step.js';
import { findMask, reviveMasks } from './mask-step.js';
import { buildGeneratorChoices, chooseGenerator, setUpModelStep } from './model-step.js';
import { updateFitButton } from './fit-step.js';
import './download.js';

const status = $('status');

client.addEventListener('status', (/** @type {CustomEvent} */ e) => {
  const d = e.detail;
  status.dataset.state = d.state;
  if (d.state === 'ready') {
    status.textContent = `ready — ${d.threads} thread${d.threads === 1 ? '' : 's'}`;
    const notice = $('notice');
    notice.hidden = d.threaded;
    notice.textContent = d.threaded
      ? ''
      : 'procfit is running on one thread: this page is served without cross-origin isolation (COOP/COEP headers), so it cannot use all your cores. Everything works; fits take longer.';
    // After a crash the worker is new but the session lives here: show the model again and
    // give each mask a worker session for corrections.
    if (client.restarts > 0) {
      state.editor?.schedule();
      reviveMasks();
    }
  } else if (d.state === 'starting') {
    status.textContent = 'starting…';
  } else if (d.state === 'crashed') {
    status.textContent = `restarting after an error: ${d.error.message}`;
  } else if (d.state === 'failed') {
    status.textContent = `could not start: ${d.error.message}`;
  }
});

async function boot() {
  const modelMessage = $('model-message');
  loadSamples();
  try {
    await client.ready;
    state.specs = await client.call(REQUESTS.GENERATOR_SPECS);
  } catch (err) {
    say(modelMessage, `The model editor could not start: ${err.message}. Reload the page to try again.`);
    return;
  }
  if (!state.specs.length) {
    say(modelMessage, 'This build has no generators.');
    return;
  }
  setUpModelStep();
  buildGeneratorChoices();
  const restored = await restore({
    photosRestored: () => {
      renderPhotos();
      reviveMasks();
      // Photos saved before their mask was ready get one now.
      state.photos.filter((p) => !p.mask).forEach((p) => findMask(p));
    },
    openModel: chooseGenerator,
  });
  if (!restored) chooseGenerator(state.specs[0].name);
  updateFitButton();
  document.body.dataset.ready = 'true';
}

boot();
