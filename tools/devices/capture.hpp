// `sweepmap capture` and `sweepmap decode`: a device's raw byte stream to a file and back to
// LIDAR_SCAN messages, with the live driver's code (drivers/lidar_sessions.hpp).
#pragma once

#include <cstdint>
#include <iosfwd>
#include <string>

#include "core/rig_components.hpp"
#include "drivers/real_lidar.hpp"

namespace sweepmap {

struct CaptureOptions {
  std::string uri;  // scip://..., ydlidar:///dev/..., rplidar:///dev/...
  double seconds = 10.0;
  std::string out;  // capture file (drivers/io/capture_file.hpp)
};

// Connects as the driver does (identify, check against `expected`, start streaming) and
// records every byte received, with receive times, for `seconds` after the first byte.
// Returns 0, or 1 when no byte came. Throws std::runtime_error for a bad URI or file.
int runCapture(const CaptureOptions& options, const LidarConfig& expected, std::ostream& report);

struct DecodeOptions {
  std::string protocol;  // scip | x4 | rplidar
  std::string in;        // a capture, or raw protocol bytes
  std::string out;       // LCM log of LIDAR_SCAN
  int baud = 0;          // raw serial bytes: the line rate their times derive from (0 = default)
};

struct DecodeResult {
  int64_t bytes = 0, scans = 0, errors = 0;  // scans: messages written (scans, IMU samples, ...)
  std::string file_error;                    // the capture ends in a broken record (its offset)
  DecoderCounters counters;                  // the decoder's (packets, checksum errors, skips)
  LidarSession::Counters session;            // the session's (360° lidars: samples, turns)
};

// Decodes `in` as the driver would have; every problem is reported with its byte offset in
// the device's stream, then what was found: messages, packets, samples and turns, checksum
// errors, resyncs and the bytes skipped. Scans go to `out` as LIDAR_SCAN (log time = scan
// time).
DecodeResult runDecode(const DecodeOptions& options, const LidarConfig& expected,
                       std::ostream& report);

}  // namespace sweepmap
