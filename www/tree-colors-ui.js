// @ts-check
// The tree labels of the mask step, shown for a generator whose fit reads branch/leaf labels
// (its spec's `mask_extra` is 'tree_labels'): the labels over the photo with their shares, and
// "Adjust the colours", the colour rules that sort the photo's pixels into leaves and branches.
import { treeLabels, treeColors, AUTUMN_CHANGE } from './tree-labels.js';
import { $, client, state, selectedPhoto, specOf, fitGenerator } from './page.js';
import { persist } from './persistence.js';
import { maskEditor } from './mask-step.js';

/**
 * The branch / leaf labels the fit will see, over the photo, with their shares. They are made
 * again when the photo or its mask changes.
 */
export function renderTreeLabels() {
  const photo = selectedPhoto();
  const tree = specOf(fitGenerator())?.mask_extra === 'tree_labels';
  const line = $('tree-state');
  line.hidden = !tree || !photo?.mask;
  $('tree-colors').hidden = line.hidden;
  if (maskEditor.showTree !== tree) {
    maskEditor.showTree = tree;
    maskEditor.draw();
  }
  if (line.hidden) return;
  showTreeColors(photo);
  const labels = photo.treeLabels;
  const colorsKey = JSON.stringify(treeColors(client, photo));
  // Made again when the mask or the colours change (an error counts as an answer too).
  if (photo.treeLabelsFor !== photo.mask.codes || photo.treeLabelsColors !== colorsKey) {
    line.textContent = 'Sorting branches from leaves…';
    // One request at a time; the last one's answer is checked against the photo's colours
    // and mask again, so quick slider moves end with the labels of the final values.
    if (photo.treeLabelsPending) return;
    photo.treeLabelsPending = true;
    const codes = photo.mask.codes;
    treeLabels(client, photo)
      .then(() => {
        photo.treeError = null;
      })
      .catch((err) => {
        photo.treeLabels = null;
        photo.treeError = err.message;
      })
      .finally(() => {
        photo.treeLabelsFor = codes;
        photo.treeLabelsColors = colorsKey;
        photo.treeLabelsPending = false;
        if (state.selected !== photo.id) return;
        maskEditor.draw();
        renderTreeLabels();
      });
    return;
  }
  if (photo.treeError) {
    line.textContent = `The tree fit cannot use this photo: ${photo.treeError}`;
    return;
  }
  let branch = 0;
  let leaf = 0;
  for (const l of labels) {
    if (l === 1) branch += 1;
    else if (l === 2) leaf += 1;
  }
  const all = Math.max(1, branch + leaf);
  const missing = !leaf ? 'No leaves found by their colour: if they are not green, open "Adjust the colours" (autumn leaves, say). ' : !branch ? 'No trunk or branches found by their colour: open "Adjust the colours" (or count everything else inside the mask as branches). ' : '';
  line.textContent = `${missing}What the tree fit sees, by colour: branches in brown (${Math.round((100 * branch) / all)} %), leaves in green (${Math.round((100 * leaf) / all)} %). Trees are fitted to one photo, the first.`;
}

/**
 * The "Adjust the colours" controls show `photo`'s colour rules.
 * @param {import('./page.js').Photo} photo
 */
function showTreeColors(photo) {
  const c = treeColors(client, photo);
  const set = (id, v, text) => {
    $(id).value = String(v);
    $(`${id}-out`).textContent = text;
  };
  set('leaf-hue-from', c.leafHue[0], `${c.leafHue[0]}°`);
  set('leaf-hue-to', c.leafHue[1], `${c.leafHue[1]}°`);
  set('leaf-min-value', c.leafMinValue, c.leafMinValue.toFixed(2));
  set('leaf-min-saturation', c.leafMinSaturation, c.leafMinSaturation.toFixed(2));
  set('bark-max-value', c.barkValue[1], c.barkValue[1].toFixed(2));
  $('rest-as-branch').checked = c.restAsBranch;
  // The hue strip: the chosen leaf hues bright, the rest faded (a range may wrap through red).
  const strip = $('leaf-hue-strip');
  const ctx = strip.getContext('2d');
  const [lo, hi] = c.leafHue;
  for (let h = 0; h < 360; h += 1) {
    const on = lo <= hi ? h >= lo && h <= hi : h >= lo || h <= hi;
    ctx.fillStyle = `hsl(${h} ${on ? 75 : 18}% ${on ? 45 : 80}%)`;
    ctx.fillRect(h, 0, 1, strip.height);
  }
}

/**
 * Changes the selected photo's colour rules and sorts its pixels again (`null`: back to the
 * defaults).
 * @param {object | null} change
 */
function changeTreeColors(change) {
  const photo = selectedPhoto();
  if (!photo) return;
  photo.treeColors = change === null ? null : { ...treeColors(client, photo), ...change };
  renderTreeLabels();
  persist();
}

for (const [id, field] of [['leaf-min-value', 'leafMinValue'], ['leaf-min-saturation', 'leafMinSaturation']]) {
  $(id).addEventListener('input', (e) => changeTreeColors({ [field]: Number(e.target.value) }));
}
$('leaf-hue-from').addEventListener('input', (e) => changeTreeColors({ leafHue: [Number(e.target.value), Number($('leaf-hue-to').value)] }));
$('leaf-hue-to').addEventListener('input', (e) => changeTreeColors({ leafHue: [Number($('leaf-hue-from').value), Number(e.target.value)] }));
$('bark-max-value').addEventListener('input', (e) => changeTreeColors({ barkValue: [client.info.treeColors.barkValue[0], Number(e.target.value)] }));
$('rest-as-branch').addEventListener('change', (e) => changeTreeColors({ restAsBranch: e.target.checked }));
$('colors-autumn').addEventListener('click', () => changeTreeColors({ ...client.info.treeColors, ...AUTUMN_CHANGE }));
$('colors-reset').addEventListener('click', () => changeTreeColors(null));
