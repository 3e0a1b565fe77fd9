// What every lidar protocol decoder shares. A decoder is a pure class: bytes in, events out
// (scans, replies, errors); no I/O and no clock, so the same code runs on a socket, a serial
// port, a capture file or a fuzzer. A false sync byte, a bad checksum or garbage makes it
// resynchronise at the next byte that can start a packet: counted, never fatal, and never a
// good packet lost after the bad bytes.
#pragma once

#include <cstdint>
#include <optional>
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
  int64_t anomalies = 0;  // packets whose fields disagree, decoded by the vendor's rule (X4: LSA
                          // below FSA off the 360 -> 0 wrap)
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

// What a binary decoder found at its cursor: a packet (or a reply) of `bytes` bytes, taken; a
// start whose rest has not arrived yet (wait for more bytes); or no packet start (the byte is
// skipped, and counted in the decoder's SkippedRun).
struct ParseStep {
  enum Kind { kTake, kWait, kSkip };
  Kind kind = kSkip;
  size_t bytes = 1;
  static ParseStep take(size_t n) { return {kTake, n}; }
  static ParseStep wait() { return {kWait, 0}; }
  static ParseStep skip() { return {kSkip, 1}; }
};

// A packet's start: the sync bytes `s0 s1`, then at least `header` bytes in all. Nothing when
// they are there, else the step to take (skip a byte that is no sync, or wait for the rest).
inline std::optional<ParseStep> expectHeader(const uint8_t* p, size_t left, uint8_t s0, uint8_t s1,
                                             size_t header) {
  if (p[0] != s0) return ParseStep::skip();
  if (left < 2) return ParseStep::wait();
  if (p[1] != s1) return ParseStep::skip();
  if (left < header) return ParseStep::wait();
  return std::nullopt;
}

// The bytes a binary decoder (RPLIDAR, YDLIDAR, HI219, wheel board) has been fed and not yet
// decoded, with the run of bytes it skipped to resynchronise. feed() appends, then a step
// function decodes from the front until it waits for more; what it took or skipped is dropped,
// so at most one unfinished packet is held.
class PacketBuffer {
 public:
  PacketBuffer(std::string name, std::string why) : skipped_(std::move(name), std::move(why)) {}

  // `step(p, left, offset)`: the ParseStep at `p` (`left` bytes from it, at stream `offset`).
  // True when every byte was taken or skipped (then the skipped run can be reported: no
  // packet can start in it any more).
  template <class Step>
  bool feed(const uint8_t* data, size_t size, DecoderCounters* counters, Step step) {
    counters->bytes += static_cast<int64_t>(size);
    buffer_.insert(buffer_.end(), data, data + size);
    return decode(step, false);
  }

  // The input has ended (the end of a file): a start still waiting for its rest will never
  // get it, so it was a false start or a packet cut short. Its first byte is skipped and the
  // bytes after it searched again, so a false sync (say a length field that runs past the
  // end) loses no good packet after it; what is left at the end is reported as skipped.
  template <class Event, class Step>
  void finish(DecoderCounters* counters, std::vector<Event>* out, Step step) {
    decode(step, true);
    skipped_.flush(counters, out);
  }

  // The same, reporting the skipped run at the end when nothing is left.
  template <class Event, class Step>
  void feed(const uint8_t* data, size_t size, DecoderCounters* counters, std::vector<Event>* out,
            Step step) {
    if (feed(data, size, counters, step)) skipped_.flush(counters, out);
  }

  // Reports the run of skipped bytes before the packet about to be emitted.
  template <class Event>
  void flushSkipped(DecoderCounters* counters, std::vector<Event>* out) {
    skipped_.flush(counters, out);
  }
  bool skippedNone() const { return skipped_.empty(); }

  // A packet whose check fails: dropped and counted, and its bytes searched again from the
  // next one (its sync bytes may have been a false start inside other data).
  template <class Event>
  ParseStep dropBadPacket(int64_t offset, std::string what, DecoderCounters* counters,
                          std::vector<Event>* out) {
    skipped_.flush(counters, out);
    ++counters->checksum_errors;
    ++counters->resyncs;
    ++counters->discarded_bytes;
    out->push_back(DecodeError{offset, std::move(what)});
    return ParseStep::take(1);
  }

  void clear() {
    buffer_.clear();
    offset_ = 0;
    skipped_.clear();
  }

 private:
  // Steps from the front until a start waits for more bytes (at the end of the input: skips
  // that start's first byte instead); drops what was taken or skipped.
  template <class Step>
  bool decode(Step step, bool at_end) {
    size_t at = 0;
    while (at < buffer_.size()) {
      const int64_t offset = offset_ + static_cast<int64_t>(at);
      ParseStep s = step(buffer_.data() + at, buffer_.size() - at, offset);
      if (s.kind == ParseStep::kWait) {
        if (!at_end) break;
        s = ParseStep::skip();
      }
      if (s.kind == ParseStep::kSkip) skipped_.skip(offset, s.bytes);
      at += s.bytes;
    }
    buffer_.erase(buffer_.begin(), buffer_.begin() + static_cast<std::ptrdiff_t>(at));
    offset_ += static_cast<int64_t>(at);
    return buffer_.empty();
  }

  std::vector<uint8_t> buffer_;
  int64_t offset_ = 0;  // stream offset of buffer_[0]
  SkippedRun skipped_;
};

}  // namespace sweepmap
