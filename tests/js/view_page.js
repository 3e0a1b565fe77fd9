// Waits shared by the view's page scripts (view_live.js, view_bench.js, view_bench_page.js,
// tools/docs/view_screenshot.js).
// They poll from node with short calls: a page drawing 2 M points in software takes seconds a
// frame, and one long wait inside the page would outlive puppeteer's protocol timeout.
'use strict';
const fs = require('fs');

const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

// Resolves once `fn(arg)`, run in the page, is true; rejects with `what` after timeoutS.
async function poll(page, fn, arg, timeoutS, what) {
  const end = Date.now() + timeoutS * 1000;
  while (Date.now() < end) {
    if (await page.evaluate(fn, arg)) return;
    await sleep(300);
  }
  throw new Error(`${what}: not within ${timeoutS} s`);
}

// Resolves once the server has sent the page everything it holds: its queue for the page empty
// and no cloud point sent between two status frames; with `o.sweeps`, also once the page has
// drawn that many sweeps and the mapper has inserted them; with `o.logEnd`, once the log's
// time is at its end.
function untilAllSent(page, timeoutS, what, o = {}) {
  return poll(page, (opt) => {
    const v = window.sweepmapView, s = v.status;
    if (!s || s.you.queued_frames !== 0 || window.__lastSeq === v.statusSeq) return false;
    if (opt.sweeps && (v.sweeps() < opt.sweeps || !s.board || !s.board.mapper ||
        s.board.mapper.sweeps < opt.sweeps)) return false;
    window.__lastSeq = v.statusSeq;
    const sent = `${s.you.points} ${s.board.view_model.chunks}`;
    const quiet = window.__lastSent === sent && (!opt.logEnd || v.time.utime === v.time.end);
    window.__lastSent = sent;
    return quiet;
  }, o, timeoutS, what);
}

// Resolves once `file` exists (another process's signal), or rejects after timeoutS.
async function waitForFile(file, timeoutS) {
  for (let t = 0; t < timeoutS * 5 && !fs.existsSync(file); t++) await sleep(200);
  if (!fs.existsSync(file)) throw new Error(`${file}: not there within ${timeoutS} s`);
}

// The frames per second the page draws over `seconds`, its camera fitted to the cloud first.
async function fittedFrameRate(page, seconds) {
  await page.evaluate(() => window.sweepmapView.setCamera('fit'));
  const f0 = await page.evaluate(() => window.sweepmapView.frames);
  const t0 = Date.now();
  await sleep(seconds * 1000);
  const f1 = await page.evaluate(() => window.sweepmapView.frames);
  return (f1 - f0) / ((Date.now() - t0) / 1000);
}

module.exports = { fittedFrameRate, poll, sleep, untilAllSent, waitForFile };
