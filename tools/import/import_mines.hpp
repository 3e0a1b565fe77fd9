// Converts a BreezySLAM / CoreSLAM "Mines" data file (e.g. examples/exp2.dat) into an LCM
// log of raw messages with the original timestamps: WHEEL_TICKS (wheel_ticks_t) and
// LIDAR_SCAN (lidar_scan_t) for its Hokuyo URG-04LX.
//
// Line format, as the original loader (BreezySLAM examples/mines.py, load_data) reads it:
// whitespace-separated tokens, the last one ignored; token 0 the timestamp [us], tokens 2
// and 3 the left and right wheel encoder counts, tokens 24.. the ranges [mm] (0 = none).
#pragma once

#include <cstdint>
#include <string>

namespace sweepmap {

struct BreezySlamImport {
  int64_t lines = 0;
  int64_t scans = 0;
  int beams = 0;  // ranges per scan
  int64_t first_utime = 0, last_utime = 0;
};

// URG-04LX geometry (1024 steps per turn, 10 Hz; the file's 682 ranges span about 240 deg).
constexpr double kUrg04lxStepRad = 2.0 * 3.14159265358979323846 / 1024.0;
constexpr double kUrg04lxScanPeriodS = 0.1;
constexpr double kUrg04lxRangeMinM = 0.02;
constexpr double kUrg04lxRangeMaxM = 5.6;

// Throws std::runtime_error naming the file, line and token on malformed input; lines
// written before the error stay in the output (it is closed properly).
BreezySlamImport importBreezySlam(const std::string& in_path, const std::string& out_log);

}  // namespace sweepmap
