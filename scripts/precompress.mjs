// Writes FILE.br and FILE.gz beside every compressible file of a folder (what `make dist`
// ships, so a static host or scripts/serve.py can send them as is): brotli at quality 11, gzip
// at level 9. A compressed copy that is not smaller than the file is not kept. Prints a table.
//
// Usage: node scripts/precompress.mjs <dir>
import { readdirSync, readFileSync, writeFileSync, statSync, rmSync } from 'node:fs';
import { join, extname, relative } from 'node:path';
import { brotliCompressSync, gzipSync, constants } from 'node:zlib';

const COMPRESSIBLE = new Set(['.html', '.js', '.mjs', '.css', '.json', '.wasm', '.svg', '.glb', '.txt', '.md']);
const MIN_BYTES = 1024;

const dir = process.argv[2];
if (!dir) {
  console.error('usage: node scripts/precompress.mjs <dir>');
  process.exit(2);
}

function* files(d) {
  for (const entry of readdirSync(d, { withFileTypes: true })) {
    const path = join(d, entry.name);
    if (entry.isDirectory()) yield* files(path);
    else if (entry.isFile()) yield path;
  }
}

let raw = 0;
let br = 0;
let n = 0;
for (const path of [...files(dir)].sort()) {
  if (!COMPRESSIBLE.has(extname(path)) || statSync(path).size < MIN_BYTES) continue;
  const bytes = readFileSync(path);
  const brotli = brotliCompressSync(bytes, {
    params: {
      [constants.BROTLI_PARAM_QUALITY]: 11,
      [constants.BROTLI_PARAM_SIZE_HINT]: bytes.length,
      [constants.BROTLI_PARAM_MODE]: extname(path) === '.wasm' ? constants.BROTLI_MODE_GENERIC : constants.BROTLI_MODE_TEXT,
    },
  });
  const gz = gzipSync(bytes, { level: 9 });
  for (const [suffix, data] of [['.br', brotli], ['.gz', gz]]) {
    if (data.length < bytes.length) writeFileSync(path + suffix, data);
    else rmSync(path + suffix, { force: true });
  }
  raw += bytes.length;
  br += Math.min(brotli.length, bytes.length);
  n += 1;
  console.log(`${relative(dir, path)}\t${bytes.length}\tbr ${brotli.length}\tgz ${gz.length}`);
}
console.log(`${n} files: ${raw} bytes, ${br} as brotli`);
