#!/bin/bash
# `sweepmap export mcap` and `export las` read back by independent readers (@mcap/core,
# @loaders.gl/las), for every rig kind: a simulated log, its replay, the MCAP of both logs
# (checked against the logs' own channel counts), and LAS from the replay's PLYs and from the
# log (checked against the PLYs). Usage: export_readers.sh BIN_DIR SCRATCH_DIR
# Exit 77 (skipped) without node, zstd or the test-only npm packages (tools/ops/setup.sh).
set -euo pipefail
bin=$1
dir=$2
js=$(cd "$(dirname "$0")" && pwd)
if ! command -v node >/dev/null || ! command -v zstd >/dev/null ||
  [ ! -d "$js/node_modules/@mcap/core" ] || [ ! -d "$js/node_modules/@loaders.gl/las" ]; then
  echo "skipped: node, zstd or tests/js/node_modules missing (tools/ops/setup.sh installs them)"
  exit 77
fi
rm -rf "$dir" && mkdir -p "$dir" && cd "$dir"
sweepmap="$bin/sweepmap"

"$sweepmap" sim --rig rig_a --mode 1 --sweeps 2 --out a.lcmlog
"$sweepmap" sim --rig rig_b --out b.lcmlog
"$sweepmap" sim --rig rig_c --out c.lcmlog
# Intensity: rig A's simulated UST measures it; rig B's X4 and rig C's profiler do not.
declare -A intensity=([a]=all [b]=none [c]=none)
for r in a b c; do
  "$sweepmap" replay $r.lcmlog --rig rig_$r --out replay_$r --quiet --no-plots
  "$sweepmap" export mcap $r.lcmlog replay_$r/derived.lcmlog --rig rig_$r --out $r.mcap
  EXPECT_INTENSITY=${intensity[$r]} node "$js/export_mcap.test.js" $r.mcap $r.lcmlog replay_$r/derived.lcmlog
done
# Uncompressed chunks, derived channels only.
"$sweepmap" export mcap replay_a/derived.lcmlog --rig rig_a --out a_plain.mcap --no-compression
node "$js/export_mcap.test.js" a_plain.mcap replay_a/derived.lcmlog

# LAS from PLY (every rig kind writes PLY now) and from the log's SWEEP_CLOUD chunks.
# Rig A's PLYs carry intensity (and so both its LAS files); rig B's and rig C's none.
plys_a=(replay_a/sweeps/sweep_*.ply)
"$sweepmap" export las "${plys_a[@]}" --out a_ply.las
EXPECT_INTENSITY=all node "$js/export_las.test.mjs" a_ply.las "${plys_a[@]}"
"$sweepmap" export las replay_a/derived.lcmlog --out a_log.las
EXPECT_INTENSITY=all node "$js/export_las.test.mjs" a_log.las "${plys_a[@]}"
for r in b c; do
  "$sweepmap" export las replay_$r/cloud.ply --out $r.las
  EXPECT_INTENSITY=none node "$js/export_las.test.mjs" $r.las replay_$r/cloud.ply
done
ls -l ./*.mcap ./*.las
