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
const { launch, openPage, until } = require(path.join(__dirname, '../../tests/js/browser.js'));

async function waitFor(page, when) {
  const [what, value] = when.split('=');
  const n = Number(value);
  if (what === 'seconds') return new Promise((r) => setTimeout(r, n * 1000));
  if (what !== 'sweeps') throw new Error(`WHEN: '${when}' is neither sweeps=N nor seconds=S`);
  return until(page, (k) => {
    const v = window.sweepmapView, s = v.status;
    if (!s || v.sweeps() < k || !s.board || !s.board.mapper || s.board.mapper.sweeps < k) return false;
    if (s.you.queued_frames !== 0 || window.__lastSeq === v.statusSeq) return false;
    window.__lastSeq = v.statusSeq;
    const sent = `${s.you.points} ${s.board.view_model.chunks}`;
    const quiet = window.__lastSent === sent;
    window.__lastSent = sent;
    return quiet;
  }, 600, `${n} sweeps drawn and mapped`, n);
}

async function main() {
  const [url, when, out, clipMax] = process.argv.slice(2);
  const errors = [];
  const { browser, close } = await launch();
  const result = { errors };
  try {
    const page = await openPage(browser, url, errors);
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
    await page.screenshot({ path: out });
    Object.assign(result, await page.evaluate(() => {
      const v = window.sweepmapView, procs = (v.status.board && v.status.board.processes) || {};
      return { points: v.pointsDrawn(), sweeps: v.sweeps(), voxels: v.voxels(),
        processes: Object.fromEntries(Object.entries(procs).map(([k, p]) => [k, p.status])) };
    }));
  } catch (e) {
    result.failure = e.message;
  } finally {
    await close();
  }
  process.stdout.write(JSON.stringify(result) + '\n');
  process.exitCode = result.failure ? 1 : 0;
}
main();
