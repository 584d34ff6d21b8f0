// Shared set-up for the browser tests: start procfit's dev server on a free port, launch Debian's
// Chromium headless through playwright-core, and record what a page does (console errors, page
// errors, every request) so tests can assert on it.
import { spawn } from 'node:child_process';
import { mkdtempSync, rmSync, mkdirSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';

export const ROOT = join(dirname(fileURLToPath(import.meta.url)), '..', '..');
export const ARTIFACTS = join(ROOT, 'test-artifacts');

/** Starts scripts/serve.py; resolves with { url, stop }. */
export function startServer({ root = ROOT, isolation = true, port = 0 } = {}) {
  const args = [join(ROOT, 'scripts', 'serve.py'), '--root', root, '--port', String(port)];
  if (!isolation) args.push('--no-isolation');
  const proc = spawn('python3', args, { stdio: ['ignore', 'pipe', 'pipe'] });
  return new Promise((resolve, reject) => {
    let out = '';
    let err = '';
    proc.stdout.on('data', (d) => {
      out += d;
      const m = out.match(/^(http:\/\/127\.0\.0\.1:\d+\/)/m);
      if (m) resolve({ url: m[1], proc, stop: () => proc.kill() });
    });
    proc.stderr.on('data', (d) => (err += d));
    proc.on('exit', (code) => reject(new Error(`server exited ${code}: ${err}`)));
  });
}

const CHROMIUM_ARGS = [
  '--no-sandbox',
  '--disable-gpu',
  '--disable-quic',
  '--no-first-run',
  '--disable-background-networking',
  '--disable-component-update',
  '--disable-sync',
  '--use-fake-device-for-media-stream',
  '--use-fake-ui-for-media-stream',
];

/** Launches headless Chromium with a fresh profile; resolves with { context, close }. */
export async function launchBrowser() {
  const dir = mkdtempSync(join(tmpdir(), 'procfit-chromium-'));
  const context = await chromium.launchPersistentContext(dir, {
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    headless: true,
    acceptDownloads: true,
    args: CHROMIUM_ARGS,
    viewport: { width: 1280, height: 900 },
  });
  return {
    context,
    close: async () => {
      await context.close();
      rmSync(dir, { recursive: true, force: true });
    },
  };
}

/**
 * Loads `url` in a fresh browser until the first model is drawn: resolves with the requests'
 * { url, transferred, decoded }, every console warning or error of the page and its workers, and
 * `close` (the browser). The weight test asserts on it; the page bench prints it.
 */
export async function firstLoad(url) {
  const browser = await launchBrowser();
  const files = [];
  const noise = [];
  browser.context.on('requestfinished', async (request) => {
    const response = await request.response();
    const sizes = await request.sizes();
    const body = response ? await response.body().catch(() => Buffer.alloc(0)) : Buffer.alloc(0);
    files.push({
      url: request.url(),
      transferred: sizes.responseBodySize + sizes.responseHeadersSize,
      decoded: body.length,
    });
  });
  const page = await browser.context.newPage();
  const listen = (where) => (m) => {
    // Headless Chromium's software GL driver reports its own performance notes ("GL Driver
    // Message … GPU stall due to ReadPixels") as console warnings; they are the driver's, not
    // the page's, and a hardware GPU prints none.
    if (/^\[\.WebGL-[0-9a-fx]+\]GL Driver Message/.test(m.text())) return;
    if (m.type() === 'warning' || m.type() === 'error') noise.push(`${where} ${m.type()}: ${m.text()}`);
  };
  page.on('console', listen('page'));
  page.on('worker', (w) => w.on('console', listen(`worker ${w.url()}`)));
  page.on('pageerror', (e) => noise.push(`page error: ${e}`));
  await page.goto(url);
  await page.waitForSelector('body[data-ready="true"]', { timeout: 120000 });
  await page.evaluate(() => window.procfit.editor.settled());
  // Let the last responses' sizes arrive.
  await page.waitForTimeout(500);
  return { files, noise, close: () => browser.close() };
}

/** Opens a page and records its console errors, page errors and requests. */
export async function openPage(context, url) {
  const page = await context.newPage();
  const log = { consoleErrors: [], pageErrors: [], requests: [] };
  page.on('console', (m) => m.type() === 'error' && log.consoleErrors.push(m.text()));
  page.on('pageerror', (e) => log.pageErrors.push(String(e)));
  context.on('request', (r) => log.requests.push(r.url()));
  await page.goto(url);
  return { page, log };
}

/** Waits until the page's worker says ready (the status line's state). */
export async function waitReady(page, timeout = 60000) {
  await page.waitForFunction(() => document.getElementById('status').dataset.state === 'ready', null, { timeout });
}

/**
 * Serves the repository, launches Chromium and opens the page until its worker is ready:
 * resolves with { server, browser, page, log, close }.
 */
export async function openReadyPage(path = '') {
  const server = await startServer();
  const browser = await launchBrowser();
  const { page, log } = await openPage(browser.context, server.url + path);
  await waitReady(page);
  return {
    server,
    browser,
    page,
    log,
    close: async () => {
      await browser.close();
      server.stop();
    },
  };
}

/** Saves a screenshot under test-artifacts/ (kept by CI runs for people to look at). */
export async function screenshot(page, name) {
  mkdirSync(ARTIFACTS, { recursive: true });
  const path = join(ARTIFACTS, `${name}.png`);
  await page.screenshot({ path, fullPage: true });
  return path;
}

export function writeArtifact(name, data) {
  mkdirSync(ARTIFACTS, { recursive: true });
  writeFileSync(join(ARTIFACTS, name), data);
}
