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
