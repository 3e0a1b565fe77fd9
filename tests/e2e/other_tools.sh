#!/bin/bash
# Other programs open our PLYs (issue 24): for each rig kind, a simulated log's replay, then
#   CloudCompare (Debian 12: 2.11) in its command-line mode (-SILENT: it fails rather than ask,
#     so no dialog was needed) loads the PLY and saves it as ASCII: every point, the same
#     bounding box;
#   pcl_viewer: Debian's PCL 1.13 viewer opens .pcd and .vtk only, so PCL's own PLY reader
#     (pcl_ply2pcd) reads the PLY and pcl_viewer shows the result under Xvfb; both must report
#     every point. The viewer has no batch mode: it is stopped by timeout after it has loaded.
# Usage: other_tools.sh BIN_DIR SCRATCH_DIR
# Exit 77 (skipped) without CloudCompare, pcl_viewer or xvfb-run (tools/ops/setup.sh installs
# them), naming what is missing.
set -euo pipefail
# Inside xvfb-run: pcl_viewer PCD LOG, stopped once it has loaded (it has no batch mode).
if [ "${1:-}" = --watch-viewer ]; then
  stdbuf -oL pcl_viewer "$2" >"$3" 2>&1 &
  viewer=$!
  for _ in $(seq 400); do
    grep -q "\[done, " "$3" && break
    kill -0 $viewer 2>/dev/null || break
    sleep 0.1
  done
  kill $viewer 2>/dev/null || true
  wait $viewer 2>/dev/null || true
  exit 0
fi
bin=$1
dir=$2
here=$(cd "$(dirname "$0")" && pwd)
missing=()
for tool in CloudCompare pcl_viewer pcl_ply2pcd xvfb-run python3; do
  command -v "$tool" >/dev/null || missing+=("$tool")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "skipped: ${missing[*]} missing (tools/ops/setup.sh installs cloudcompare, pcl-tools, xvfb)"
  exit 77
fi
rm -rf "$dir" && mkdir -p "$dir" && cd "$dir"
sweepmap="$bin/sweepmap"
stats="$here/ply_stats.py"

"$sweepmap" sim --rig rig_a --mode 1 --sweeps 1 --out a.lcmlog
"$sweepmap" sim --rig rig_b --out b.lcmlog
"$sweepmap" sim --rig rig_c --out c.lcmlog
for r in a b c; do
  "$sweepmap" replay $r.lcmlog --rig rig_$r --out replay_$r --quiet --no-plots
done
plys=(replay_a/sweeps/sweep_000000.ply replay_b/cloud.ply replay_c/cloud.ply)

failed=0
fail() {
  echo "FAILED: $*"
  failed=1
}

# CloudCompare: loads without a dialog, saves what it loaded as x y z text.
cloudcompare() {
  local ply=$1 asc=$2 log=$3
  # -SILENT: no GUI, and an open that would need a dialog fails instead; -AUTO_SAVE OFF: only
  # the explicit -SAVE_CLOUDS writes; -NO_TIMESTAMP: the file is named as asked.
  local rc=0
  timeout 50 xvfb-run -a CloudCompare -SILENT -AUTO_SAVE OFF -NO_TIMESTAMP -O "$ply" \
    -C_EXPORT_FMT ASC -PREC 8 -SAVE_CLOUDS FILE "$asc" >"$log" 2>&1 || rc=$?
  if [ "$rc" -ne 0 ]; then
    fail "CloudCompare exited $rc on $ply (log: $dir/$log)"
    tail -20 "$log"
    return
  fi
  [ -s "$asc" ] || fail "CloudCompare wrote no $asc for $ply (log: $dir/$log)"
  grep -q "loaded successfully" "$log" || fail "CloudCompare did not say it loaded $ply"
  python3 "$stats" compare "$ply" "$asc" || fail "CloudCompare's copy of $ply differs"
}

# pcl_viewer: PCL's PLY reader converts, the viewer loads; both must count every point.
pclviewer() {
  local ply=$1 pcd=$2 log=$3 want
  want=$(python3 "$stats" count "$ply")
  local rc=0
  pcl_ply2pcd "$ply" "$pcd" >"$log.ply2pcd" 2>&1 || rc=$?
  [ "$rc" -eq 0 ] || fail "pcl_ply2pcd exited $rc on $ply"
  grep -q "Loading $ply \[done, .* : $want points\]" "$log.ply2pcd" ||
    fail "pcl_ply2pcd did not read $want points from $ply: $(grep Loading "$log.ply2pcd")"
  # The viewer has no batch mode: watch_viewer stops it once it has printed its load (or after
  # 40 s); stdbuf makes its lines reach the log at once.
  rc=0
  timeout 60 xvfb-run -a bash "$here/other_tools.sh" --watch-viewer "$pcd" "$log" || rc=$?
  [ "$rc" -eq 0 ] || fail "pcl_viewer under xvfb-run exited $rc on $pcd (log: $dir/$log)"
  grep -q "\[done, .* : $want points\]" "$log" ||
    fail "pcl_viewer did not load $want points from $pcd: $(grep -a "done" "$log" || true)"
}

for i in 0 1 2; do
  kind=$(echo a b c | cut -d' ' -f$((i + 1)))
  ply=${plys[$i]}
  echo "rig $kind: $ply, $(python3 "$stats" count "$ply") points"
  cloudcompare "$ply" "cc_$kind.asc" "cc_$kind.log"
  pclviewer "$ply" "pcl_$kind.pcd" "pcl_$kind.log"
done
[ "$failed" -eq 0 ] && echo "CloudCompare and pcl_viewer opened every rig kind's PLY"
exit "$failed"
