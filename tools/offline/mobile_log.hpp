// A rig-B log in memory for calibration and evaluation: its valid lidar scans, the poses
// of the odometry process replayed over its raw wheel and IMU messages (EKF and wheels
// alone), and the simulator's truth when present. The world-frame cloud can then be
// assembled again with any mounting without replaying the log.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "calib/mounting_calibration.hpp"
#include "calib/wheel_gyro_calibration.hpp"
#include "calib/world_assembly.hpp"
#include "core/scan.hpp"
#include "rigs/mobile_lidar.hpp"
#include "sweepmap/truth_mobile_rig_t.hpp"
#include "sweepmap/truth_mounting_t.hpp"

namespace sweepmap {

struct MobileLog {
  // Valid scans (validateScan), in log order, on the odometry's clock (their stamps less the
  // rig's lidar.time_offset_s).
  std::vector<Scan2D> scans;
  PoseTrack ekf;                                   // ODOMETRY_POSE, replayed
  PoseTrack wheels;                                // WHEEL_ODOMETRY, replayed
  PoseTrack truth;                                 // TRUTH_POSE from the log (simulation only)
  std::optional<truth_mounting_t> truth_mounting;  // TRUTH_MOUNTING (simulation only)
  std::optional<truth_mobile_rig_t> truth_rig;     // TRUTH_MOBILE_RIG (simulation only)
  double ekf_gyro_bias_rad_s = 0.0;                // the EKF's gyro bias at the end, and its
  double ekf_gyro_bias_sigma_rad_s = 0.0;          //   sigma
  int64_t invalid_scans = 0;
  int64_t gated_wheel_readings = 0;
  bool log_error = false;  // truncated or corrupt: everything before the error is kept
  std::string error;
};

// Reads `path` through the odometry node of `rig`. Throws LogError if the file cannot be
// opened; a corrupt tail sets log_error/error and keeps what came before.
MobileLog loadMobileLog(const std::string& path, const MobileLidarConfig& rig);

// The raw encoder readings (WHEEL_TICKS) and gyro z rates (IMU) of a log, each sorted by its
// device time (a log is in arrival order, which a busy host can swap), for the
// wheels-against-gyro calibration, which integrates the gyro between wheel readings. Throws
// LogError if the file cannot be opened.
struct OdometryReadings {
  std::vector<WheelReading> wheels;
  std::vector<GyroReading> gyro;
};
OdometryReadings loadOdometryReadings(const std::string& path);

// World points of every scan with `track` and the mounting; `scan_of_point`, when given,
// receives the index (into log.scans) of each point's scan.
std::vector<Eigen::Vector3f> assembleWorld(const MobileLog& log, const PoseTrack& track,
                                           const LidarMounting& mounting,
                                           std::vector<int>* scan_of_point = nullptr);

// The mounting the simulator used (truth), from TRUTH_MOUNTING.
LidarMounting trueMounting(const truth_mounting_t& truth);

// A mounting calibration's result for reports, as the text of a JSON object: method, ok
// (reason), gamma/beta/alpha_rad, time_offset_s, track_drift_m_s, residual_before_m/after_m,
// correspondences, iterations, the fast solver's 1-sigma uncertainties from its covariance
// under "sigma" {gamma_rad, beta_rad, alpha_rad, time_offset_s when estimated} and, given the
// truth and a result, error_mrad {gamma, beta, alpha} (estimate minus truth). Text, so that no JSON
// type is in a header; parse it to add keys (numbers read back exactly).
std::string mountingResultJsonText(const MountingCalibrationResult& r,
                                   const std::optional<LidarMounting>& truth = std::nullopt);

}  // namespace sweepmap
