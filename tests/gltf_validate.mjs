// Validates every .glb in a directory with the Khronos glTF-Validator (npm `gltf-validator`,
// offline) and prints one markdown row per file: size, errors, warnings, infos, hints.
//
// Usage: node tests/gltf_validate.mjs <dir>
// Exits non-zero when a file has any error or warning, when the directory holds no .glb, or on
// a validator crash; prints every error and warning message first.

import { readdirSync, readFileSync } from 'node:fs';
import { join } from 'node:path';
import validator from 'gltf-validator';

const dir = process.argv[2];
if (!dir) {
  console.error('usage: node tests/gltf_validate.mjs <dir-with-glb-files>');
  process.exit(2);
}
const files = readdirSync(dir).filter((f) => f.endsWith('.glb')).sort();
if (files.length === 0) {
  console.error(`no .glb files in ${dir}`);
  process.exit(1);
}

let failed = 0;
const rows = [];
const totals = { errors: 0, warnings: 0, infos: 0, hints: 0, bytes: 0 };
for (const file of files) {
  const bytes = new Uint8Array(readFileSync(join(dir, file)));
  const report = await validator.validateBytes(bytes, {
    uri: file,
    maxIssues: 100,
    // A GLB from procfit is self-contained: any external reference is itself a failure.
    externalResourceFunction: (uri) => Promise.reject(new Error(`external resource ${uri}`)),
  });
  const i = report.issues;
  for (const m of i.messages) {
    // Severity 0 = error, 1 = warning (2 info, 3 hint are reported in the counts only).
    if (m.severity <= 1) {
      console.error(`${file}: ${m.severity === 0 ? 'ERROR' : 'WARNING'} ${m.code} at ${m.pointer}: ${m.message}`);
    }
  }
  if (i.numErrors > 0 || i.numWarnings > 0) failed += 1;
  totals.errors += i.numErrors;
  totals.warnings += i.numWarnings;
  totals.infos += i.numInfos;
  totals.hints += i.numHints;
  totals.bytes += bytes.length;
  const info = report.info ?? {};
  rows.push(
    `| ${file} | ${bytes.length} | ${info.totalTriangleCount ?? '?'} | ${i.numErrors} | ${i.numWarnings} | ${i.numInfos} | ${i.numHints} |`,
  );
}

console.log('| file | bytes | triangles | errors | warnings | infos | hints |');
console.log('|---|---:|---:|---:|---:|---:|---:|');
for (const r of rows) console.log(r);
console.log(
  `| **${files.length} files** | ${totals.bytes} | | ${totals.errors} | ${totals.warnings} | ${totals.infos} | ${totals.hints} |`,
);
if (failed > 0) {
  console.error(`${failed} of ${files.length} files have errors or warnings`);
  process.exit(1);
}
