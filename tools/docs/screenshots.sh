#!/usr/bin/env bash
# Redraws the docs' pictures of each rig kind (A, B, C): the live view and the report's 3D
# rendering. Run by a person after a change to the view or the renderings; not run in CI
# (about 4 minutes, root for the private network namespaces, headless chromium).
#   tools/docs/screenshots.sh BIN_DIR [OUT_DIR [RIG...]]   (docs/images; rig_a rig_b rig_c)
# For each rig, `sweepmap demo` runs the rig's processes in its private network namespace; a
# `sweepmap view` started inside that namespace (nsenter) serves the live run to headless
# chromium (tools/docs/view_screenshot.js), which saves the page during the run, while every
# process is up: rig A once the first of its 2 mode-3 sweeps is drawn and mapped, rig B 42 s
# into its 60 s drive, rig C 10 s in (2 of its 3 plate sweeps); the ceiling of the rooms is
# clipped away. OUT_DIR/view_rig_X.png. The demo's replay then draws cloud_3d.png, scaled down
# to OUT_DIR/report_3d_rig_X.png (tools/docs/shrink_png.js). The simulations are seeded, so
# the clouds are the same each run; a live run's timing (which scans a sweep gets, where
# rig B's car is after 42 s) can move a few points.
# Needs root (nsenter), node with tests/js/node_modules and chromium (tools/ops/setup.sh).
set -euo pipefail
bin=$(cd "$1" && pwd)
root=$(cd "$(dirname "$0")/../.." && pwd)
out=$(realpath -m "${2:-$root/docs/images}")
rigs=("${@:3}")
[ ${#rigs[@]} -gt 0 ] || rigs=(rig_a rig_b rig_c)
mkdir -p "$out"
work=$(mktemp -d)
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
  rm -rf "$work"
}
trap cleanup EXIT
url='udpm://239.255.76.67:7667?ttl=0&recv_buf_size=2097152'

# The network namespace of process $1 once it has left ours (the demo enters its own first).
wait_for_namespace() {
  local mine
  mine=$(readlink /proc/self/ns/net)
  for _ in $(seq 100); do
    if [ "$(readlink "/proc/$1/ns/net" 2>/dev/null)" != "$mine" ]; then return 0; fi
    sleep 0.05
  done
  echo "screenshots: the demo (pid $1) never entered its own network namespace" >&2
  return 1
}

# shot RIG WHEN CLIP_MAX_M DEMO_ARGS...: the live view of a demo of RIG at WHEN
# (view_screenshot.js), and its replay's 3D rendering.
shot() {
  local rig=$1 when=$2 clip=$3
  shift 3
  local dir="$work/$rig"
  mkdir -p "$dir"
  "$bin/sweepmap" demo --rig "$rig" --out "$dir/demo" "$@" >"$dir/demo.txt" 2>&1 &
  local demo=$!
  pids+=("$demo")
  wait_for_namespace "$demo"
  local ns="/proc/$demo/ns/net"
  nsenter --net="$ns" "$bin/sweepmap" view --rig "$rig" --lcm-url "$url" --port 8080 \
    >"$dir/view.txt" 2>&1 &
  local view=$!
  pids+=("$view")
  local rc=0
  nsenter --net="$ns" node "$root/tools/docs/view_screenshot.js" http://127.0.0.1:8080/ \
    "$when" "$out/view_$rig.png" "$clip" >"$dir/page.json" 2>"$dir/page.txt" || rc=$?
  echo "$rig live view: $(cat "$dir/page.json")"
  kill "$view" 2>/dev/null || true
  wait "$view" 2>/dev/null || true
  wait "$demo" || { echo "screenshots: demo of $rig failed:" >&2; tail "$dir/demo.txt" >&2; return 1; }
  [ "$rc" -eq 0 ] || { cat "$dir/page.txt" "$dir/view.txt" >&2; return 1; }
  node "$root/tools/docs/shrink_png.js" "$dir/demo/cloud_3d.png" "$out/report_3d_$rig.png" 600
}

for rig in "${rigs[@]}"; do
  case "$rig" in
    rig_a) shot rig_a sweeps=1 1.5 --mode 3 --sweeps 2 ;;
    rig_b) shot rig_b seconds=42 2.3 ;;
    rig_c) shot rig_c seconds=10 "" ;;
    *) echo "screenshots: no picture plan for '$rig' (rig_a, rig_b or rig_c)" >&2 && exit 2 ;;
  esac
  ls -l "$out/view_$rig.png" "$out/report_3d_$rig.png"
done
