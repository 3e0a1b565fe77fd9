"""python/sweepmap_log.py as a command: its exit statuses (core/exit_codes.hpp) and one-line
messages, never a traceback, on a good log, a corrupt one, an empty one, a missing file, bad
arguments and a channel the log lacks; a closed pipe (`| head -1`) ends it quietly.

Needs nothing built: the logs are written here, event by event.
Usage: test_log_reader_cli.py PYTHON_SOURCE_DIR WORK_DIR
"""

import os
import struct
import subprocess
import sys

SYNC = 0xEDA1DA01


def event(num: int, utime: int, channel: str, data: bytes) -> bytes:
    c = channel.encode("ascii")
    return struct.pack(">IqqII", SYNC, num, utime, len(c), len(data)) + c + data


def run(script: str, *args: str):
    p = subprocess.run([sys.executable, script, *args], capture_output=True, text=True)
    return p.returncode, p.stdout, p.stderr


def main(python_dir: str, work: str) -> int:
    script = os.path.join(python_dir, "sweepmap_log.py")
    os.makedirs(work, exist_ok=True)
    good = os.path.join(work, "good.lcmlog")
    events = [event(i, 1000 + i, "A" if i % 3 else "B", bytes(10)) for i in range(30000)]
    with open(good, "wb") as f:
        f.write(b"".join(events))
    corrupt = os.path.join(work, "corrupt.lcmlog")
    bad_from = sum(len(e) for e in events[:5])
    bad_to = bad_from + len(events[5]) + len(events[6])
    with open(corrupt, "wb") as f:
        f.write(b"".join(events[:5]) + b"\xff" * (bad_to - bad_from) + b"".join(events[7:20]))
    empty = os.path.join(work, "empty.lcmlog")
    open(empty, "wb").close()
    missing = os.path.join(work, "missing.lcmlog")

    failures = []

    def check(what, got, status, stdout=None, stderr=None):
        rc, out, err = got
        if rc != status:
            failures.append(f"{what}: exit {rc}, expected {status} (stderr: {err!r})")
        if stdout is not None and out != stdout:
            failures.append(f"{what}: stdout {out[:200]!r}, expected {stdout!r}")
        if stderr is not None and err != stderr:
            failures.append(f"{what}: stderr {err!r}, expected {stderr!r}")
        if "Traceback" in err:
            failures.append(f"{what}: a traceback: {err}")

    check("good log", run(script, good), 0, stdout="A 20000\nB 10000\n", stderr="")
    check("one channel", run(script, good, "B"), 0, stderr="")
    check("corrupt log", run(script, corrupt), 1, stdout="A 12\nB 6\n",
          stderr=f"{corrupt}: byte {bad_from} to {bad_to} skipped: bad sync word\n")
    check("empty log", run(script, empty), 1, stdout="",
          stderr=f"sweepmap_log.py: {empty}: holds no event\n")
    check("missing log", run(script, missing), 2, stdout="",
          stderr=f"sweepmap_log.py: {missing}: no such file or directory\n")
    check("a folder", run(script, work), 2, stdout="",
          stderr=f"sweepmap_log.py: {work}: is a directory\n")
    check("no arguments", run(script), 2, stdout="")
    check("too many arguments", run(script, good, "A", "B"), 2, stdout="")
    check("unknown channel", run(script, good, "NOPE"), 2,
          stderr=f"sweepmap_log.py: {good}: no channel NOPE; its channels (events): "
                 "A (20000), B (10000)\n")

    # A closed pipe: the reader stops without a word. Its 20000 lines (260 kB) do not fit the
    # pipe's buffer, so it writes after `head` has read its first line and gone, whatever the
    # timing.
    pipe = subprocess.run(f"'{sys.executable}' '{script}' '{good}' A | head -1",
                          shell=True, capture_output=True, text=True)
    if pipe.stdout != "1001 A 10\n" or pipe.stderr != "":
        failures.append(f"closed pipe: stdout {pipe.stdout!r}, stderr {pipe.stderr!r}")

    for f in failures:
        print("FAIL:", f)
    print(f"{9 - len(failures)} cases checked" if not failures else f"{len(failures)} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:3]))
