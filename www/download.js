// @ts-check
// The download step: the model as the very GLB the 3D view shows, or as params JSON; the other
// formats of the download menu (issue 17: compact GLB, OBJ + MTL, STL), written by the worker
// from the model the editor shows; and opening a saved model (GLB or JSON) to edit again.
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

/**
 * What each download-menu entry asks the worker for, and how its files are saved.
 * @type {Record<string, { format: string, compact: boolean, ext: string, type: string, companion?: { ext: string, type: string } }>}
 */
export const FORMATS = {
  'glb-compact': { format: 'glb', compact: true, ext: 'glb', type: 'model/gltf-binary' },
  obj: { format: 'obj', compact: false, ext: 'obj', type: 'model/obj', companion: { ext: 'mtl', type: 'model/mtl' } },
  stl: { format: 'stl', compact: false, ext: 'stl', type: 'model/stl' },
};

/** `#download-as` saves the model in `#download-format`'s format; enabled whenever "Download GLB" is. */
function initDownloadMenu() {
  const select = /** @type {HTMLSelectElement | null} */ (document.getElementById('download-format'));
  const button = /** @type {HTMLButtonElement | null} */ (document.getElementById('download-as'));
  const glbButton = /** @type {HTMLButtonElement | null} */ (document.getElementById('download-glb'));
  if (!select || !button || !glbButton) return;
  const mirror = () => {
    button.disabled = glbButton.disabled;
  };
  new MutationObserver(mirror).observe(glbButton, { attributes: true, attributeFilter: ['disabled'] });
  mirror();
  button.addEventListener('click', async () => {
    const choice = FORMATS[select.value];
    const ed = state.editor;
    if (!choice || !ed) return;
    button.disabled = true;
    try {
      await ed.settled();
      const name = fileStem();
      const fileName = `${name}.${choice.ext}`;
      const { files } = await client.call(REQUESTS.EXPORT_FILES, { ...ed.state, format: choice.format, compact: choice.compact, fileName });
      download(files[0], choice.compact ? `${name}.compact.glb` : fileName, choice.type);
      if (choice.companion && files[1]) download(files[1], `${name}.${choice.companion.ext}`, choice.companion.type);
    } catch (err) {
      say(outMessage, `Could not save the model: ${err.message}`);
    } finally {
      mirror();
    }
  });
}
initDownloadMenu();
