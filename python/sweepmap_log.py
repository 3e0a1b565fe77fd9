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

As a command (`python3 sweepmap_log.py LOG [CHANNEL]`) it follows sweepmap's exit statuses:
0 success; 1 the log held a problem (corrupt bytes, each skipped range named with its byte
offsets on stderr, or no event at all); 2 usage (bad arguments, a missing log, a CHANNEL the
log does not have); 4 the log cannot be read. Each error is one line on stderr, never a
traceback; a closed pipe (`... | head -1`) ends it quietly, as it ends `cat`.
"""

import errno
import os
import stat
import signal
import struct
import sys
from typing import Callable, Iterator, NamedTuple, Optional, Set

SYNC = 0xEDA1DA01
_SYNC_BYTES = struct.pack(">I", 0xEDA1DA01)
_HEADER = struct.Struct(">IqqII")  # sync, event number, utime, channel length, data length
_MAX_CHANNEL = 255
_MAX_DATA = 256 << 20


class Event(NamedTuple):
    eventnum: int
    utime: int  # [us]
    channel: str
    data: bytes
    offset: int  # of the event's first byte in the file


def _event_at(buf: bytes, at: int, look_inside: bool = True) -> Optional[Event]:
    """The event at `at` if a good one starts there: sync word, lengths, inside the file, a
    printable channel, and it swallows no event (see core/event_log.hpp)."""
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
    # It swallows no event (core/event_log.hpp's rule): where it ends, the file ends, a cut
    # header or a sync word follows, or else no good event starts inside the span it claims.
    if len(buf) - end >= _HEADER.size and _HEADER.unpack_from(buf, end)[0] != SYNC:
        if not look_inside:
            return None
        c = buf.find(_SYNC_BYTES, at + 1, end + 3)  # a sync word starting before `end`
        while c != -1:
            if _event_at(buf, c, False) is not None:
                return None
            c = buf.find(_SYNC_BYTES, c + 1, end + 3)
    return Event(eventnum, utime, channel.decode("ascii"), buf[start + channel_len:end], at)


def _report(path: str) -> Callable[[int, int, str], None]:
    def report(begin: int, end: int, why: str) -> None:
        print(f"{path}: byte {begin} to {end} skipped: {why}", file=sys.stderr)
    return report


def events(path: str, channels: Optional[Set[str]] = None,
           on_skip: Optional[Callable[[int, int, str], None]] = None) -> Iterator[Event]:
    """Every event of the log in file order (only `channels`, if given). Only a regular file is
    read (a device or FIFO would never end): anything else raises IsADirectoryError or
    OSError."""
    mode = os.stat(path).st_mode  # before open(): opening a FIFO would wait for a writer
    if stat.S_ISDIR(mode):
        raise IsADirectoryError(errno.EISDIR, "is a directory")
    if not stat.S_ISREG(mode):
        raise OSError(errno.EINVAL, "not a regular file (a device, FIFO or folder is no log)")
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


EXIT_OK, EXIT_BAD_INPUT, EXIT_USAGE, EXIT_IO = 0, 1, 2, 4  # core/exit_codes.hpp
_PROG = "sweepmap_log.py"


def _fail(status: int, message: str) -> int:
    print(f"{_PROG}: {message}", file=sys.stderr)
    return status


def _read_all(path: str, channel: Optional[str]):
    """Every event's channel in the log (all of it) and the events of `channel` (or none);
    whether any byte range was skipped. Raises OSError."""
    skipped = []

    def on_skip(begin: int, end: int, why: str) -> None:
        skipped.append(begin)
        _report(path)(begin, end, why)

    counts = {}
    for ev in events(path, on_skip=on_skip):
        counts[ev.channel] = counts.get(ev.channel, 0) + 1
        if channel is not None and ev.channel == channel:
            print(ev.utime, ev.channel, len(ev.data))
    return counts, bool(skipped)


def main(argv) -> int:
    """python3 sweepmap_log.py LOG [CHANNEL]: event counts per channel, or one line per event
    of CHANNEL (log time [us], channel, bytes)."""
    if len(argv) not in (2, 3) or argv[1] in ("-h", "--help"):
        print(main.__doc__, file=sys.stderr)
        return EXIT_USAGE if len(argv) not in (2, 3) else EXIT_OK
    path = argv[1]
    channel = argv[2] if len(argv) > 2 else None
    try:
        counts, corrupt = _read_all(path, channel)
    except (FileNotFoundError, IsADirectoryError, NotADirectoryError) as e:
        return _fail(EXIT_USAGE, f"{path}: {e.strerror.lower()}")
    except OSError as e:
        if e.errno == errno.EINVAL:
            return _fail(EXIT_USAGE, f"{path}: {e.strerror}")
        return _fail(EXIT_IO, f"{path}: cannot read: {e.strerror or e}")
    if not counts:
        return _fail(EXIT_BAD_INPUT, f"{path}: holds no event"
                     + (" (corrupt throughout)" if corrupt else ""))
    if channel is None:
        for name, n in sorted(counts.items()):
            print(f"{name} {n}")
    elif channel not in counts:
        have = ", ".join(f"{name} ({n})" for name, n in sorted(counts.items()))
        return _fail(EXIT_USAGE, f"{path}: no channel {channel}; its channels (events): {have}")
    return EXIT_BAD_INPUT if corrupt else EXIT_OK


def _run() -> int:
    # A closed pipe ends the program as it ends `cat`: by SIGPIPE, silently. Where SIGPIPE does
    # not exist, the BrokenPipeError is caught instead and stdout pointed at /dev/null so that
    # the interpreter's last flush does not raise again.
    if hasattr(signal, "SIGPIPE"):
        signal.signal(signal.SIGPIPE, signal.SIG_DFL)
    try:
        status = main(sys.argv)
        sys.stdout.flush()
        return status
    except BrokenPipeError:
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return EXIT_OK
    except KeyboardInterrupt:
        return 130


if __name__ == "__main__":
    sys.exit(_run())
