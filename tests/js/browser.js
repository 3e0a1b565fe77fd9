// The browsers every browser test here starts, driven by puppeteer-core: Debian's chromium
// (headless, over the DevTools protocol) or Debian's firefox-esr (over WebDriver BiDi). Which one:
// SWEEPMAP_BROWSER=chromium (the default) or firefox. Each gets a new empty profile and no
// network besides the page's own host; nothing is fetched by the browser itself.
//
// Firefox runs with a window on its own Xvfb display, not headless: headless Firefox on Linux
// has no WebGL (https://bugzilla.mozilla.org/show_bug.cgi?id=1375585), so the page could not
// draw; under Xvfb it draws with Mesa's llvmpipe, a software renderer like Chromium's SwiftShader,
// on one thread (LP_NUM_THREADS), so that the browser leaves a core to the processes under test.
'use strict';
const { spawn } = require('child_process');
const fs = require('fs');
const os = require('os');
const path = require('path');
const puppeteer = require('puppeteer-core');

const kWidth = 1280, kHeight = 800;

function browserKind() {
  const kind = process.env.SWEEPMAP_BROWSER || 'chromium';
  if (kind !== 'chromium' && kind !== 'firefox') {
    throw new Error(`SWEEPMAP_BROWSER=${kind}: expected chromium or firefox`);
  }
  return kind;
}

// An Xvfb server on the first free display (Xvfb picks it: -displayfd), resolved once it
// accepts clients: { display: ':N', stop() }.
function startXvfb() {
  return new Promise((resolve, reject) => {
    const x = spawn('/usr/bin/Xvfb', ['-displayfd', '3', '-screen', '0',
      `${kWidth + 320}x${kHeight + 320}x24`, '-nolisten', 'tcp'],
    { stdio: ['ignore', 'ignore', 'pipe', 'pipe'] });
    let said = '', number = '';
    x.stderr.on('data', (d) => { said += d; });
    x.stdio[3].on('data', (d) => {
      number += d;
      if (number.includes('\n')) {
        resolve({ display: `:${number.trim()}`, stop: () => x.kill('SIGTERM') });
      }
    });
    x.on('error', reject);
    x.on('exit', (code) => reject(new Error(`Xvfb ended (${code}) before it served: ${said}`)));
  });
}

async function launchChromium(profile) {
  return puppeteer.launch({
    executablePath: '/usr/bin/chromium',
    headless: true,
    userDataDir: profile,
    args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
      '--disable-background-networking', '--disable-component-update', '--disable-sync',
      '--use-gl=angle', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
      `--window-size=${kWidth},${kHeight}`],
  });
}

async function launchFirefox(profile, display) {
  return puppeteer.launch({
    browser: 'firefox',
    executablePath: '/usr/bin/firefox-esr',
    headless: false,
    userDataDir: profile,
    args: [`--width=${kWidth}`, `--height=${kHeight}`],
    env: { ...process.env, DISPLAY: display, MOZ_ENABLE_WAYLAND: '0', LP_NUM_THREADS: '1' },
    extraPrefsFirefox: {
      'webgl.force-enabled': true,  // llvmpipe is on Firefox's list of GL drivers it avoids
      'network.proxy.type': 0,
      'app.normandy.enabled': false,
      'messaging-system.rsexperimentloader.enabled': false,
      'services.settings.server': 'http://127.0.0.1:9/',  // no remote settings fetched
    },
  });
}

// The browser SWEEPMAP_BROWSER names, and close() that ends it and removes its profile.
async function launch() {
  const kind = browserKind();
  const profile = fs.mkdtempSync(path.join(os.tmpdir(), `sweepmap-${kind}-`));
  const xvfb = kind === 'firefox' ? await startXvfb() : null;
  let browser;
  try {
    browser = kind === 'firefox' ? await launchFirefox(profile, xvfb.display)
      : await launchChromium(profile);
  } catch (e) {
    if (xvfb) xvfb.stop();
    throw e;
  }
  const close = async () => {
    await browser.close();
    if (xvfb) xvfb.stop();
    fs.rmSync(profile, { recursive: true, force: true });
  };
  return { browser, close, kind };
}

// A page at `url` whose console errors and uncaught exceptions are collected in `errors`.
async function openPage(browser, url, errors) {
  const page = await browser.newPage();
  await page.setViewport({ width: kWidth, height: kHeight });
  page.on('console', (m) => { if (m.type() === 'error') errors.push(`console: ${m.text()}`); });
  page.on('pageerror', (e) => errors.push(`page: ${e.message}`));
  page.on('requestfailed', (r) => errors.push(`request failed: ${r.url()}`));
  await page.goto(url, { waitUntil: 'load' });
  await page.waitForFunction(() => window.sweepmapView && window.sweepmapView.connected,
    { timeout: 20000 });
  return page;
}

// The fraction of the canvas's pixels that differ from its background colour.
async function nonBlankFraction(page) {
  return page.evaluate(() => {
    const src = document.getElementById('scene');
    const c = document.createElement('canvas');
    c.width = src.width; c.height = src.height;
    const g = c.getContext('2d');
    g.drawImage(src, 0, 0);
    const d = g.getImageData(0, 0, c.width, c.height).data;
    let n = 0;
    for (let i = 0; i < d.length; i += 4) {
      if (Math.abs(d[i] - 17) + Math.abs(d[i + 1] - 17) + Math.abs(d[i + 2] - 17) > 30) n++;
    }
    return n / (d.length / 4);
  });
}

// Resolves when `fn` (run in the page) is true, or rejects with `what` after timeout_s.
async function until(page, fn, timeout_s, what, arg) {
  try {
    await page.waitForFunction(fn, { timeout: timeout_s * 1000, polling: 200 }, arg);
  } catch (e) {
    throw new Error(`${what}: not within ${timeout_s} s`);
  }
}

// The WebGL renderer the page's browser draws with (e.g. SwiftShader, llvmpipe), or 'unknown'.
async function webglRenderer(page) {
  return page.evaluate(() => {
    const gl = document.createElement('canvas').getContext('webgl');
    const ext = gl && gl.getExtension('WEBGL_debug_renderer_info');
    return ext ? gl.getParameter(ext.UNMASKED_RENDERER_WEBGL) : 'unknown';
  });
}

// The frame of every page script: opens `url` in the browser SWEEPMAP_BROWSER names and runs
// `body(page, out)`; whatever happens, closes the browser, prints `out` as one JSON object on
// stdout and sets the exit code to 1 if it failed. `out` starts as { errors, ...init }, `errors`
// collecting the page's console errors and uncaught exceptions; a failure (the page not loading,
// a wait running out) is out.failure, its message.
async function runPageScript(url, body, init = {}) {
  const out = { errors: [], ...init };
  const { browser, close } = await launch();
  try {
    await body(await openPage(browser, url, out.errors), out);
  } catch (e) {
    out.failure = e.message;
  } finally {
    await close();
  }
  process.stdout.write(JSON.stringify(out) + '\n');
  process.exitCode = out.failure ? 1 : 0;
}

module.exports = { launch, openPage, nonBlankFraction, until, webglRenderer, runPageScript };
