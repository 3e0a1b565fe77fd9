"""The C++ and Python log readers agree (issue 21), on one corpus of damaged logs made here,
deterministically: a grown data length (by one bit, by 64 KiB, to 2^32 - 1), a shrunk one, a
truncated tail (in a header, in a body), garbage between events, megabytes of repeated sync
words, channels that are not ASCII (nor UTF-8), payloads that are not UTF-8, zero-length data
and channels, an empty file, and seeded random damage to headers. For each log, the events
(offset, number, time, channel, size, FNV-1a hash of the data) and the skipped byte ranges of
core/event_log.hpp (through tests/core/log_events) and python/sweepmap_log.py are the same;
and events and skipped ranges together cover every byte of the file, so nothing is lost
unreported. A few cases also check what a damage must cost (only its own event).

Usage: test_log_readers_agree.py LOG_EVENTS_EXE PYTHON_SOURCE_DIR WORK_DIR [EMULATOR...]
(EMULATOR: what runs LOG_EVENTS_EXE when it was cross-built, e.g. qemu-aarch64-static.)
"""

import os
import random
import struct
import subprocess
import sys

SYNC = 0xEDA1DA01
HEADER = struct.Struct(">IqqII")


def event(num: int, utime: int, channel: bytes, data: bytes) -> bytes:
    return HEADER.pack(SYNC, num, utime, len(channel), len(data)) + channel + data


def base_events(rng: random.Random):
    """A clean log's events: several channels, sizes from 0 to 3 kB, payloads with strings
    that are not UTF-8."""
    channels = [b"LIDAR_SCAN", b"IMU", b"STATUS_ASSEMBLER", b"SWEEP_CLOUD", b"X"]
    out = []
    for i in range(120):
        size = rng.choice([0, 1, 7, 40, 300, 3000])
        data = bytes(rng.getrandbits(8) for _ in range(size))
        if i % 7 == 3:
            data = b"\x00\x00\x00\x05\xff\xfe\xc3(\x00" + data  # an LCM string, not UTF-8
        out.append(event(i, 1_000_000 + 25_000 * i, channels[i % len(channels)], data))
    return out


def with_field(ev: bytes, index: int, value: int) -> bytes:
    fields = list(HEADER.unpack_from(ev, 0))
    fields[index] = value
    return HEADER.pack(*fields) + ev[HEADER.size:]


def corpus(rng: random.Random):
    """{name: bytes} of damaged logs."""
    evs = base_events(rng)
    clean = b"".join(evs)
    logs = {"clean": clean, "empty": b"", "header_only": clean[:20]}

    def replaced(k: int, ev: bytes) -> bytes:
        return b"".join(evs[:k] + [ev] + evs[k + 1:])

    data_len = lambda ev: HEADER.unpack_from(ev, 0)[4]  # noqa: E731
    logs["grown_length_bit16"] = replaced(10, with_field(evs[10], 4, data_len(evs[10]) | 1 << 16))
    logs["grown_length_plus_one"] = replaced(11, with_field(evs[11], 4, data_len(evs[11]) + 1))
    logs["shrunk_length"] = replaced(17, with_field(evs[17], 4, max(0, data_len(evs[17]) - 5)))
    logs["huge_length"] = replaced(20, with_field(evs[20], 4, 0xFFFFFFFF))
    logs["huge_channel_length"] = replaced(21, with_field(evs[21], 3, 0xFFFFFFFF))
    logs["zero_channel_length"] = replaced(22, with_field(evs[22], 3, 0))
    logs["grown_last_length"] = replaced(len(evs) - 1,
                                         with_field(evs[-1], 4, data_len(evs[-1]) + 100))
    logs["truncated_in_body"] = clean[:len(clean) - 10]
    logs["truncated_in_header"] = clean[:len(clean) - len(evs[-1]) + 13]
    logs["garbage_between"] = b"".join(evs[:30]) + bytes(
        rng.getrandbits(8) for _ in range(5000)) + b"".join(evs[30:])
    sync = struct.pack(">I", SYNC)
    logs["repeated_sync_words"] = b"".join(evs[:40]) + sync * (1 << 18) + b"".join(evs[40:])
    logs["sync_words_and_half_headers"] = b"".join(evs[:5]) + (sync + b"\x00" * 19) * 3000 + \
        b"".join(evs[5:])
    ch = evs[33][HEADER.size:HEADER.size + 3]
    bad_channel = evs[33][:HEADER.size] + b"\xff\xfe\x80" + evs[33][HEADER.size + 3:]
    assert ch != b"\xff\xfe\x80"
    logs["channel_not_utf8"] = replaced(33, bad_channel)
    logs["zero_length_events"] = b"".join(
        [event(i, i, b"E", b"") for i in range(50)]) + clean
    for k in range(12):  # seeded random damage to headers
        buf = bytearray(clean)
        starts = [sum(len(e) for e in evs[:i]) for i in range(len(evs))]
        for _ in range(3):
            at = rng.choice(starts) + rng.randrange(HEADER.size)
            buf[at] = rng.getrandbits(8)
        logs[f"random_header_damage_{k}"] = bytes(buf)
    return logs, evs


def read_cpp(exe: list, path: str):
    p = subprocess.run([*exe, path], capture_output=True, text=True)
    if p.returncode != 0:
        raise RuntimeError(f"{' '.join(exe)} {path}: exit {p.returncode}: {p.stderr}")
    events, skipped = [], []
    for line in p.stdout.splitlines():
        kind, *f = line.split(" ")
        if kind == "event":
            events.append((int(f[0]), int(f[1]), int(f[2]), f[3], int(f[4]), f[5]))
        else:
            skipped.append((int(f[0]), int(f[1])))
    return events, skipped


def fnv1a64(data: bytes) -> str:
    h = 0xcbf29ce484222325
    for b in data:
        h = ((h ^ b) * 0x100000001b3) & 0xFFFFFFFFFFFFFFFF
    return f"{h:016x}"


def read_python(sweepmap_log, path: str):
    skipped = []
    events = [(e.offset, e.eventnum, e.utime, e.channel, len(e.data), fnv1a64(e.data))
              for e in sweepmap_log.events(path, on_skip=lambda b, e, why: skipped.append((b, e)))]
    return events, skipped


def uncovered(size: int, events, skipped):
    """Byte ranges of the file neither in an event nor in a skipped range."""
    spans = sorted([(e[0], e[0] + 28 + len(e[3]) + e[4]) for e in events] + list(skipped))
    gaps, at = [], 0
    for begin, end in spans:
        if begin > at:
            gaps.append((at, begin))
        at = max(at, end)
    if at < size:
        gaps.append((at, size))
    return gaps


def main(exe: str, python_dir: str, work: str, *emulator: str) -> int:
    sys.path.insert(0, python_dir)
    import sweepmap_log  # noqa: E402
    os.makedirs(work, exist_ok=True)
    logs, evs = corpus(random.Random(21))
    failures = []
    results = {}
    for name, data in logs.items():
        path = os.path.join(work, name + ".lcmlog")
        with open(path, "wb") as f:
            f.write(data)
        cpp = read_cpp([*emulator, exe], path)
        py = read_python(sweepmap_log, path)
        results[name] = cpp
        if cpp[0] != py[0]:
            diff = next((i for i, (a, b) in enumerate(zip(cpp[0], py[0])) if a != b),
                        min(len(cpp[0]), len(py[0])))
            failures.append(f"{name}: events differ: C++ {len(cpp[0])}, Python {len(py[0])}; "
                            f"first difference at event {diff}")
        if cpp[1] != py[1]:
            failures.append(f"{name}: skipped ranges differ: C++ {cpp[1]}, Python {py[1]}")
        gaps = uncovered(len(data), *cpp)
        if gaps:
            failures.append(f"{name}: bytes neither read nor reported skipped: {gaps}")
    # What some damages must cost: only the damaged event.
    n = len(evs)
    for name in ("grown_length_bit16", "grown_length_plus_one", "huge_length",
                 "huge_channel_length", "zero_channel_length", "channel_not_utf8"):
        got = len(results[name][0])
        if got != n - 1:
            failures.append(f"{name}: {got} events read, expected {n - 1} (only the damaged one "
                            "lost)")
    for name in ("clean", "garbage_between", "repeated_sync_words", "sync_words_and_half_headers"):
        if len(results[name][0]) != n:
            failures.append(f"{name}: {len(results[name][0])} events read, expected all {n}")
    # A shrunk length reads its event short and reports the bytes it left behind.
    start18 = sum(len(e) for e in evs[:18])
    if results["shrunk_length"] != (results["shrunk_length"][0], [(start18 - 5, start18)]) or \
            len(results["shrunk_length"][0]) != n:
        failures.append(f"shrunk_length: {len(results['shrunk_length'][0])} events, skipped "
                        f"{results['shrunk_length'][1]}; expected {n} and [({start18 - 5}, "
                        f"{start18})]")
    if results["empty"] != ([], []):
        failures.append(f"empty: {results['empty']}")
    for f in failures:
        print("FAIL:", f)
    print(f"{len(logs)} logs read alike by both readers" if not failures
          else f"{len(failures)} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:]))
