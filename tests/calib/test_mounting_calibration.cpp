// Mounting calibration (calib/mounting_calibration.hpp) on synthetic drives of the rig-B
// simulator: noise-free circle with the true poses as the track -> both methods recover the
// simulator's true (gamma, beta, alpha); an injected lidar time offset is recovered; too
// little data is refused with a reason.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <iostream>

#include "calib/mounting_calibration.hpp"
#include "sim/mobile.hpp"

namespace sweepmap {
namespace {

constexpr int64_t kStart = 1'000'000;

// A noise-free drive in the lab (config/scene_lab.yaml) with the lidar of config/rig_b.yaml
// (vertical, 0.1 m ahead of the axle, 0.3 m up) and the simulator's true mounting error.
class NoiseFreeDrive : public ::testing::Test {
 protected:
  static SimMobileConfig quiet() {
    SimMobileConfig c;
    c.encoder_speed_sigma_fraction = 0.0;
    c.slip_mean_interval_s = 0.0;
    c.gyro_sigma_rad_s = 0.0;
    c.gyro_bias_z_rad_s = 0.0;
    c.accel_sigma_m_s2 = 0.0;
    c.attitude_sigma_deg = 0.0;
    c.range_sigma_fraction = 0.0;
    // No build errors either: the track is the truth and the lidar where the rig says.
    c.wheel_radius_left_error_fraction = c.wheel_radius_right_error_fraction = 0.0;
    c.wheel_distance_error_m = 0.0;
    c.lever_error_x_m = c.lever_error_y_m = c.lever_error_z_m = 0.0;
    c.lidar_time_offset_ms = 0.0;
    c.switchArtefactsOff();  // nor the scene's artefacts
    return c;
  }

  // Scans and the true body poses in W as the track.
  void drive(const SimMobileConfig& c) {
    const Scene scene(loadScene(std::string(SWEEPMAP_SOURCE_DIR) + "/config/scene_lab.yaml"),
                      PlateConfig{});
    SimMobile car(c, WheelGeometry{}, Eigen::Vector3d::Zero(), kLidarPos, scene, 7, kStart);
    scans_ = car.scans();
    for (const TruthPose& t : car.truth()) track_.add(t.utime, t.pose);
    truth_ = {c.gamma_true_rad, c.beta_true_rad, c.alpha_true_rad};
  }

  LidarMounting initial() const {
    LidarMounting m;
    m.t_BL_m = kLidarPos;
    return m;  // nominal vertical, no error: the calibration starts from zero
  }

  void expectTruth(const MountingCalibrationResult& r, double tol_rad) const {
    ASSERT_TRUE(r.ok) << r.reason;
    std::cerr << mountingMethodName(r.method) << ": error gamma " << r.gamma_rad - truth_[0]
              << ", beta " << r.beta_rad - truth_[1] << ", alpha " << r.alpha_rad - truth_[2]
              << " rad, time offset " << r.time_offset_s << " s, residual " << r.residual_before_m
              << " -> " << r.residual_after_m << " m, " << r.correspondences << " correspondences, "
              << r.iterations << " iterations\n";
    EXPECT_NEAR(r.gamma_rad, truth_[0], tol_rad);
    EXPECT_NEAR(r.beta_rad, truth_[1], tol_rad);
    EXPECT_NEAR(r.alpha_rad, truth_[2], tol_rad);
    EXPECT_LT(r.residual_after_m, r.residual_before_m);
  }

  const Eigen::Vector3d kLidarPos{0.10, 0.0, 0.30};
  std::vector<Scan2D> scans_;
  PoseTrack track_;
  std::array<double, 3> truth_{};
};

TEST_F(NoiseFreeDrive, PointToPlaneRecoversMountingTo1e6Rad) {
  SimMobileConfig c = quiet();
  c.duration_s = 32.0;  // a bit more than a lap: every direction seen by both halves
  drive(c);
  MountingCalibrationOptions o;
  o.method = MountingMethod::kPointToPlane;
  o.range_noise_fraction = 0.0;  // the data's: flat means flat, residuals beyond 0.1 mm are edges
  const MountingCalibrationResult r = calibrateMounting(scans_, track_, initial(), o);
  expectTruth(r, 1e-6);
  EXPECT_EQ(r.method, MountingMethod::kPointToPlane);
  EXPECT_GT(r.correspondences, 1000);
  EXPECT_LT(r.residual_after_m, 1e-5);
  EXPECT_GT(r.residual_before_m, 1e-3);
  EXPECT_EQ(r.time_offset_s, 0.0);

  // Deterministic: the same input gives the same numbers.
  const MountingCalibrationResult again = calibrateMounting(scans_, track_, initial(), o);
  EXPECT_EQ(again.gamma_rad, r.gamma_rad);
  EXPECT_EQ(again.beta_rad, r.beta_rad);
  EXPECT_EQ(again.alpha_rad, r.alpha_rad);
  EXPECT_EQ(again.correspondences, r.correspondences);
}

// The fast solver's result does not depend on its number of threads (chunks reduced in a
// fixed order), and agrees with the reference solver's on the same drive.
TEST_F(NoiseFreeDrive, FastSolverIsTheSameOnAnyNumberOfThreadsAndAgreesWithTheReference) {
  SimMobileConfig c = quiet();
  c.duration_s = 32.0;
  drive(c);
  MountingCalibrationOptions o;
  o.range_noise_fraction = 0.0;
  o.threads = 1;
  const MountingCalibrationResult one = calibrateMounting(scans_, track_, initial(), o);
  o.threads = 3;
  const MountingCalibrationResult three = calibrateMounting(scans_, track_, initial(), o);
  ASSERT_TRUE(one.ok) << one.reason;
  EXPECT_EQ(one.gamma_rad, three.gamma_rad);
  EXPECT_EQ(one.beta_rad, three.beta_rad);
  EXPECT_EQ(one.alpha_rad, three.alpha_rad);
  EXPECT_EQ(one.correspondences, three.correspondences);
  EXPECT_EQ(one.residual_after_m, three.residual_after_m);
  o.reference_solver = true;
  o.threads = 0;
  const MountingCalibrationResult reference = calibrateMounting(scans_, track_, initial(), o);
  EXPECT_NEAR(one.gamma_rad, reference.gamma_rad, 2e-6);
  EXPECT_NEAR(one.beta_rad, reference.beta_rad, 2e-6);
  EXPECT_NEAR(one.alpha_rad, reference.alpha_rad, 2e-6);
}

TEST_F(NoiseFreeDrive, PaperPointsFromTheTargetsEdgesRecoverGamma) {
  SimMobileConfig c = quiet();
  c.duration_s = 32.0;
  drive(c);
  MountingCalibrationOptions o;
  o.method = MountingMethod::kPaperPoints;
  const MountingCalibrationResult r = calibrateMounting(scans_, track_, initial(), o);
  ASSERT_TRUE(r.ok) << r.reason;
  EXPECT_EQ(r.method, MountingMethod::kPaperPoints);
  EXPECT_GE(r.correspondences, 4);
  EXPECT_LT(r.residual_after_m, 0.2 * r.residual_before_m);
  // The board's edge points lie on its horizontal top and bottom edges, paired with the
  // nearest edge point of the other pass: gamma (the scan plane's tilt in itself moves the
  // edges up and down) is recovered to below a milliradian (measured 0.6 mrad); beta and
  // alpha move the points along the edges, where the pairs are quantised by the scan
  // spacing on the board (6.5 cm), and are not (measured 20 and 15 mrad off).
  EXPECT_NEAR(r.gamma_rad, truth_[0], 1e-3);
}

TEST_F(NoiseFreeDrive, TimeOffsetRecoveredWhenInjected) {
  // On a circle at constant speed a time offset only turns the whole cloud about the
  // circle's centre (both passes alike): unobservable. On the lab loop the straights run
  // both ways, so a late lidar clock shifts the two passes apart.
  SimMobileConfig c = quiet();
  c.path = "loop";
  c.speed_m_s = 0.5;
  c.duration_s = 55.0;
  drive(c);
  constexpr int64_t kLidarLateUs = 20'000;  // lidar stamps 20 ms late
  for (Scan2D& s : scans_) s.utime += kLidarLateUs;
  MountingCalibrationOptions o;
  o.method = MountingMethod::kPointToPlane;
  o.estimate_time_offset = true;
  o.ray_stride = 3;
  o.range_noise_fraction = 0.002;  // flatness tolerant of the first rounds' misalignment
  o.trim_sigmas = 3.0;             // then edge points trimmed by the residuals' spread
  const MountingCalibrationResult r = calibrateMounting(scans_, track_, initial(), o);
  // Measured: 2e-5 rad in alpha, 24 us in the offset (alpha and the offset are correlated).
  expectTruth(r, 5e-5);
  EXPECT_NEAR(r.time_offset_s, -kLidarLateUs * 1e-6, 5e-5);
}

TEST_F(NoiseFreeDrive, TrackDriftEstimatedWhenInjected) {
  // Odometry drifts slowly (wheel-speed noise, slip): the two passes of a place are seen
  // from positions a few millimetres apart, the shift alpha is seen by (1.7 mm/mrad).
  SimMobileConfig c = quiet();
  c.duration_s = 32.0;
  drive(c);
  constexpr double kVx = 2e-4, kVy = -1e-4;  // m/s: 6 and 3 mm over the drive
  PoseTrack drifting;
  for (const auto& [t, p] : track_.poses()) {
    Pose2 q = p;
    const double s = double(t - kStart) * 1e-6;
    q.x_m += kVx * s;
    q.y_m += kVy * s;
    drifting.add(t, q);
  }
  MountingCalibrationOptions o;
  o.method = MountingMethod::kPointToPlane;
  o.range_noise_fraction = 0.0;  // the data's (as above)
  const MountingCalibrationResult plain = calibrateMounting(scans_, drifting, initial(), o);
  ASSERT_TRUE(plain.ok) << plain.reason;
  std::cerr << "without drift: alpha error " << plain.alpha_rad - truth_[2] << ", beta error "
            << plain.beta_rad - truth_[1] << " rad\n";
  EXPECT_GT(std::abs(plain.alpha_rad - truth_[2]), 5e-4);  // measured 1.1 mrad
  o.estimate_track_drift = true;
  const MountingCalibrationResult r = calibrateMounting(scans_, drifting, initial(), o);
  std::cerr << "drift " << r.drift_x_m_s << ", " << r.drift_y_m_s << " m/s\n";
  expectTruth(r, 5e-6);  // measured 5e-7 rad
  EXPECT_NEAR(r.drift_x_m_s, kVx, 1e-6);
  EXPECT_NEAR(r.drift_y_m_s, kVy, 1e-6);
}

TEST_F(NoiseFreeDrive, TooLittleDataIsRefusedWithAReason) {
  SimMobileConfig c = quiet();
  c.duration_s = 4.0;  // not even a quarter turn: no second pass
  drive(c);
  for (MountingMethod m : {MountingMethod::kPointToPlane, MountingMethod::kPaperPoints}) {
    MountingCalibrationOptions o;
    o.method = m;
    const MountingCalibrationResult r = calibrateMounting(scans_, track_, initial(), o);
    EXPECT_FALSE(r.ok) << mountingMethodName(m);
    EXPECT_FALSE(r.reason.empty());
    EXPECT_EQ(r.method, m);
  }
  // Enough time but no overlap: a pass gap longer than the drive.
  SimMobileConfig c2 = quiet();
  c2.duration_s = 12.0;
  scans_.clear();
  track_ = PoseTrack();
  drive(c2);
  MountingCalibrationOptions o;
  const MountingCalibrationResult r = calibrateMounting(scans_, track_, initial(), o);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.reason.find("overlap"), std::string::npos) << r.reason;
  // No scans at all.
  EXPECT_FALSE(calibrateMounting({}, track_, initial(), o).ok);
}

}  // namespace
}  // namespace sweepmap
