// A screenshot of `sweepmap view`'s page during a live run, for the docs (tools/docs/screenshots.sh):
//   node view_screenshot.js URL WHEN OUT.png [CLIP_MAX_M]
// Opens the page in headless Debian chromium (tests/js/browser.js) before the run publishes,
// then waits for WHEN, a moment while the processes still run:
//   sweeps=N    the page has drawn N sweeps, the mapper has inserted them and the server has
//               sent everything (no cloud point sent between two status frames);
//   seconds=S   S seconds after the page connected.
// Then it clips the cloud above CLIP_MAX_M (a room's ceiling, which hides the room from above),
// fits the camera and saves a 768x480 screenshot. Prints one JSON object: what the page shows.
'use strict';
const path = require('path');
const js = path.join(__dirname, '../../tests/js');
const { runPageScript } = require(path.join(js, 'browser.js'));
const { untilAllSent } = require(path.join(js, 'view_page.js'));

async function waitFor(page, when) {
  const [what, value] = when.split('=');
  const n = Number(value);
  if (what === 'seconds') return new Promise((r) => setTimeout(r, n * 1000));
  if (what !== 'sweeps') throw new Error(`WHEN: '${when}' is neither sweeps=N nor seconds=S`);
  return untilAllSent(page, 600, `${n} sweeps drawn and mapped`, { sweeps: n });
}

const [url, when, png, clipMax] = process.argv.slice(2);
runPageScript(url, async (page, out) => {
  await waitFor(page, when);
  await page.setViewport({ width: 1280, height: 800, deviceScaleFactor: 0.6 });
  await page.evaluate((clip) => {
    if (clip) {
      const input = document.getElementById('clip-max');
      input.value = clip;
      input.dispatchEvent(new Event('input'));
    }
    window.sweepmapView.setCamera('fit');
  }, clipMax || '');
  const f = await page.evaluate(() => window.sweepmapView.frames);
  await page.waitForFunction((n) => window.sweepmapView.frames > n + 2, { timeout: 60000 }, f);
  await page.screenshot({ path: png });
  Object.assign(out, await page.evaluate(() => {
    const v = window.sweepmapView, procs = (v.status.board && v.status.board.processes) || {};
    return { points: v.pointsDrawn(), sweeps: v.sweeps(), voxels: v.voxels(),
      processes: Object.fromEntries(Object.entries(procs).map(([k, p]) => [k, p.status])) };
  }));
});
