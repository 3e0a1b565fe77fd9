#!/usr/bin/env bash
# Figures of `sweepmap view` (issue 24; docs/how-to/view.md): `make bench-view`.
#   tools/bench/bench_view.sh BIN_DIR [WORK_DIR] [SWEEPS]
# 1. Live: `sweepmap demo` runs rig A's processes in its private network namespace for SWEEPS
#    (3) mode-7 sweeps (about 680 k points each); a `sweepmap view` in that namespace serves
#    them to headless Debian chromium (tests/js/view_bench_page.js), connected from the start.
#    Prints what the view received of the SWEEP_CLOUD chunks the recorder logged, and the
#    latency from a sweep's end (its chunks reaching the view as the assembler publishes them)
#    to the page's first frame that draws them: median, 90 %, max over every chunk.
# 2. The recorded log: `sweepmap view LOG --point-budget 2100000` at the log's end holds every
#    point of the sweeps (about 2.05 M; the default budget, 2 M, would halve the oldest sweep)
#    (tests/js/view_bench_page.js --log): the frame rate with all of them (10 s, camera
#    fitted); then the server's CPU per connected client (tests/js/view_clients.js, 4
#    WebSocket readers): CPU-seconds to send one client the whole state, and the share of a
#    core each costs while connected (status frames, 10 s).
# Needs root (the namespace), node with tests/js/node_modules and chromium (tools/ops/setup.sh).
# Prints figures, asserts nothing; run on an idle machine (chromium draws with SwiftShader,
# a software renderer, so the frame rate is the CPU's).
set -euo pipefail
bin=$(cd "$1" && pwd)
root=$(cd "$(dirname "$0")/../.." && pwd)
work=$(realpath -m "${2:-build/bench/view}")
sweeps=${3:-3}
js="$root/tests/js"
if ! command -v node >/dev/null || [ ! -x /usr/bin/chromium ] || [ ! -d "$js/node_modules/puppeteer-core" ]; then
  echo "bench_view: needs node, /usr/bin/chromium and tests/js/node_modules (tools/ops/setup.sh)" >&2
  exit 2
fi
rm -rf "$work" && mkdir -p "$work"
url='udpm://239.255.76.67:7667?ttl=0&recv_buf_size=2097152'
pids=()
stop_all() {
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
}
trap stop_all EXIT
# stop PID: ends a process this script started, and waits for it.
stop() {
  kill "$1" 2>/dev/null || true
  wait "$1" 2>/dev/null || true
}

# 1. Live.
"$bin/sweepmap" demo --rig rig_a --mode 7 --sweeps "$sweeps" --out "$work/demo" >"$work/demo.txt" 2>&1 &
demo=$!
pids+=("$demo")
mine=$(readlink /proc/self/ns/net)
for _ in $(seq 100); do
  [ "$(readlink "/proc/$demo/ns/net" 2>/dev/null)" != "$mine" ] && break
  sleep 0.05
done
ns="/proc/$demo/ns/net"
nsenter --net="$ns" "$bin/sweepmap" view --rig rig_a --lcm-url "$url" --port 8080 >"$work/view_live.txt" 2>&1 &
view=$!
pids+=("$view")
nsenter --net="$ns" node "$js/view_bench_page.js" http://127.0.0.1:8080/ "$work/done" 2 \
  >"$work/live.json" 2>"$work/live.txt" &
page=$!
pids+=("$page")
wait "$demo" || echo "bench_view: the demo failed (see $work/demo.txt)" >&2
touch "$work/done"
wait "$page" || true
stop "$view"
# The SWEEP_CLOUD chunks and points the recorder logged: what the view could have received.
logged=$("$bin/sweepmap" dump "$work/demo/demo.lcmlog" --channel SWEEP_CLOUD 2>/dev/null |
  awk '/^  npoints = /{n += $3; k++} END{print k + 0, n + 0}')

# 2. The recorded log, in a namespace of its own (port 8080 free).
# shellcheck disable=SC2016  # expanded by the inner bash, from its arguments
unshare --net bash -c '
  ip link set lo up
  "$1/sweepmap" view "$2/demo/demo.lcmlog" --rig rig_a --port 8080 --point-budget 2100000 \
    >"$2/view_log.txt" 2>&1 &
  view=$!
  for _ in $(seq 100); do (exec 3<>/dev/tcp/127.0.0.1/8080) 2>/dev/null && break; sleep 0.1; done
  node "$3/view_bench_page.js" http://127.0.0.1:8080/ --log 10 >"$2/log.json" 2>"$2/log.txt" || true
  node "$3/view_clients.js" ws://127.0.0.1:8080/ws 4 10 "$view" >"$2/clients.json" 2>&1 || true
  kill "$view"; wait "$view" 2>/dev/null || true
' bench_view "$bin" "$work" "$js"

python3 - "$work" "$sweeps" "$logged" <<'PY'
import json, sys
work, sweeps = sys.argv[1:3]
logged, logged_points = sys.argv[3].split()
def last(name):
    lines = open(f"{work}/{name}").read().strip().splitlines()
    return json.loads(lines[-1]) if lines else {"failure": f"{name} is empty"}
live, log, clients = last("live.json"), last("log.json"), last("clients.json")
for what, r in (("live page", live), ("log page", log), ("clients", clients)):
    if "failure" in r:
        sys.exit(f"bench_view: {what}: {r['failure']} (see {work})")
l = live["latency"]
# What the view itself took in, from the counters it prints when stopped (the page's last
# status frame can be a backlog behind: the page drew more points than that status said).
stopped = [x for x in open(f"{work}/view_live.txt") if x.startswith("sweepmap view: stopped: ")]
if not stopped:
    sys.exit(f"bench_view: the live view printed no counters when stopped (see {work})")
got = json.loads(stopped[-1].split("stopped: ", 1)[1])
print(f"view, rig A, {sweeps} mode-7 sweeps, headless chromium ({log['renderer']}):")
print(f"  live: the view received {got['chunks']} of the {logged} SWEEP_CLOUD chunks the recorder "
      f"logged ({got['points_received']} of {logged_points} points; {got['receive_dropped']} "
      f"dropped by its receive queue, {got['receive_queue_peak_mb']:.1f} MB at its peak); the "
      f"page drew {live['points']} points, console errors: {len(live['errors'])}")
print(f"  latency, sweep end (chunk at the view) -> drawn, {l['chunks']} chunks: median "
      f"{l['median_ms']} ms, 90 % {l['p90_ms']} ms, max {l['max_ms']} ms")
print(f"  log, at its end: {log['points']} points on screen, {log['sweeps']} sweeps, "
      f"{log['voxels']} voxels: {log['fps']:.2f} frames/s")
print(f"  server CPU, {clients['clients']} more clients: "
      f"{clients['cpu_s_per_client_to_catch_up']:.3f} CPU-s per client to send the whole state "
      f"({clients['mb_per_client'][0]} MB, {clients['points_per_client'][0]} points; all caught up in "
      f"{clients['caught_up_s']:.1f} s), then {100 * clients['cpu_share_per_client_connected']:.2f} % "
      f"of a core per client connected")
PY
