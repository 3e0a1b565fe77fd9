#include "core/event_log.hpp"

#include <stdio_ext.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace sweepmap {
namespace {

constexpr uint32_t kSync = 0xEDA1DA01u;
constexpr uint32_t kMaxChannelLength = 255;      // LCM's own limit for channel names
constexpr uint32_t kMaxDataLength = 256u << 20;  // far above any LCM message

uint64_t readBE(const uint8_t* p, int n) {
  uint64_t v = 0;
  for (int i = 0; i < n; ++i) v = (v << 8) | p[i];
  return v;
}

void writeBE(uint8_t* p, uint64_t v, int n) {
  for (int i = n - 1; i >= 0; --i) {
    p[i] = static_cast<uint8_t>(v & 0xff);
    v >>= 8;
  }
}

}  // namespace

LogError::LogError(const std::string& path, uint64_t offset, const std::string& what)
    : std::runtime_error(path + ": byte " + std::to_string(offset) + ": " + what),
      offset_(offset),
      detail_(what) {}

EventLogReader::EventLogReader(const std::string& path) : path_(path) {
  file_ = std::fopen(path.c_str(), "rb");
  if (!file_) throw LogError(path, 0, std::string("cannot open: ") + std::strerror(errno));
  if (std::fseek(file_, 0, SEEK_END) == 0) {
    const long end = std::ftell(file_);
    size_ = end > 0 ? static_cast<uint64_t>(end) : 0;
  }
  std::fseek(file_, 0, SEEK_SET);
}

EventLogReader::~EventLogReader() {
  if (file_) std::fclose(file_);
}

std::string describeSkipped(const std::string& path, const std::vector<SkippedRange>& skipped) {
  std::string out;
  for (const SkippedRange& r : skipped) {
    out += (out.empty() ? path + ": " : std::string("; ")) + "byte " + std::to_string(r.begin) +
           " to " + std::to_string(r.end) + " skipped: " + r.why;
  }
  return out;
}

bool EventLogReader::next(LogEvent* event) {
  try {
    return readAt(event);
  } catch (const LogError& e) {
    if (!resync_) throw;
    const uint64_t bad = offset_;
    uint64_t good = nextSyncAt(bad + 1);
    while (good < size_ && !plausibleEventAt(good)) good = nextSyncAt(good + 1);
    skipped_.push_back({bad, good, e.detail()});
    offset_ = std::min(good, size_);
    std::clearerr(file_);
    std::fseek(file_, static_cast<long>(offset_), SEEK_SET);
    return offset_ < size_ && readAt(event);
  }
}

uint64_t EventLogReader::nextSyncAt(uint64_t from) {
  std::vector<uint8_t> buf(1 << 16);
  for (uint64_t at = from; at < size_;) {
    if (std::fseek(file_, static_cast<long>(at), SEEK_SET) != 0) break;
    const size_t n = std::fread(buf.data(), 1, buf.size(), file_);
    if (n < 4) break;
    for (size_t i = 0; i + 4 <= n; ++i) {
      if (buf[i] == 0xED && readBE(&buf[i], 4) == kSync) return at + i;
    }
    at += n - 3;  // a sync word across the chunk boundary is found in the next chunk
  }
  return size_;
}

bool EventLogReader::plausibleEventAt(uint64_t offset) {
  const auto headerAt = [this](uint64_t at, uint8_t* h) {
    return std::fseek(file_, static_cast<long>(at), SEEK_SET) == 0 &&
           std::fread(h, 1, 28, file_) == 28 && readBE(h, 4) == kSync;
  };
  uint8_t h[28];
  if (offset + 28 > size_ || !headerAt(offset, h)) return false;
  const uint64_t channel_len = readBE(h + 20, 4), data_len = readBE(h + 24, 4);
  if (channel_len == 0 || channel_len > kMaxChannelLength || data_len > kMaxDataLength) {
    return false;
  }
  const uint64_t end = offset + 28 + channel_len + data_len;
  if (end > size_) return false;
  char channel[kMaxChannelLength];
  if (std::fread(channel, 1, channel_len, file_) != channel_len) return false;
  for (uint64_t i = 0; i < channel_len; ++i) {
    if (channel[i] < 0x20 || channel[i] > 0x7e) return false;
  }
  uint8_t next[28];
  return end == size_ || (end + 28 <= size_ && headerAt(end, next)) ||
         (end + 28 > size_ && end < size_);  // a cut event after it is the next range's
}

bool EventLogReader::readAt(LogEvent* event) {
  uint8_t header[28];
  const size_t got = std::fread(header, 1, sizeof header, file_);
  if (got == 0 && std::feof(file_)) return false;
  if (got != sizeof header) {
    throw LogError(path_, offset_,
                   "truncated event header (" + std::to_string(got) + " of 28 bytes)");
  }
  if (readBE(header, 4) != kSync) throw LogError(path_, offset_, "bad sync word (corrupt log)");
  const uint32_t channel_len = static_cast<uint32_t>(readBE(header + 20, 4));
  const uint32_t data_len = static_cast<uint32_t>(readBE(header + 24, 4));
  if (channel_len == 0 || channel_len > kMaxChannelLength) {
    throw LogError(path_, offset_, "bad channel length " + std::to_string(channel_len));
  }
  if (data_len > kMaxDataLength) {
    throw LogError(path_, offset_, "bad data length " + std::to_string(data_len));
  }
  const uint64_t event_size = sizeof header + uint64_t(channel_len) + data_len;
  if (size_ != 0 && offset_ + event_size > size_) {
    throw LogError(path_, offset_,
                   "truncated event: needs " + std::to_string(event_size) + " bytes, " +
                       std::to_string(size_ - offset_) + " left");
  }
  event->eventnum = static_cast<int64_t>(readBE(header + 4, 8));
  event->utime = static_cast<int64_t>(readBE(header + 12, 8));
  event->channel.resize(channel_len);
  event->data.resize(data_len);
  if (std::fread(event->channel.data(), 1, channel_len, file_) != channel_len ||
      std::fread(event->data.data(), 1, data_len, file_) != data_len) {
    throw LogError(path_, offset_, "truncated event body");
  }
  offset_ += event_size;
  return true;
}

EventLogWriter::EventLogWriter(const std::string& path) : path_(path) {
  file_ = std::fopen(path.c_str(), "wb");
  if (!file_) throw std::runtime_error(path + ": cannot create: " + std::strerror(errno));
}

EventLogWriter::~EventLogWriter() {
  if (file_) std::fclose(file_);
}

void EventLogWriter::write(int64_t utime, const std::string& channel, const uint8_t* data,
                           size_t size) {
  if (!file_) throw std::logic_error(path_ + ": write after close");
  uint8_t header[28];
  writeBE(header, kSync, 4);
  writeBE(header + 4, static_cast<uint64_t>(next_eventnum_), 8);
  writeBE(header + 12, static_cast<uint64_t>(utime), 8);
  writeBE(header + 20, channel.size(), 4);
  writeBE(header + 24, size, 4);
  if (std::fwrite(header, 1, sizeof header, file_) != sizeof header ||
      std::fwrite(channel.data(), 1, channel.size(), file_) != channel.size() ||
      (size && std::fwrite(data, 1, size, file_) != size)) {
    fail("write failed: " + std::string(std::strerror(errno)));
  }
  ++next_eventnum_;
  end_ += sizeof header + channel.size() + size;
  unflushed_ends_.push_back(end_);
}

void EventLogWriter::flush() {
  if (!file_) return;
  if (std::fflush(file_) != 0) fail("write failed: " + std::string(std::strerror(errno)));
  flushed_end_ = end_;
  unflushed_ends_.clear();
}

// Cuts the file back to the last event that reached it whole, closes it and throws.
void EventLogWriter::fail(const std::string& what) {
  __fpurge(file_);  // what stdio still holds must not follow the cut at fclose
  const int fd = ::fileno(file_);
  struct stat st {};
  uint64_t keep = flushed_end_;
  if (::fstat(fd, &st) == 0) {
    for (uint64_t e : unflushed_ends_) {
      if (e <= static_cast<uint64_t>(st.st_size)) keep = e;
    }
  }
  const int truncated = ::ftruncate(fd, static_cast<off_t>(keep));
  std::fclose(file_);
  file_ = nullptr;
  throw std::runtime_error(
      path_ + ": " + what +
      (truncated == 0
           ? "; the log ends after its last complete event, at byte " + std::to_string(keep)
           : "; could not cut the log back to byte " + std::to_string(keep)));
}

void EventLogWriter::close() {
  if (!file_) return;
  flush();
  const bool ok = std::fclose(file_) == 0;
  file_ = nullptr;
  if (!ok) throw std::runtime_error(path_ + ": close failed");
}

}  // namespace sweepmap
