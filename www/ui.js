// @ts-check
// Small DOM helpers shared by the page's modules: element creation, messages a person can act
// on, and file downloads. No framework: the page is a handful of ES modules.

/**
 * Creates an element. `attrs`: attributes (booleans toggle presence; `class`, `for`, data-*
 * and aria-* are plain attributes); `children`: nodes or strings.
 */
export function el(tag, attrs = {}, children = []) {
  const node = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (v === false || v === null || v === undefined) continue;
    if (v === true) node.setAttribute(k, '');
    else node.setAttribute(k, String(v));
  }
  for (const c of children) node.append(c);
  return node;
}

/**
 * Shows `text` in the message box `box` (an element with role=alert or status). `kind`:
 * 'error' | 'info'. An empty text hides the box.
 */
export function say(box, text, kind = 'error') {
  box.textContent = text || '';
  box.dataset.kind = kind;
  box.hidden = !text;
}

/** Offers `bytes` (Uint8Array or string) as a download called `name`. */
export function download(bytes, name, type) {
  const url = URL.createObjectURL(new Blob([bytes], { type }));
  const a = el('a', { href: url, download: name });
  document.body.append(a);
  a.click();
  a.remove();
  // Revoke later: some browsers read the blob after click() returns.
  setTimeout(() => URL.revokeObjectURL(url), 10000);
}

/** A file name without its extension, safe to reuse in a download name. */
export function stem(name) {
  return (name || 'model').replace(/\.[^.]*$/, '').replace(/[^\w.-]+/g, '_').slice(0, 60) || 'model';
}
