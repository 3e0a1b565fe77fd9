"""Reads LCM event logs (what lcm-logger writes, and sweepmap's own logs) in pure Python.

Debian 12 has no Python binding for LCM; the message types need none: `lcm-gen --python`
makes plain classes with `decode(bytes)`, generated at build time into build/python/sweepmap/.
With both on the path (PYTHONPATH=build/python):

    import sweepmap, sweepmap_log
    for ev in sweepmap_log.events("run.lcmlog", channels={"LIDAR_SCAN"}):
        scan = sweepmap.lidar_scan_t.decode(ev.data)
        print(ev.utime, scan.nranges, max(scan.ranges_m))

Each event: sync word 0xEDA1DA01, event number, timestamp [us], channel length, data length
(big-endian), channel, data. A corrupt region or a truncated tail is skipped to the next
event header that holds up (as sweepmap replay does); each skipped byte range is reported
through `on_skip(begin, end, why)` (default: a line on stderr).
"""

import struct
import sys
from typing import Callable, Iterator, NamedTuple, Optional, Set

SYNC = 0xEDA1DA01
_HEADER = struct.Struct(">IqqII")  # sync, event number, utime, channel length, data length
_MAX_CHANNEL = 255
_MAX_DATA = 256 << 20


class Event(NamedTuple):
    eventnum: int
    utime: int  # [us]
    channel: str
    data: bytes
    offset: int  # of the event's first byte in the file


def _event_at(buf: bytes, at: int) -> Optional[Event]:
    """The event at `at` if a whole, plausible one starts there."""
    if at + _HEADER.size > len(buf):
        return None
    sync, eventnum, utime, channel_len, data_len = _HEADER.unpack_from(buf, at)
    if sync != SYNC or not 0 < channel_len <= _MAX_CHANNEL or data_len > _MAX_DATA:
        return None
    start = at + _HEADER.size
    end = start + channel_len + data_len
    if end > len(buf):
        return None
    channel = buf[start:start + channel_len]
    if any(c < 0x20 or c > 0x7E for c in channel):
        return None
    return Event(eventnum, utime, channel.decode("ascii"), buf[start + channel_len:end], at)


def _report(path: str) -> Callable[[int, int, str], None]:
    def report(begin: int, end: int, why: str) -> None:
        print(f"{path}: byte {begin} to {end} skipped: {why}", file=sys.stderr)
    return report


def events(path: str, channels: Optional[Set[str]] = None,
           on_skip: Optional[Callable[[int, int, str], None]] = None) -> Iterator[Event]:
    """Every event of the log in file order (only `channels`, if given)."""
    with open(path, "rb") as f:
        buf = f.read()
    on_skip = on_skip or _report(path)
    sync_bytes = struct.pack(">I", SYNC)
    at = 0
    while at < len(buf):
        ev = _event_at(buf, at)
        if ev is None:
            why = ("truncated event" if buf.startswith(sync_bytes, at) else "bad sync word")
            good = buf.find(sync_bytes, at + 1)
            while good != -1 and _event_at(buf, good) is None:
                good = buf.find(sync_bytes, good + 1)
            good = len(buf) if good == -1 else good
            on_skip(at, good, why)
            at = good
            continue
        at += _HEADER.size + len(ev.channel) + len(ev.data)
        if channels is None or ev.channel in channels:
            yield ev


def main(argv) -> int:
    """python3 sweepmap_log.py LOG [CHANNEL]: event counts per channel, or one line per event."""
    if len(argv) < 2:
        print(main.__doc__, file=sys.stderr)
        return 2
    if len(argv) > 2:
        for ev in events(argv[1], {argv[2]}):
            print(ev.utime, ev.channel, len(ev.data))
        return 0
    counts = {}
    for ev in events(argv[1]):
        counts[ev.channel] = counts.get(ev.channel, 0) + 1
    for channel, n in sorted(counts.items()):
        print(f"{channel} {n}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
