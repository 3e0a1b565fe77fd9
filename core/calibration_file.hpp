// Calibration results are config files too: a small YAML file that a rig file points to
// (rig A: plate.calibration_file; rig B: mounting.calibration_file), written atomically by
// the calibration tools.
//
//   plate:
//     alpha_deg: 29.3598          # the calibrated value the assembler uses
//   source:                        # provenance, free-form
//     tool: sweepmap calib plate-angle
//     date: 2026-11-22T04:00:00Z
//     logs: [a.lcmlog, b.lcmlog]
//
//   mounting:                      # rig B (Miao 2022 section 4.2)
//     gamma_rad: 0.0355
//     beta_rad: 0.0126
//     alpha_rad: -0.0058
//   source: {...}                  # as above
//
//   axis_offset:                   # rig C (Zhao 2021): geometry.calibration_file
//     m_mm: 123.0                  # the offsets M, N (core/profile_geometry.hpp)
//     n_mm: 409.0
//     laser_tilt_deg: 0.2
//     encoder_zero_deg: 0          # as given: planes cannot determine it
//   source: {...}                  # as above, with each parameter's standard deviation
//
//   geometry:                      # rig A (t_L^O' by plane constraints): geometry.calibration_file
//     lidar_offset_x_mm: 16.0      # replaces the rig's geometry.lidar_offset_x_mm
//   source: {...}                  # as above, with the standard deviation
#pragma once

#include <map>
#include <string>
#include <vector>

namespace sweepmap {

struct PlateCalibration {
  double alpha_deg = 0.0;
  // Provenance written under `source:` (scalars and the list of logs).
  std::map<std::string, std::string> source;
  std::vector<std::string> logs;
};

// Throws ConfigError naming the file and key when `plate.alpha_deg` is missing or bad, or
// a key other than `plate` and `source` is present.
PlateCalibration loadPlateCalibration(const std::string& path);

// Writes to `path.tmp`, then renames over `path`. Throws std::runtime_error on failure.
void writePlateCalibration(const std::string& path, const PlateCalibration& calibration);

struct MountingCalibration {
  double gamma_rad = 0.0;  // about body x
  double beta_rad = 0.0;   // about body y
  double alpha_rad = 0.0;  // about body z
  std::map<std::string, std::string> source;
  std::vector<std::string> logs;
};

// Same rules as the plate's: `mounting.{gamma,beta,alpha}_rad` required and finite, only
// `mounting` and `source` at the top.
MountingCalibration loadMountingCalibration(const std::string& path);
void writeMountingCalibration(const std::string& path, const MountingCalibration& calibration);

struct AxisOffsetCalibration {
  double m_mm = 0.0;
  double n_mm = 0.0;
  double laser_tilt_deg = 0.0;
  double encoder_zero_deg = 0.0;
  std::map<std::string, std::string> source;
  std::vector<std::string> logs;
};

// Same rules: `axis_offset.{m_mm,n_mm,laser_tilt_deg,encoder_zero_deg}` required and finite.
AxisOffsetCalibration loadAxisOffsetCalibration(const std::string& path);
void writeAxisOffsetCalibration(const std::string& path, const AxisOffsetCalibration& calibration);

// Rig A's lidar-to-axis offset (t_L^O' = (x, 0, 0), Yuan 2021 Eq. 5-6).
struct LidarOffsetCalibration {
  double lidar_offset_x_mm = 0.0;
  std::map<std::string, std::string> source;
  std::vector<std::string> logs;
};

// Same rules: `geometry.lidar_offset_x_mm` required and finite, only `geometry` and `source`.
LidarOffsetCalibration loadLidarOffsetCalibration(const std::string& path);
void writeLidarOffsetCalibration(const std::string& path,
                                 const LidarOffsetCalibration& calibration);

// A whole rig's calibration (sweepmap calib rig): rig-file keys with their calibrated values,
// applied over the rig file's own by its top-level `calibration_file` key (relative to the rig
// file). Rig-neutral: the keys are whatever the rig kind's schema has.
//
//   parameters:
//     plate.alpha_deg: 29.3598
//     geometry.lidar_offset_x_mm: 13.9
//   source: {...}                  # as above, with each parameter's sigma
struct RigCalibrationFile {
  std::vector<std::pair<std::string, double>> parameters;  // in the order written
  std::map<std::string, std::string> source;
  std::vector<std::string> logs;
};

// Throws ConfigError naming the file and key when `parameters` is missing or empty, a value
// is not a finite number, or a top-level key other than `parameters` and `source` is present.
RigCalibrationFile loadRigCalibration(const std::string& path);
void writeRigCalibration(const std::string& path, const RigCalibrationFile& calibration);

}  // namespace sweepmap
