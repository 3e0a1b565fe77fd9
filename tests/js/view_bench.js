// Figures of `sweepmap view` in a browser (docs/how-to/view.md; SWEEPMAP_BROWSER: browser.js): node view_bench.js URL
// SECONDS [SCREENSHOT.png]. For a log view: pauses, moves to the log's end, waits until every
// point is drawn, then counts the frames drawn in SECONDS. Prints one JSON object: points and
// voxels drawn, frames per second, the page's WebGL renderer; a half-size screenshot if asked.
'use strict';
const { launch, openPage, until } = require('./browser.js');

async function main() {
  const [url, secondsArg, screenshot] = process.argv.slice(2);
  const errors = [];
  const { browser, close } = await launch();
  const out = { errors };
  try {
    const page = await openPage(browser, url, errors);
    await until(page, () => window.sweepmapView.time, 10, 'the log\'s time');
    await page.evaluate(() => { window.sweepmapView.pause(); window.sweepmapView.seek(window.sweepmapView.time.end); });
    await until(page, () => {
      const v = window.sweepmapView, s = v.status;
      if (!s || s.you.queued_frames !== 0 || window.__lastSeq === v.statusSeq) return false;
      window.__lastSeq = v.statusSeq;
      const sent = `${s.you.points} ${s.board.view_model.chunks}`;
      const quiet = window.__lastSent === sent && v.time.utime === v.time.end;
      window.__lastSent = sent;
      return quiet;
    }, 300, 'the whole log drawn');
    await page.evaluate(() => window.sweepmapView.setCamera('fit'));
    const f0 = await page.evaluate(() => window.sweepmapView.frames);
    const t0 = Date.now();
    await new Promise((r) => setTimeout(r, Number(secondsArg) * 1000));
    const f1 = await page.evaluate(() => window.sweepmapView.frames);
    out.fps = (f1 - f0) / ((Date.now() - t0) / 1000);
    Object.assign(out, await page.evaluate(() => ({ points: window.sweepmapView.pointsDrawn(),
      voxels: window.sweepmapView.voxels(), sweeps: window.sweepmapView.sweeps() })));
    out.renderer = await page.evaluate(() => {
      const gl = document.createElement('canvas').getContext('webgl');
      const ext = gl && gl.getExtension('WEBGL_debug_renderer_info');
      return ext ? gl.getParameter(ext.UNMASKED_RENDERER_WEBGL) : 'unknown';
    });
    if (screenshot) {  // half size, for the docs
      await page.setViewport({ width: 1280, height: 800, deviceScaleFactor: 0.5 });
      const f = await page.evaluate(() => window.sweepmapView.frames);
      await page.waitForFunction((n) => window.sweepmapView.frames > n + 2, { timeout: 60000 }, f);
      await page.screenshot({ path: screenshot });
    }
  } catch (e) {
    out.failure = e.message;
  } finally {
    await close();
  }
  process.stdout.write(JSON.stringify(out) + '\n');
}
main();
