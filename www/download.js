// @ts-check
// The download step: the model as the very GLB the 3D view shows, or as params JSON; and
// opening a saved model (GLB or JSON) to edit again.
import { REQUESTS } from './protocol.js';
import { say, download, stem } from './ui.js';
import { LODS } from './editor.js';
import { $, client, state } from './page.js';
import { openModelFile } from './model-step.js';

const outMessage = $('out-message');

/** The downloaded files' name: generator, preset (when one is shown) and level of detail. */
function fileStem() {
  const st = state.editor.state;
  return stem(`${st.generator}${state.presetName && !['custom', 'fitted'].includes(state.presetName) ? '-' + state.presetName : ''}-${LODS[st.lod].toLowerCase()}`);
}

$('download-glb').addEventListener('click', async () => {
  await state.editor.settled();
  const glb = state.editor.glb;
  if (!glb) return;
  download(glb.bytes, `${fileStem()}.glb`, 'model/gltf-binary');
});

$('download-json').addEventListener('click', async () => {
  try {
    const { text } = await client.call(REQUESTS.PARAMS_JSON, state.editor.state);
    download(text, `${fileStem()}.json`, 'application/json');
  } catch (err) {
    say(outMessage, `Could not save the parameters: ${err.message}`);
  }
});

$('open-model').addEventListener('change', async (e) => {
  const file = e.target.files[0];
  e.target.value = '';
  if (file) await openModelFile(file);
});
