// @ts-check
// Tree labels (a generator whose spec's `mask_extra` is 'tree_labels'): each photo's colour
// rules (`photo.treeColors`, over the core's defaults) and the branch / leaf labels the worker
// sorts its pixels into inside the mask, which the tree fit sees and the overlay shows.
import { REQUESTS } from './protocol.js';
import { photoPixels, fitCodes } from './masking.js';

/**
 * Changed from the defaults, the colour rules for orange, red and yellow leaves as well as
 * green; dark bark stays bark. The rules sort a tree photo's pixels into leaves and branches:
 * the fields of the core's ColorThresholds (hues in degrees, a range starting above its end
 * wraps through red); the defaults come from the worker (`client.info.treeColors`).
 */
export const AUTUMN_CHANGE = Object.freeze({ leafHue: [330, 170], leafMinValue: 0.45 });

/** `photo`'s colour rules: its own, or the core's defaults that `client` reported. */
export function treeColors(client, photo) {
  return { ...client.info.treeColors, ...(photo.treeColors ?? {}) };
}

/** Asks the worker for `photo`'s tree labels (branch / leaf by colour, inside the mask). */
export async function treeLabels(client, photo) {
  const rgba = photoPixels(photo);
  const codes = fitCodes(photo).buffer;
  const { width, height } = photo.mask;
  const colors = treeColors(client, photo);
  const t = await client.call(REQUESTS.TREE_LABELS, { width, height, rgba, codes, colors }, { transfer: [rgba, codes] });
  photo.treeLabels = new Uint8Array(t.labels);
  return photo.treeLabels;
}
