// The download menu's other formats (issue 17): compact GLB, OBJ + MTL and STL, written by the
// worker from the model the editor shows (the plain GLB stays the "Download GLB" button, which
// saves the very bytes on screen). Draws and listens only; the export runs in the worker.
import { REQUESTS } from './protocol.js';
import { download } from './ui.js';

/** What each menu entry asks the worker for, and how its files are saved. */
export const FORMATS = {
  'glb-compact': { format: 'glb', compact: true, ext: 'glb', type: 'model/gltf-binary' },
  obj: { format: 'obj', compact: false, ext: 'obj', type: 'model/obj', companion: { ext: 'mtl', type: 'model/mtl' } },
  stl: { format: 'stl', compact: false, ext: 'stl', type: 'model/stl' },
};

/**
 * Wires `#download-format` and `#download-as`: `client` is the worker client, `editor()` the
 * current editor, `fileStem()` the download name without extension, `onError(message)` shows a
 * failure. The button is enabled whenever "Download GLB" is.
 */
export function initDownloadMenu({ client, editor, fileStem, onError }) {
  const select = document.getElementById('download-format');
  const button = document.getElementById('download-as');
  const glbButton = document.getElementById('download-glb');
  if (!select || !button || !glbButton) return;
  const mirror = () => { button.disabled = glbButton.disabled; };
  new MutationObserver(mirror).observe(glbButton, { attributes: true, attributeFilter: ['disabled'] });
  mirror();
  button.addEventListener('click', async () => {
    const choice = FORMATS[select.value];
    const ed = editor();
    if (!choice || !ed) return;
    button.disabled = true;
    try {
      await ed.settled();
      const stem = fileStem();
      const fileName = `${stem}.${choice.ext}`;
      const { files } = await client.call(REQUESTS.EXPORT_FILES, {
        ...ed.state,
        format: choice.format,
        compact: choice.compact,
        fileName,
      });
      download(files[0], choice.compact ? `${stem}.compact.glb` : fileName, choice.type);
      if (choice.companion && files[1]) {
        download(files[1], `${stem}.${choice.companion.ext}`, choice.companion.type);
      }
    } catch (err) {
      onError(`Could not save the model: ${err.message}`);
    } finally {
      mirror();
    }
  });
}
