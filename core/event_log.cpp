#include "core/event_log.hpp"

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
      offset_(offset) {}

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

bool EventLogReader::next(LogEvent* event) {
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
  writeBE(header + 4, static_cast<uint64_t>(next_eventnum_++), 8);
  writeBE(header + 12, static_cast<uint64_t>(utime), 8);
  writeBE(header + 20, channel.size(), 4);
  writeBE(header + 24, size, 4);
  if (std::fwrite(header, 1, sizeof header, file_) != sizeof header ||
      std::fwrite(channel.data(), 1, channel.size(), file_) != channel.size() ||
      (size && std::fwrite(data, 1, size, file_) != size)) {
    throw std::runtime_error(path_ + ": write failed: " + std::strerror(errno));
  }
}

void EventLogWriter::flush() {
  if (file_) std::fflush(file_);
}

void EventLogWriter::close() {
  if (!file_) return;
  const bool ok = std::fclose(file_) == 0;
  file_ = nullptr;
  if (!ok) throw std::runtime_error(path_ + ": close failed");
}

}  // namespace sweepmap
