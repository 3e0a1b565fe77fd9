#!/usr/bin/env python3
"""The stale-reference check can fail: pages generated now pass `--check`; the same pages with
one line of config.md altered fail it, with a diff showing that line and the fix.

Usage: test_stale_check.py GENERATOR BIN_DIR SOURCE_DIR
"""

import subprocess
import sys
import tempfile
from pathlib import Path


def check(generator: str, bin_dir: str, source: str, pages: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, generator, bin_dir, "--source", source,
                           "--out", str(pages), "--check"], capture_output=True, text=True)


def main(generator: str, bin_dir: str, source: str) -> int:
    failures = []
    with tempfile.TemporaryDirectory(prefix="sweepmap-stale-") as tmp:
        pages = Path(tmp)
        subprocess.run([sys.executable, generator, bin_dir, "--source", source, "--out", tmp],
                       check=True)
        fresh = check(generator, bin_dir, source, pages)
        if fresh.returncode != 0:
            failures.append(f"freshly generated pages reported stale:\n{fresh.stdout}")
        config = pages / "config.md"
        lines = config.read_text().splitlines(True)
        row = next(i for i, line in enumerate(lines) if line.startswith("| `"))
        altered = lines[row].replace("| `", "| `stale.", 1)
        config.write_text("".join(lines[:row] + [altered] + lines[row + 1:]))
        stale = check(generator, bin_dir, source, pages)
        if stale.returncode != 1:
            failures.append(f"altered config.md: exit {stale.returncode}, expected 1")
        for expected in ("-" + altered, "stale: config.md", "make docs"):
            if expected not in stale.stdout:
                failures.append(f"altered config.md: the output lacks {expected!r}")
        print(stale.stdout[-2000:])
    for f in failures:
        print("FAIL:", f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:4]))
