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
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    throw LogError(path, 0, std::string("cannot open: ") + std::strerror(errno));
  }
  if (!S_ISREG(st.st_mode)) {
    throw LogError(path, 0, "not a regular file (a device, FIFO or folder is no log)");
  }
  file_ = std::fopen(path.c_str(), "rb");
  if (!file_) throw LogError(path, 0, std::string("cannot open: ") + std::strerror(errno));
  size_ = static_cast<uint64_t>(st.st_size);
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
    while (good < size_ && !problemAt(good).empty()) good = nextSyncAt(good + 1);
    skipped_.push_back({bad, good, e.detail()});
    offset_ = std::min(good, size_);
    return offset_ < size_ && readAt(event);
  }
}

const uint8_t* EventLogReader::view(uint64_t at, size_t n) {
  if (at + n > size_) return nullptr;
  if (at < window_start_ || at + n > window_start_ + window_.size()) {
    constexpr size_t kWindow = 1 << 20;
    window_.resize(std::min<uint64_t>(std::max(kWindow, n), size_ - at));
    window_start_ = at;
    std::clearerr(file_);
    if (std::fseek(file_, static_cast<long>(at), SEEK_SET) != 0 ||
        std::fread(window_.data(), 1, window_.size(), file_) != window_.size()) {
      window_.clear();
      return nullptr;
    }
  }
  return window_.data() + (at - window_start_);
}

uint64_t EventLogReader::nextSyncAt(uint64_t from) {
  while (from + 4 <= size_) {
    const uint8_t* p = view(from, 4);
    if (!p) break;
    const uint8_t* end = window_.data() + window_.size();
    for (const uint8_t* q = p; q + 4 <= end; ++q) {
      q = static_cast<const uint8_t*>(std::memchr(q, 0xED, static_cast<size_t>(end - q)));
      if (!q || q + 4 > end) break;
      if (readBE(q, 4) == kSync) return window_start_ + static_cast<uint64_t>(q - window_.data());
    }
    from = window_start_ + window_.size() - 3;  // a sync word across the edge: next window
  }
  return size_;
}

std::string EventLogReader::problemAt(uint64_t at, bool look_inside) {
  if (size_ - at < 28) {
    return "truncated event header (" + std::to_string(size_ - at) + " of 28 bytes)";
  }
  const uint8_t* h = view(at, 28);
  if (!h) return "cannot read the event header";
  if (readBE(h, 4) != kSync) return "bad sync word (corrupt log)";
  const uint64_t channel_len = readBE(h + 20, 4), data_len = readBE(h + 24, 4);
  if (channel_len == 0 || channel_len > kMaxChannelLength) {
    return "bad channel length " + std::to_string(channel_len);
  }
  if (data_len > kMaxDataLength) return "bad data length " + std::to_string(data_len);
  const uint64_t end = at + 28 + channel_len + data_len;
  if (end > size_) {
    return "truncated event: needs " + std::to_string(end - at) + " bytes, " +
           std::to_string(size_ - at) + " left";
  }
  const uint8_t* channel = view(at + 28, channel_len);
  if (!channel) return "cannot read the channel name";
  for (uint64_t i = 0; i < channel_len; ++i) {
    if (channel[i] < 0x20 || channel[i] > 0x7e) return "channel name not printable";
  }
  if (size_ - end < 28) return {};
  const uint8_t* next = view(end, 4);
  if (next && readBE(next, 4) == kSync) return {};
  // No event where this one ends: either its length is damaged (then a good event starts
  // inside the span it claims, and it must not swallow it) or what follows it is.
  if (!look_inside) return "not followed by an event at byte " + std::to_string(end);
  for (uint64_t c = nextSyncAt(at + 1); c < end; c = nextSyncAt(c + 1)) {
    if (problemAt(c, false).empty()) {
      return "event claims " + std::to_string(end - at) + " bytes, but a good event starts " +
             "inside them at byte " + std::to_string(c) + " (a damaged length)";
    }
  }
  return {};
}

bool EventLogReader::readAt(LogEvent* event) {
  if (offset_ >= size_) return false;
  if (const std::string why = problemAt(offset_); !why.empty()) {
    throw LogError(path_, offset_, why);
  }
  const uint8_t* h = view(offset_, 28);
  const uint32_t channel_len = static_cast<uint32_t>(readBE(h + 20, 4));
  const uint32_t data_len = static_cast<uint32_t>(readBE(h + 24, 4));
  event->eventnum = static_cast<int64_t>(readBE(h + 4, 8));
  event->utime = static_cast<int64_t>(readBE(h + 12, 8));
  const uint8_t* channel = view(offset_ + 28, channel_len);
  event->channel.assign(reinterpret_cast<const char*>(channel), channel_len);
  event->data.resize(data_len);
  const uint64_t data_at = offset_ + 28 + channel_len;
  if (data_len > 0) {
    if (const uint8_t* d = data_len <= (1u << 20) ? view(data_at, data_len) : nullptr) {
      std::memcpy(event->data.data(), d, data_len);
    } else {
      std::clearerr(file_);
      if (std::fseek(file_, static_cast<long>(data_at), SEEK_SET) != 0 ||
          std::fread(event->data.data(), 1, data_len, file_) != data_len) {
        throw LogError(path_, offset_, "truncated event body");
      }
    }
  }
  offset_ += 28 + uint64_t{channel_len} + data_len;
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
