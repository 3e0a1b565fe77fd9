// Headless Debian chromium driven by puppeteer-core, as every browser test here starts it: a new
// empty profile, no network besides the page's own host, nothing fetched by chromium itself.
'use strict';
const fs = require('fs');
const os = require('os');
const path = require('path');
const puppeteer = require('puppeteer-core');

async function launch() {
  const profile = fs.mkdtempSync(path.join(os.tmpdir(), 'sweepmap-chromium-'));
  const browser = await puppeteer.launch({
    executablePath: '/usr/bin/chromium',
    headless: true,
    userDataDir: profile,
    args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
      '--disable-background-networking', '--disable-component-update', '--disable-sync',
      '--use-gl=angle', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
      '--window-size=1280,800'],
  });
  const close = async () => {
    await browser.close();
    fs.rmSync(profile, { recursive: true, force: true });
  };
  return { browser, close };
}

// A page at `url` whose console errors and uncaught exceptions are collected in `errors`.
async function openPage(browser, url, errors) {
  const page = await browser.newPage();
  await page.setViewport({ width: 1280, height: 800 });
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

module.exports = { launch, openPage, nonBlankFraction, until };
