// The wasm benchmark page (bench.html): runs www/bench-worker.js and shows its table. Driven
// headless by scripts/bench-wasm.mjs (`make bench`); also useful opened by hand in a browser.
const status = document.getElementById('status');
const out = document.getElementById('results');
const worker = new Worker(new URL('./bench-worker.js', import.meta.url), { type: 'module' });
worker.onmessage = (e) => {
  const msg = e.data;
  if (msg.type === 'progress') {
    status.textContent = `running: ${msg.label}`;
  } else if (msg.type === 'done') {
    window.benchResults = msg;
    status.textContent = `done — ${msg.threads} threads`;
    out.textContent = msg.rows
      .map((r) => `${r.group}\t${r.name}\t${r.median.toFixed(3)} ms (min ${r.min.toFixed(3)}, max ${r.max.toFixed(3)}, n=${r.n})`)
      .join('\n');
  } else if (msg.type === 'error') {
    window.benchResults = msg;
    status.textContent = `failed: ${msg.message}`;
  }
};
