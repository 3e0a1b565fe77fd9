// A byte capture: what a device sent, in the chunks the host received it in, each with its
// host receive time — enough to decode it later exactly as the driver did live.
//
// File format (little-endian):
//   the text line "SWEEPMAP-CAPTURE 1 <device URI>\n", then records of
//   int64 receive time [us, host clock] | uint32 length | `length` bytes.
// A file without that first line is taken as raw protocol bytes (e.g. from `cat
// /dev/ttyUSB0 > f`, or a vendor's recording) with no receive times.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace sweepmap {

struct CaptureChunk {
  int64_t utime = -1;       // host receive time; -1 in a raw file
  int64_t offset = 0;       // offset of the first byte in the device's byte stream
  int64_t file_offset = 0;  // where the record starts in the file
  std::vector<uint8_t> bytes;
};

struct Capture {
  bool raw = false;  // no header: raw protocol bytes, one chunk
  std::string uri;   // the device, from the header
  std::vector<CaptureChunk> chunks;
  // Non-empty when the file ends inside a record (or a record is implausible): names the
  // file and the byte offset; the chunks before it are all there.
  std::string error;
};

// Throws std::runtime_error when the file cannot be read at all.
Capture readCapture(const std::string& path);

class CaptureWriter {
 public:
  // Creates (truncates) `path` and writes the header. Throws std::runtime_error.
  CaptureWriter(const std::string& path, const std::string& uri);
  ~CaptureWriter();
  CaptureWriter(const CaptureWriter&) = delete;
  CaptureWriter& operator=(const CaptureWriter&) = delete;
  // One record, written through to the kernel at once (a killed capture loses nothing that
  // was received before). Throws std::runtime_error (disk full).
  void append(int64_t utime, const uint8_t* data, size_t size);
  void close();
  int64_t bytes() const { return bytes_; }

 private:
  std::string path_;
  std::FILE* file_ = nullptr;
  int64_t bytes_ = 0;
};

}  // namespace sweepmap
