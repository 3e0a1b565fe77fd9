// Waits shared by the view's page scripts (view_bench_live.js, tools/docs/view_screenshot.js).
'use strict';
const fs = require('fs');
const { until } = require('./browser.js');

// Resolves once the server has sent the page everything it holds: its queue for the page empty
// and no cloud point sent between two status frames; with `sweeps` > 0, also once the page has
// drawn that many sweeps and the mapper has inserted them.
function untilAllSent(page, timeoutS, what, sweeps = 0) {
  return until(page, (k) => {
    const v = window.sweepmapView, s = v.status;
    if (!s || s.you.queued_frames !== 0 || window.__lastSeq === v.statusSeq) return false;
    if (k > 0 && (v.sweeps() < k || !s.board || !s.board.mapper || s.board.mapper.sweeps < k)) {
      return false;
    }
    window.__lastSeq = v.statusSeq;
    const sent = `${s.you.points} ${s.board.view_model.chunks}`;
    const quiet = window.__lastSent === sent;
    window.__lastSent = sent;
    return quiet;
  }, timeoutS, what, sweeps);
}

// Resolves once `file` exists (another process's signal), or rejects after timeoutS.
async function waitForFile(file, timeoutS) {
  for (let t = 0; t < timeoutS * 5 && !fs.existsSync(file); t++) {
    await new Promise((r) => setTimeout(r, 200));
  }
  if (!fs.existsSync(file)) throw new Error(`${file}: not there within ${timeoutS} s`);
}

module.exports = { untilAllSent, waitForFile };
