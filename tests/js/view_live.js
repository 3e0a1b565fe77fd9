// Live view check (run by tests/e2e/test_view.cpp inside the live run's network namespace):
// node view_live.js URL SWEEPS TIMEOUT_S SCREENSHOT.png
// Loads the page (says "page connected" once it is: the test starts the sweeps then), waits
// until it has drawn SWEEPS sweeps, the mapper has inserted them and the server has sent
// everything (its queue empty, no cloud sent between two status frames), then
// prints one JSON object of what the page shows: console errors, the points drawn against the
// points the server says it sent, the extent of the drawn points, the voxels, the non-blank
// fraction of the canvas, the server's status, and the colours of a sample of points by
// intensity and by height. The C++ test judges it.
'use strict';
const { nonBlankFraction, runPageScript } = require('./browser.js');
const { untilAllSent } = require('./view_page.js');

// What the page shows once SWEEPS sweeps are drawn and sent: see the top of the file.
async function check(page, out, sweeps, timeoutS, screenshot) {
  await untilAllSent(page, timeoutS, `${sweeps} sweeps drawn and the server quiet`, { sweeps });
  await page.evaluate(() => window.sweepmapView.setCamera('fit'));
  await page.waitForFunction((f) => window.sweepmapView.frames > f + 3, {},
    await page.evaluate(() => window.sweepmapView.frames));
  Object.assign(out, await page.evaluate(() => {
    const v = window.sweepmapView;
    return { check: v.lastCheck, points_drawn: v.pointsDrawn(), sweeps: v.sweeps(),
      voxels: v.voxels(), voxel_source: v.voxelSource(), extent: v.extent(0.01), status: v.status,
      mode: v.mode, latencies_ms: v.latenciesMs };
  }));
  out.non_blank = await nonBlankFraction(page);
  if (screenshot) await page.screenshot({ path: screenshot });
  // The colour selector: intensity offered (rig A's lidar measures it), then each mode's
  // colours for a sample of points (the C++ test checks the hue follows that mode's value).
  out.colour = await page.evaluate(() => {
    const v = window.sweepmapView;
    const r = { available: v.intensityAvailable, initial: v.colour };
    r.intensity_set = v.setColour('intensity');
    r.intensity = v.colourSample(100).map((p) => [p.intensity, p.hue]);
    r.height_set = v.setColour('height');
    r.height = v.colourSample(100).map((p) => [p.z, p.hue]);
    return r;
  });
}

const [url, sweepsArg, timeoutArg, screenshot] = process.argv.slice(2);
runPageScript(url, async (page, out) => {
  out.connected = true;
  process.stdout.write('page connected\n');
  try {
    await check(page, out, Number(sweepsArg), Number(timeoutArg), screenshot);
  } catch (e) {
    out.at_failure = await page.evaluate(() => ({ sweeps: window.sweepmapView.sweeps(),
      status: window.sweepmapView.status })).catch(() => null);
    throw e;
  }
});
