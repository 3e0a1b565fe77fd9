// Reader and writer for LCM event logs (the format lcm-logger writes and lcm-logplayer
// reads). Each event: sync word 0xEDA1DA01, event number, timestamp [us], channel
// length, data length (all big-endian), channel, data.
//
// Written here rather than with lcm::LogFile because the reader must report the byte
// offset of a truncated or corrupt event and stop there (LCM's reader silently skips
// ahead to the next sync word), and the writer must be byte-deterministic.
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

 private:
  uint64_t offset_;
};

class EventLogReader {
 public:
  explicit EventLogReader(const std::string& path);  // throws LogError
  ~EventLogReader();
  EventLogReader(const EventLogReader&) = delete;
  EventLogReader& operator=(const EventLogReader&) = delete;

  // Reads the next event. Returns false at a clean end of file; throws LogError with the
  // byte offset of the event that is truncated or corrupt.
  bool next(LogEvent* event);
  uint64_t offset() const { return offset_; }  // start of the next event
  uint64_t size() const { return size_; }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::FILE* file_ = nullptr;
  uint64_t offset_ = 0;
  uint64_t size_ = 0;
};

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
  void flush();
  void close();  // flushes; throws on I/O error
  int64_t events() const { return next_eventnum_; }

 private:
  std::string path_;
  std::FILE* file_ = nullptr;
  int64_t next_eventnum_ = 0;
};

}  // namespace sweepmap
