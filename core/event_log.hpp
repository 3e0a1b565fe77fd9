// Reader and writer for LCM event logs (the format lcm-logger writes and lcm-logplayer
// reads). Each event: sync word 0xEDA1DA01, event number, timestamp [us], channel
// length, data length (all big-endian), channel, data.
//
// Written here rather than with lcm::LogFile because the reader must report the byte
// offset of a truncated or corrupt event (LCM's reader silently skips ahead to the next sync
// word), and the writer must be byte-deterministic.
//
// An event is good when its header has the sync word, a channel length of 1..255, a data
// length of at most 256 MiB, it lies inside the file, its channel is printable ASCII, and it
// swallows no event: at its end the file ends, fewer than 28 bytes remain (a cut header,
// reported on its own), or a sync word follows, or else no good event (by the same rule,
// with a sync word at its end) starts inside the span it claims. So a damaged length costs
// only its own event, never the ones it would swallow, and a damaged header costs only its
// own event, not the one before it. A reader either stops at the first event
// that is not good (throws), or, with resync, skips to the earliest good event after that
// one's first byte and keeps the skipped byte ranges. python/sweepmap_log.py reads by the same
// rule (tests/python/test_log_reader_cli.py holds them to the same results).
// Only regular files are read; resync scans a window in memory, not one read per candidate.
#pragma once

#include <cstdint>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

namespace sweepmap {

struct LogEvent {
  int64_t eventnum = 0;
  int64_t utime = 0;  // [us]
  std::string channel;
  std::vector<uint8_t> data;
};

class LogError : public std::runtime_error {
 public:
  LogError(const std::string& path, uint64_t offset, const std::string& what);
  uint64_t offset() const { return offset_; }
  const std::string& detail() const { return detail_; }  // what, without path and offset

 private:
  uint64_t offset_;
  std::string detail_;
};

// Bytes [begin, end) of a log that held no readable event, and why.
struct SkippedRange {
  uint64_t begin = 0, end = 0;
  std::string why;
};

// "PATH: byte B to E skipped: why; byte ..." ("" for none).
std::string describeSkipped(const std::string& path, const std::vector<SkippedRange>& skipped);

class EventLogReader {
 public:
  explicit EventLogReader(const std::string& path);  // throws LogError
  ~EventLogReader();
  EventLogReader(const EventLogReader&) = delete;
  EventLogReader& operator=(const EventLogReader&) = delete;

  // Reads the next event. Returns false at the end of the file. A truncated or corrupt event:
  // throws LogError with its byte offset; with resync, skips to the next good event instead
  // (or to the end) and records the range in skipped().
  bool next(LogEvent* event);
  void setResync(bool resync) { resync_ = resync; }
  const std::vector<SkippedRange>& skipped() const { return skipped_; }
  uint64_t offset() const { return offset_; }  // start of the next event
  uint64_t size() const { return size_; }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::FILE* file_ = nullptr;
  uint64_t offset_ = 0;
  uint64_t size_ = 0;
  bool resync_ = false;
  std::vector<SkippedRange> skipped_;

  // The event at offset_ (true), or false at the end; throws LogError if it is not good.
  bool readAt(LogEvent* event);
  // Why the event at `offset` is not good ("" when it is). look_inside: when no event follows
  // it, look for a good event (checked without look_inside) inside the span it claims.
  std::string problemAt(uint64_t offset, bool look_inside = true);
  // The offset of the next sync word at or after `from`, or size_.
  uint64_t nextSyncAt(uint64_t from);
  // Bytes [at, at + n) of the file, from a window kept in memory; nullptr past the end.
  const uint8_t* view(uint64_t at, size_t n);
  std::vector<uint8_t> window_;
  uint64_t window_start_ = 0;
};

// Writes an LCM event log. A write or flush that fails (a full disk) never leaves half an
// event: the file is cut back to the end of its last complete event, closed, and the error
// (std::runtime_error) says where the log now ends.
class EventLogWriter {
 public:
  explicit EventLogWriter(const std::string& path);  // truncates; throws std::runtime_error
  ~EventLogWriter();
  EventLogWriter(const EventLogWriter&) = delete;
  EventLogWriter& operator=(const EventLogWriter&) = delete;

  void write(int64_t utime, const std::string& channel, const uint8_t* data, size_t size);
  void write(int64_t utime, const std::string& channel, const std::vector<uint8_t>& data) {
    write(utime, channel, data.data(), data.size());
  }
  void flush();  // throws on I/O error, as write
  void close();  // flushes; throws on I/O error
  int64_t events() const { return next_eventnum_; }
  uint64_t bytes() const { return end_; }  // written so far, complete events only

 private:
  [[noreturn]] void fail(const std::string& what);

  std::string path_;
  std::FILE* file_ = nullptr;
  int64_t next_eventnum_ = 0;
  uint64_t end_ = 0;                      // where the next event starts
  std::vector<uint64_t> unflushed_ends_;  // ends of the events written since the last flush
  uint64_t flushed_end_ = 0;              // end of the last event known to be on disk
};

}  // namespace sweepmap
