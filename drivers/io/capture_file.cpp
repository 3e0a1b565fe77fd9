#include "drivers/io/capture_file.hpp"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>
#include <stdexcept>

namespace sweepmap {
namespace {

constexpr char kMagic[] = "SWEEPMAP-CAPTURE 1 ";
constexpr size_t kMaxRecord = 64u << 20;  // a single read is never this large

uint64_t readLE(const uint8_t* p, int n) {
  uint64_t v = 0;
  for (int i = n - 1; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}

void writeLE(uint8_t* p, uint64_t v, int n) {
  for (int i = 0; i < n; ++i) p[i] = static_cast<uint8_t>(v >> (8 * i));
}

}  // namespace

Capture readCapture(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open: " + std::strerror(errno));
  const std::vector<uint8_t> data{std::istreambuf_iterator<char>(in),
                                  std::istreambuf_iterator<char>()};
  Capture c;
  const size_t magic = sizeof kMagic - 1;
  if (data.size() < magic || std::memcmp(data.data(), kMagic, magic) != 0) {
    c.raw = true;
    CaptureChunk chunk;
    chunk.bytes = data;
    c.chunks.push_back(std::move(chunk));
    return c;
  }
  size_t at = magic;
  while (at < data.size() && data[at] != '\n') ++at;
  if (at >= data.size()) {
    c.error = path + ": header line not terminated";
    return c;
  }
  c.uri.assign(data.begin() + magic, data.begin() + static_cast<std::ptrdiff_t>(at));
  ++at;
  int64_t stream_offset = 0;
  while (at < data.size()) {
    if (data.size() - at < 12) {
      c.error = path + ": truncated record header at byte " + std::to_string(at);
      break;
    }
    const auto utime = static_cast<int64_t>(readLE(&data[at], 8));
    const uint64_t length = readLE(&data[at + 8], 4);
    if (length > kMaxRecord) {
      c.error = path + ": implausible record length " + std::to_string(length) + " at byte " +
                std::to_string(at);
      break;
    }
    if (data.size() - at - 12 < length) {
      c.error = path + ": truncated record at byte " + std::to_string(at) + " (" +
                std::to_string(length) + " bytes announced, " +
                std::to_string(data.size() - at - 12) + " present)";
      break;
    }
    CaptureChunk chunk;
    chunk.utime = utime;
    chunk.offset = stream_offset;
    chunk.file_offset = static_cast<int64_t>(at);
    chunk.bytes.assign(data.begin() + static_cast<std::ptrdiff_t>(at + 12),
                       data.begin() + static_cast<std::ptrdiff_t>(at + 12 + length));
    stream_offset += static_cast<int64_t>(length);
    c.chunks.push_back(std::move(chunk));
    at += 12 + length;
  }
  return c;
}

CaptureWriter::CaptureWriter(const std::string& path, const std::string& uri) : path_(path) {
  file_ = std::fopen(path.c_str(), "wb");
  if (!file_) throw std::runtime_error(path + ": cannot create: " + std::strerror(errno));
  const std::string header = std::string(kMagic) + uri + "\n";
  if (std::fwrite(header.data(), 1, header.size(), file_) != header.size() ||
      std::fflush(file_) != 0) {
    throw std::runtime_error(path + ": write failed: " + std::strerror(errno));
  }
}

CaptureWriter::~CaptureWriter() {
  if (file_) std::fclose(file_);
}

void CaptureWriter::append(int64_t utime, const uint8_t* data, size_t size) {
  uint8_t head[12];
  writeLE(head, static_cast<uint64_t>(utime), 8);
  writeLE(head + 8, size, 4);
  if (std::fwrite(head, 1, 12, file_) != 12 || std::fwrite(data, 1, size, file_) != size ||
      std::fflush(file_) != 0) {
    throw std::runtime_error(path_ + ": write failed: " + std::strerror(errno));
  }
  bytes_ += static_cast<int64_t>(size);
}

void CaptureWriter::close() {
  if (file_ && std::fclose(file_) != 0) {
    file_ = nullptr;
    throw std::runtime_error(path_ + ": close failed: " + std::strerror(errno));
  }
  file_ = nullptr;
}

}  // namespace sweepmap
