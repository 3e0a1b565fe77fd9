// LAS 1.4 point cloud files (ASPRS LAS Specification 1.4 - R15), written by hand: Debian 12
// packages no LAS library. Point data record format 6 (30 bytes: X, Y, Z as scaled int32,
// intensity, return 1 of 1, GPS time), no variable length records; the header carries the
// 64-bit point counts and zeros in the legacy 32-bit ones (as R15 requires for formats 6-10),
// the scales, offsets and bounds. Written atomically; the same points give the same bytes.
// Also a reader of binary little-endian PLY vertices, the input of `sweepmap export las`.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace sweepmap {

struct LasPoint {
  double x = 0, y = 0, z = 0;  // [m]
  double gps_time = 0;         // adjusted standard GPS time [s] (GPS time - 1e9)
  uint16_t intensity = 0;
};

struct LasOptions {
  double scale_m = 1e-4;  // 0.1 mm per count
  std::string software = "sweepmap";
  // File creation day of year (1..366) and year from this time [Unix s]; <= 0: both 0 (unknown)
  int64_t creation_unix_s = 0;
};

// Header fields a reader needs, as written (for tests and the command's report).
struct LasSummary {
  uint64_t points = 0;
  double min[3] = {0, 0, 0}, max[3] = {0, 0, 0};
  double offset[3] = {0, 0, 0};
  uint64_t bytes = 0;
};

// Throws std::runtime_error naming `path` (unwritable file, non-finite point, a point beyond
// the int32 range of the scale around the offset).
LasSummary writeLas14(const std::string& path, const std::vector<LasPoint>& points,
                      const LasOptions& options = {});

// Adjusted standard GPS time of a Unix time [s]: GPS epoch 1980-01-06, 18 leap seconds (the
// count since 2017-01-01), minus 1e9 as LAS's "adjusted standard GPS time".
double adjustedGpsTime(double unix_s);

// A lidar's intensity (lidar_scan_t's device units, e.g. the UST's reflectance) as LAS's
// 16-bit intensity: rounded to the nearest count and clipped to 0..65535, so a reading keeps
// its value up to 65535 (a UST's or the simulated lidar's readings of a room stay below that);
// negative or NaN gives 0. LAS 1.4 leaves the scale to the writer; this one is the identity.
uint16_t lasIntensity(double device_units);

// The vertices of a binary little-endian PLY: x, y, z (float or double), and, when present,
// intensity ("intensity" or "scalar_intensity", through lasIntensity) and GPS time ("gps_time" or
// "scalar_gps_time"). Throws std::runtime_error naming the file and what is wrong.
std::vector<LasPoint> readPlyVertices(const std::string& path);

}  // namespace sweepmap
