// LCM channel names, with their types: docs/reference/channels.md is generated from this file.
#pragma once

namespace sweepmap {
// LCM's default multicast group with ttl=0 (this host only) and a 2 MiB receive buffer, so a
// burst of cloud chunks is not dropped by the kernel (LCM 1.3.1 leaves the system default,
// ~208 kB). Reaching another host (Pi -> laptop) needs ttl=1 and a multicast route.
constexpr const char* kDefaultLcmUrl = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=2097152";

namespace channels {

constexpr const char* kLidarScan = "LIDAR_SCAN";      // lidar_scan_t, raw
constexpr const char* kMotorState = "MOTOR_STATE";    // motor_state_t
constexpr const char* kMotorSwitch = "MOTOR_SWITCH";  // switch_event_t, raw
constexpr const char* kScanWindow = "SCAN_WINDOW";    // scan_window_t
constexpr const char* kSweepCloud = "SWEEP_CLOUD";    // cloud_chunk_t
constexpr const char* kSweepStatus = "SWEEP_STATUS";  // sweep_status_t
constexpr const char* kMapStats = "MAP_STATS";        // map_stats_t
constexpr const char* kMapSave = "MAP_SAVE";          // map_save_t
constexpr const char* kMapUpdate =
    "MAP_UPDATE";  // map_update_t, the voxels each map update made occupied or freed
constexpr const char* kWheelTicks = "WHEEL_TICKS";        // wheel_ticks_t, raw (rig B)
constexpr const char* kImu = "IMU";                       // imu_t, raw (rig B)
constexpr const char* kWheelCmd = "WHEEL_CMD";            // wheel_cmd_t, to the wheel board
constexpr const char* kOdometryPose = "ODOMETRY_POSE";    // pose2d_t, EKF
constexpr const char* kWheelOdometry = "WHEEL_ODOMETRY";  // pose2d_t, wheels alone
constexpr const char* kTruthShaft = "TRUTH_SHAFT";        // truth_shaft_t, simulation only
constexpr const char* kTruthRig = "TRUTH_RIG";            // truth_rig_t, simulation only
constexpr const char* kTruthRigErrors =
    "TRUTH_RIG_ERRORS";  // truth_rig_errors_t, simulation only (rig A's build errors)
constexpr const char* kTruthSweep = "TRUTH_SWEEP";  // truth_sweep_t, simulation only
constexpr const char* kTruthPose =
    "TRUTH_POSE";  // pose2d_t, true body pose (rig B simulation only)
constexpr const char* kTruthMounting =
    "TRUTH_MOUNTING";  // truth_mounting_t (rig B simulation only)
constexpr const char* kTruthMobileRig =
    "TRUTH_MOBILE_RIG";  // truth_mobile_rig_t (rig B simulation only): wheels, lever, clocks
constexpr const char* kProfile = "PROFILE";  // profile_t, raw (rig C): one profile + encoder
constexpr const char* kTruthProfileRig =
    "TRUTH_PROFILE_RIG";  // truth_profile_rig_t (rig C simulation only), per sweep
constexpr const char* kTruthTestPiece =
    "TRUTH_TEST_PIECE";  // truth_test_piece_t (rig C simulation only), test-piece sweep
// Health: STATUS_<PROCESS> (process_status_t), e.g. STATUS_ASSEMBLER.

}  // namespace channels
}  // namespace sweepmap
