// Times procfit's wasm workloads (src/web/bench.rs) with performance.now() in a worker with the
// rayon pool: renderer forward/backward, generators, and photo → mask. Medians of repeated runs
// after warm-up; the same workloads as the native `cargo bench` tables.
self.onmessage = () => {};

function time(fn, reps, warmup = 2) {
  for (let i = 0; i < warmup; i++) fn();
  const t = [];
  for (let i = 0; i < reps; i++) {
    const t0 = performance.now();
    fn();
    t.push(performance.now() - t0);
  }
  t.sort((a, b) => a - b);
  return { median: t[Math.floor(t.length / 2)], min: t[0], max: t[t.length - 1], n: reps };
}

async function run() {
  const wasm = await import('../pkg/procfit.js');
  await wasm.default();
  const threads = wasm.threaded() ? navigator.hardwareConcurrency : 1;
  if (wasm.threaded()) await wasm.initThreadPool(threads);
  const rows = [];
  const add = (group, name, r) => {
    rows.push({ group, name, ...r });
    self.postMessage({ type: 'progress', label: `${group} ${name}` });
  };

  for (const large of [false, true]) {
    for (const size of [128, 256, 512]) {
      const b = new wasm.RenderBench(large, size, 4);
      const mesh = `cup ${b.vertexCount()} v ${size}²`;
      b.setParallel(false);
      add('render', `${mesh} forward 1T`, time(() => b.forward(), 30));
      add('render', `${mesh} fwd+bwd 1T`, time(() => b.forwardBackward(), 30));
      add('render', `${mesh} 4 views 1T`, time(() => b.evaluate(), 15));
      b.setParallel(true);
      add('render', `${mesh} 4 views rayon`, time(() => b.evaluate(), 15));
      b.free();
    }
  }

  for (const [gen, preset, lod] of [
    ['dish', 'mug', 0],
    ['dish', 'mug', 1],
    ['building', 'panel_block', 1],
    ['building', 'panel_block', 3],
  ]) {
    const b = new wasm.GeneratorBench(gen, preset, lod);
    const name = `${gen} ${preset} lod ${lod} (${b.vertexCount()} v)`;
    add('generator', `${name} generate`, time(() => b.generate(), 30));
    add('generator', `${name} gradient`, time(() => b.gradient(), 30));
    b.free();
  }

  const s = new wasm.SegmentBench();
  add('segment', `decode 12 MP JPEG (${(s.jpegBytes() / 1024) | 0} KB) + downscale`, time(() => s.decode(), 5, 1));
  add('segment', 'automatic mask', time(() => s.automatic(), 5, 1));
  add('segment', 'interactive re-cut', time(() => s.recut(), 9, 1));
  s.free();

  self.postMessage({ type: 'done', threads, rows });
}

run().catch((err) => self.postMessage({ type: 'error', message: String(err && err.message || err) }));
