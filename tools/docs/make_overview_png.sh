#!/usr/bin/env bash
# Draws docs/images/overview.png, the README's picture until a screenshot of the live view
# replaces it: one simulated rig-A sweep of the conference room (mode 4), replayed, its points
# seen in perspective from above the room's corner, coloured by height, the ceiling cut away.
#   tools/docs/make_overview_png.sh BIN_DIR [OUT_PNG]
# Needs gnuplot and python3. Deterministic: the same build draws the same points.
set -euo pipefail
bin_dir=$(cd "$1" && pwd)
out=$(realpath -m "${2:-$(dirname "$0")/../../docs/images/overview.png}")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
"$bin_dir/sweepmap" sim --rig rig_a --mode 4 --sweeps 1 --seed 1 --out room.lcmlog
"$bin_dir/sweepmap" replay room.lcmlog --rig rig_a --out room --no-plots
# The sweep's PLY (binary little-endian float32 x, y, z) as text, ceiling and floor cut, thinned.
python3 - room/sweeps/sweep_000000.ply points.txt <<'PY'
import struct, sys
data = open(sys.argv[1], "rb").read()
end = data.index(b"end_header\n") + len(b"end_header\n")
count = int(next(l.split()[2] for l in data[:end].decode().splitlines() if l.startswith("element vertex")))
with open(sys.argv[2], "w") as out:
    for i in range(0, count, 3):
        x, y, z = struct.unpack_from("<fff", data, end + 12 * i)
        if -1.2 < z < 1.1 and x * x + y * y > 0.04:
            out.write(f"{x:.3f} {y:.3f} {z:.3f}\n")
PY
gnuplot <<GP
set terminal pngcairo size 1200,640 background rgb "white"
set output "$out"
unset key; unset border; unset tics; unset colorbox
set view 62, 30, 1.75, 1.2
set view equal xyz
set palette defined (0 "#2c7bb6", 0.35 "#abd9e9", 0.6 "#fdae61", 1 "#d7191c")
splot "points.txt" using 1:2:3:3 with points pt 7 ps 0.12 lc palette
GP
echo "wrote $out"
