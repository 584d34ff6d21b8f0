// @ts-check
// The windows tools of the mask step, shown for a generator whose fit reads window labels
// (its spec's `mask_extra` is 'windows'): how much of the object is marked as window, what
// the last mask correction did to the windows, find them automatically, clear them.
import { say } from './ui.js';
import { detectWindows, WINDOW } from './window-labels.js';
import { $, client, selectedPhoto, specOf, fitGenerator } from './page.js';
import { persist } from './persistence.js';
import { maskEditor } from './mask-step.js';

/**
 * The windows tools: shown when the chosen generator reads window labels, with how much of
 * the object is marked as window and what the last mask correction did to the windows (found
 * again, or painted ones clipped).
 */
export function renderWindowTools() {
  const photo = selectedPhoto();
  const windows = specOf(fitGenerator())?.mask_extra === 'windows';
  const tools = $('window-tools');
  tools.hidden = !windows || !photo?.mask;
  if (tools.hidden && ['window', 'wall'].includes(maskEditor.tool)) {
    /** @type {HTMLInputElement} */ (document.querySelector('input[name="tool"][value="none"]')).checked = true;
    maskEditor.setTool('none');
  }
  if (maskEditor.showWindows !== windows) {
    maskEditor.showWindows = windows;
    maskEditor.draw();
  }
  const codes = photo?.windows?.codes;
  $('windows-clear').disabled = !codes;
  const note = photo?.windowsNote ? ` ${photo.windowsNote}` : '';
  if (!codes) {
    $('windows-state').textContent = `No windows marked yet.${note}`;
    return;
  }
  let win = 0;
  let inside = 0;
  for (const c of codes) {
    if (c === WINDOW) win += 1;
    if (c === 1 || c === WINDOW) inside += 1;
  }
  $('windows-state').textContent = `${
    win
      ? `Windows marked in teal: ${Math.round((100 * win) / Math.max(1, inside))} % of the building.`
      : 'No windows found: paint a few with the windows brush.'
  }${note}`;
}

$('windows-auto').addEventListener('click', async () => {
  const photo = selectedPhoto();
  if (!photo?.mask) return;
  const photosMessage = $('photos-message');
  say(photosMessage, '');
  $('windows-state').textContent = 'Looking for windows…';
  try {
    await photo.reviving;
    await detectWindows(client, photo);
  } catch (err) {
    say(photosMessage, `No windows found: ${err.message}. Paint a few with the windows brush.`);
  }
  maskEditor.draw();
  renderWindowTools();
  persist();
});

$('windows-clear').addEventListener('click', () => {
  const photo = selectedPhoto();
  if (!photo) return;
  photo.windows = null;
  photo.windowsNote = '';
  maskEditor.draw();
  renderWindowTools();
  persist();
});
