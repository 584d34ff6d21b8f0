// Prints procfit's wasm benchmark table: serves the repository, opens bench.html in headless
// Chromium (the same flags as the browser tests) and waits for www/bench-worker.js to finish.
// Run by `make bench` after `make wasm`.
import { startServer, launchBrowser, openPage } from '../tests/e2e/harness.mjs';

const server = await startServer();
const browser = await launchBrowser();
try {
  const { page } = await openPage(browser.context, `${server.url}bench.html`);
  await page.waitForFunction(() => window.benchResults, null, { timeout: 15 * 60 * 1000, polling: 1000 });
  const res = await page.evaluate(() => window.benchResults);
  if (res.type === 'error') throw new Error(res.message);
  console.log(`\nwasm in headless Chromium, ${res.threads} threads; medians in ms (min–max)\n`);
  let group = null;
  for (const r of res.rows) {
    if (r.group !== group) {
      group = r.group;
      console.log(`\n| ${group} | median ms | min | max | runs |\n|---|---:|---:|---:|---:|`);
    }
    console.log(`| ${r.name} | ${r.median.toFixed(3)} | ${r.min.toFixed(3)} | ${r.max.toFixed(3)} | ${r.n} |`);
  }
} finally {
  await browser.close();
  server.stop();
}
