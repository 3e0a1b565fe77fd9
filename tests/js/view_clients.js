// The view server's CPU per connected client (tools/bench/bench_view.sh):
//   node view_clients.js WS_URL CLIENTS HOLD_S VIEW_PID
// Connects CLIENTS WebSocket readers to the view's /ws (as pages do, without drawing), waits
// until each has everything the server holds (a status frame with an empty queue and the same
// points as the one before), then keeps them connected HOLD_S seconds. The server's CPU time
// (utime + stime of /proc/VIEW_PID/stat) is read before, when all have caught up, and after
// the hold. Prints one JSON object.
'use strict';
const fs = require('fs');
const WebSocket = require('ws');

const ticksPerS = 100;  // USER_HZ: the unit of /proc/PID/stat's times on Linux
function cpuS(pid) {
  const stat = fs.readFileSync(`/proc/${pid}/stat`, 'utf8');
  const f = stat.slice(stat.lastIndexOf(')') + 2).split(' ');
  return (Number(f[11]) + Number(f[12])) / ticksPerS;  // fields 14 and 15 (utime, stime)
}

function reader(url) {
  return new Promise((resolve, reject) => {
    const ws = new WebSocket(url);
    const got = { ws, bytes: 0, points: -1, caught_up: false };
    ws.on('message', (data, binary) => {
      got.bytes += data.length;
      if (binary) return;
      const msg = JSON.parse(data.toString());
      if (msg.type !== 'status') return;
      if (msg.you.queued_frames === 0 && msg.you.points === got.points && !got.caught_up) {
        got.caught_up = true;
        resolve(got);
      }
      got.points = msg.you.points;
    });
    ws.on('error', reject);
  });
}

async function main() {
  const [url, clientsArg, holdArg, pid] = process.argv.slice(2);
  const n = Number(clientsArg);
  const out = { clients: n };
  const cpu0 = cpuS(pid), t0 = Date.now();
  const readers = await Promise.all(Array.from({ length: n }, () => reader(url)));
  const cpu1 = cpuS(pid), t1 = Date.now();
  out.caught_up_s = (t1 - t0) / 1000;
  out.cpu_s_to_catch_up = cpu1 - cpu0;
  out.cpu_s_per_client_to_catch_up = (cpu1 - cpu0) / n;
  out.mb_per_client = readers.map((r) => +(r.bytes / 1e6).toFixed(1));
  out.points_per_client = readers.map((r) => r.points);
  await new Promise((r) => setTimeout(r, Number(holdArg) * 1000));
  const cpu2 = cpuS(pid);
  out.hold_s = (Date.now() - t1) / 1000;
  out.cpu_share_per_client_connected = (cpu2 - cpu1) / out.hold_s / n;
  for (const r of readers) r.ws.close();
  process.stdout.write(JSON.stringify(out) + '\n');
}
main().catch((e) => { process.stdout.write(JSON.stringify({ failure: e.message }) + '\n'); process.exit(1); });
