// What every lidar protocol decoder shares. A decoder is a pure class: bytes in, events out
// (scans, replies, errors); no I/O and no clock, so the same code runs on a socket, a serial
// port, a capture file or a fuzzer. A false sync byte, a bad checksum or garbage makes it
// resynchronise at the next byte that can start a packet: counted, never fatal, and never a
// good packet lost after the bad bytes.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace sweepmap {

// One problem in the byte stream, with the offset of its first byte: the number of bytes fed
// to the decoder before it (since construction or the last reset()).
struct DecodeError {
  int64_t offset = 0;
  std::string what;  // names the protocol, the packet and the field, e.g. "SCIP MD reply: ..."
};

// Cumulative since construction or reset(); the lidar process publishes them in its status.
struct DecoderCounters {
  int64_t bytes = 0;            // bytes fed
  int64_t packets = 0;          // well-formed packets / replies decoded
  int64_t scans = 0;            // complete scans emitted
  int64_t checksum_errors = 0;  // packets dropped for a bad checksum
  int64_t resyncs = 0;          // times bytes were skipped to find the next packet start
  int64_t discarded_bytes = 0;  // bytes skipped while resynchronising
  int64_t device_errors = 0;    // replies that carry an error status or bad health
};

// The bytes a decoder skips while it looks for the next packet start: one resync and one
// error per run of consecutive skipped bytes, reported when the run ends ("X: 4 bytes
// skipped to the next frame", at the run's first byte).
class SkippedRun {
 public:
  SkippedRun(std::string name, std::string why) : name_(std::move(name)), why_(std::move(why)) {}
  void skip(int64_t offset, size_t n = 1) {
    if (bytes_ == 0) start_ = offset;
    bytes_ += static_cast<int64_t>(n);
  }
  bool empty() const { return bytes_ == 0; }
  void clear() { bytes_ = 0; }
  template <class Event>
  void flush(DecoderCounters* counters, std::vector<Event>* out) {
    if (bytes_ == 0) return;
    ++counters->resyncs;
    counters->discarded_bytes += bytes_;
    out->push_back(
        DecodeError{start_, name_ + ": " + std::to_string(bytes_) + " bytes skipped " + why_});
    bytes_ = 0;
  }

 private:
  std::string name_, why_;
  int64_t start_ = 0, bytes_ = 0;
};

}  // namespace sweepmap
