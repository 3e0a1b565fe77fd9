"""The Python example of docs/how-to/python-logs.md, checked: python/sweepmap_log.py and the lcm-gen Python types
read a simulated rig-B log as sweepmap's own `dump` does (every LIDAR_SCAN, same times and
ranges), and skip a corrupt region to the same byte ranges as sweepmap's reader.

Usage: test_log_reader.py BIN_DIR PYTHON_DIR WORK_DIR
"""

import json
import os
import subprocess
import sys


def main(bin_dir: str, python_dir: str, work: str) -> int:
    sys.path.insert(0, python_dir)
    import sweepmap  # noqa: E402 (generated at build time)
    import sweepmap_log  # noqa: E402

    os.makedirs(work, exist_ok=True)
    log = os.path.join(work, "b.lcmlog")
    sweepmap_bin = os.path.join(bin_dir, "sweepmap")
    subprocess.run([sweepmap_bin, "sim", "--rig", "rig_b", "--set", "sim.duration_s=3",
                    "--seed", "2", "--out", log], check=True, stdout=subprocess.DEVNULL)

    # The docs' example.
    scans = []
    for ev in sweepmap_log.events(log, channels={"LIDAR_SCAN"}):
        scan = sweepmap.lidar_scan_t.decode(ev.data)
        scans.append((ev.utime, scan))
    dumped = subprocess.run([sweepmap_bin, "dump", log, "--json", "--channel", "LIDAR_SCAN"],
                            check=True, capture_output=True, text=True).stdout.splitlines()
    dumped = [json.loads(line) for line in dumped]
    failures = []
    if len(scans) != len(dumped) or not scans:
        failures.append(f"{len(scans)} scans read, sweepmap dump has {len(dumped)}")
    for (log_utime, scan), d in zip(scans, dumped):
        if log_utime != d["log_utime"] or scan.utime != d["utime"] or scan.nranges != d["nranges"]:
            failures.append(f"scan at {log_utime}: times or sizes differ from dump's")
            break
        for a, b in zip(scan.ranges_m, d["ranges_m"]):
            if abs(a - b) > 1e-6 * max(1.0, abs(b)):
                failures.append(f"scan at {log_utime}: range {a} != {b}")
                break

    # A corrupt region in the middle: the same events outside it, the same range skipped.
    with open(log, "rb") as f:
        data = bytearray(f.read())
    starts = [ev.offset for ev in sweepmap_log.events(log)]
    bad_from, bad_to = starts[len(starts) // 2], starts[len(starts) // 2 + 3]
    for i in range(bad_from + 2, bad_to - 5):
        data[i] = (i * 37) & 0xFF
    bad = os.path.join(work, "bad.lcmlog")
    with open(bad, "wb") as f:
        f.write(data)
    skipped = []
    kept = list(sweepmap_log.events(bad, on_skip=lambda b, e, why: skipped.append((b, e))))
    cpp = subprocess.run([sweepmap_bin, "dump", bad], capture_output=True, text=True)
    cpp_skipped = [line for line in cpp.stderr.splitlines() if "skipped" in line]
    if skipped != [(bad_from, bad_to)]:
        failures.append(f"python skipped {skipped}, expected [({bad_from}, {bad_to})]")
    if len(cpp_skipped) != 1 or f"byte {bad_from} to {bad_to} skipped" not in cpp_skipped[0]:
        failures.append(f"sweepmap dump reported {cpp_skipped}")
    if len(kept) != len(starts) - 3:
        failures.append(f"{len(kept)} events kept of {len(starts)} - 3")

    for f in failures:
        print("FAIL:", f)
    print(f"{len(scans)} LIDAR_SCAN read; corrupt bytes {bad_from}..{bad_to} skipped by both")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:4]))
