// Figures of `sweepmap view` in headless chromium (tools/bench/bench_view.sh):
//   node view_bench_page.js URL DONE_FILE SECONDS   beside a live run
//   node view_bench_page.js URL --log SECONDS       a log view, at the log's end
// Live, it connects before the run publishes and records the latency of every cloud chunk from
// the view's receipt (the assembler's publication at a sweep's end, on the same host) to the
// page's first frame that draws it, until DONE_FILE exists (the run has ended). A log view is
// paused and moved to the log's end. Then, once the server has sent everything, it fits the
// camera and counts the frames drawn in SECONDS. Prints one JSON object: points, sweeps and
// voxels on screen, what the view received, frames per second, latency quantiles, the renderer.
'use strict';
const { runPageScript, webglRenderer } = require('./browser.js');
const { fittedFrameRate, poll, untilAllSent, waitForFile } = require('./view_page.js');

function quantiles(values) {
  const v = values.slice().sort((a, b) => a - b);
  const q = (p) => (v.length ? +v[Math.min(v.length - 1, Math.floor(p * v.length))].toFixed(0) : null);
  return { chunks: v.length, median_ms: q(0.5), p90_ms: q(0.9), max_ms: q(1) };
}

const [url, doneFile, secondsArg] = process.argv.slice(2);
runPageScript(url, async (page, out) => {
  const log = doneFile === '--log';
  if (log) {
    await poll(page, () => !!window.sweepmapView.time, null, 30, 'the log\'s time');
    await page.evaluate(() => {
      window.sweepmapView.pause();
      window.sweepmapView.seek(window.sweepmapView.time.end);
    });
  } else {
    await waitForFile(doneFile, 900);
  }
  await untilAllSent(page, 600, 'everything sent', { logEnd: log });
  out.fps = +(await fittedFrameRate(page, Number(secondsArg))).toFixed(2);
  Object.assign(out, await page.evaluate(() => {
    const v = window.sweepmapView;
    return { points: v.pointsDrawn(), sent: v.status.you.points, sweeps: v.sweeps(),
      voxels: v.voxels(), mb_sent: +(v.status.you.bytes_sent / 1e6).toFixed(1),
      received: v.status.board.view_model,
      dropped: v.status.you.frames_dropped, latencies: v.latenciesMs };
  }));
  out.latency = quantiles(out.latencies);
  delete out.latencies;
  out.renderer = await webglRenderer(page);
});
