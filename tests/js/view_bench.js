// Figures of `sweepmap view` in a browser (docs/how-to/view.md; SWEEPMAP_BROWSER: browser.js): node view_bench.js URL
// SECONDS [SCREENSHOT.png]. For a log view: pauses, moves to the log's end, waits until every
// point is drawn, then counts the frames drawn in SECONDS. Prints one JSON object: points and
// voxels drawn, frames per second, the page's WebGL renderer; a half-size screenshot if asked.
'use strict';
const { runPageScript, until, webglRenderer } = require('./browser.js');
const { fittedFrameRate, untilAllSent } = require('./view_page.js');

const [url, secondsArg, screenshot] = process.argv.slice(2);
runPageScript(url, async (page, out) => {
  await until(page, () => window.sweepmapView.time, 10, 'the log\'s time');
  await page.evaluate(() => { window.sweepmapView.pause(); window.sweepmapView.seek(window.sweepmapView.time.end); });
  await untilAllSent(page, 300, 'the whole log drawn', { logEnd: true });
  out.fps = await fittedFrameRate(page, Number(secondsArg));
  Object.assign(out, await page.evaluate(() => ({ points: window.sweepmapView.pointsDrawn(),
    voxels: window.sweepmapView.voxels(), sweeps: window.sweepmapView.sweeps() })));
  out.renderer = await webglRenderer(page);
  if (screenshot) {  // half size, for the docs
    await page.setViewport({ width: 1280, height: 800, deviceScaleFactor: 0.5 });
    const f = await page.evaluate(() => window.sweepmapView.frames);
    await page.waitForFunction((n) => window.sweepmapView.frames > n + 2, { timeout: 60000 }, f);
    await page.screenshot({ path: screenshot });
  }
});
