import { chromium } from 'playwright-core';
const [src, out, y] = process.argv.slice(2);
const b = await chromium.launch({ executablePath: '/usr/bin/chromium', args: ['--no-sandbox'] });
const p = await b.newPage({ viewport: { width: 1280, height: 900 } });
await p.goto('file://' + src);
await p.screenshot({ path: out, clip: { x: 0, y: Number(y), width: 1280, height: 900 } });
await b.close();
