// What every lidar protocol decoder shares. A decoder is a pure class: bytes in, events out
// (scans, replies, errors); no I/O and no clock, so the same code runs on a socket, a serial
// port, a capture file or a fuzzer. A false sync byte, a bad checksum or garbage makes it
// resynchronise at the next byte that can start a packet: counted, never fatal, and never a
// good packet lost after the bad bytes.
#pragma once

#include <cstdint>
#include <string>

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

}  // namespace sweepmap
