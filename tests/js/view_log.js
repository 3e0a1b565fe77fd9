// Log view check (run by tests/e2e/test_view.cpp): node view_log.js URL UTIME...
// Loads the page of `sweepmap view LOG`, pauses the playback, and for each UTIME moves the time
// slider there (as a person drags it: its value, then a change event), waits until the server
// has played to that time and sent everything, and records what the page draws. Prints one JSON
// object: console errors and, per seek, the time reached, the sweeps and points drawn, the
// points the server says it sent, and the voxels drawn and their source.
'use strict';
const { runPageScript, until } = require('./browser.js');

// Only status frames the page gets after the time frame at UTIME count: one from before (its
// counters taken before the server played back to UTIME, e.g. before a seek back's reset) can
// repeat the previous seek's figures and look quiet.
async function seek(page, utime) {
  await page.evaluate((u) => {
    window.__lastSent = undefined;
    const t = window.sweepmapView.time;
    const slider = document.getElementById('time');
    slider.value = String(Math.round(1000 * (u - t.start) / Math.max(1, t.end - t.start)));
    slider.dispatchEvent(new Event('change'));
  }, utime);
  await until(page, (u) => {
    const v = window.sweepmapView, t = v.time, s = v.status;
    if (!t || t.playing || Math.abs(t.utime - u) > (t.end - t.start) / 1000 || !s) {
      window.__lastSent = undefined;
      return false;
    }
    if (s.you.queued_frames !== 0) return false;
    if (window.__lastSeq === v.statusSeq) return false;  // the same status frame
    window.__lastSeq = v.statusSeq;
    const sent = `${s.you.points} ${s.board.view_model.chunks}`;
    const quiet = window.__lastSent === sent;
    window.__lastSent = sent;
    return quiet;
  }, 30, `the view at ${utime}`, utime);
  return page.evaluate(() => {
    const v = window.sweepmapView;
    return { utime: v.time.utime, sweeps: v.sweeps(), points_drawn: v.pointsDrawn(),
      check: v.lastCheck, voxels: v.voxels(), voxel_source: v.voxelSource() };
  });
}

const [url, ...utimes] = process.argv.slice(2);
runPageScript(url, async (page, out) => {
  await until(page, () => window.sweepmapView.time, 10, 'the log\'s time');
  out.mode = await page.evaluate(() => window.sweepmapView.mode);
  await page.evaluate(() => window.sweepmapView.pause());
  for (const u of utimes) out.seeks.push(await seek(page, Number(u)));
}, { seeks: [] });
