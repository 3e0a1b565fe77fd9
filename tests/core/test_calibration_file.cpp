#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/calibration_file.hpp"
#include "core/config.hpp"
#include "rigs/rotating_lidar.hpp"

namespace sweepmap {
namespace {

namespace fs = std::filesystem;

class CalibrationFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("sweepmap_calib_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(CalibrationFileTest, RoundTripAndNoTemporaryLeft) {
  PlateCalibration c;
  c.alpha_deg = 29.359812345;
  c.source["tool"] = "sweepmap calib plate-angle";
  c.source["date"] = "2026-11-22T04:00:00Z";
  c.logs = {"a.lcmlog", "b.lcmlog"};
  const std::string p = (dir_ / "plate.yaml").string();
  writePlateCalibration(p, c);
  EXPECT_FALSE(fs::exists(p + ".tmp"));
  const PlateCalibration r = loadPlateCalibration(p);
  EXPECT_NEAR(r.alpha_deg, c.alpha_deg, 1e-9);
  EXPECT_EQ(r.logs, c.logs);
  EXPECT_EQ(r.source.at("date"), "2026-11-22T04:00:00Z");
}

TEST_F(CalibrationFileTest, RigFilePointsToCalibration) {
  PlateCalibration c;
  c.alpha_deg = 29.5;
  writePlateCalibration((dir_ / "plate.yaml").string(), c);
  std::ifstream in(std::string(SWEEPMAP_SOURCE_DIR) + "/config/rig_a.yaml");
  std::stringstream text;
  text << in.rdbuf();
  std::string rig = text.str();
  const std::string from = "calibration_file: \"\"";
  rig.replace(rig.find(from, rig.find("plate:")), from.size(), "calibration_file: plate.yaml");
  std::ofstream(dir_ / "rig.yaml") << rig;
  EXPECT_DOUBLE_EQ(loadRotatingLidarConfig((dir_ / "rig.yaml").string()).plate.alpha_deg, 29.5);
  // A missing calibration file is an error naming it.
  fs::remove(dir_ / "plate.yaml");
  try {
    loadRotatingLidarConfig((dir_ / "rig.yaml").string());
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("plate.yaml"), std::string::npos) << e.what();
  }
}

TEST_F(CalibrationFileTest, RejectsBadFiles) {
  const auto write = [&](const std::string& text) {
    std::ofstream(dir_ / "c.yaml") << text;
    return (dir_ / "c.yaml").string();
  };
  EXPECT_THROW(loadPlateCalibration(write("plate: {}\n")), ConfigError);
  EXPECT_THROW(loadPlateCalibration(write("plate: {alpha_deg: abc}\n")), ConfigError);
  EXPECT_THROW(loadPlateCalibration(write("plate: {alpha_deg: 30, beta: 1}\n")), ConfigError);
  EXPECT_THROW(loadPlateCalibration(write("plate: {alpha_deg: 30}\nother: 1\n")), ConfigError);
  EXPECT_THROW(loadPlateCalibration(write("plate: [1\n")), ConfigError);
  EXPECT_NO_THROW(loadPlateCalibration(write("plate: {alpha_deg: 30}\n")));
}

TEST_F(CalibrationFileTest, MountingRoundTripAndNoTemporaryLeft) {
  MountingCalibration c;
  c.gamma_rad = 0.0355123456789;
  c.beta_rad = 0.0126;
  c.alpha_rad = -0.0058;
  c.source["tool"] = "sweepmap calib mounting";
  c.logs = {"circle.lcmlog"};
  const std::string p = (dir_ / "mounting.yaml").string();
  writeMountingCalibration(p, c);
  EXPECT_FALSE(fs::exists(p + ".tmp"));
  const MountingCalibration r = loadMountingCalibration(p);
  EXPECT_NEAR(r.gamma_rad, c.gamma_rad, 1e-12);
  EXPECT_DOUBLE_EQ(r.beta_rad, c.beta_rad);
  EXPECT_DOUBLE_EQ(r.alpha_rad, c.alpha_rad);
  EXPECT_EQ(r.logs, c.logs);
  EXPECT_EQ(r.source.at("tool"), "sweepmap calib mounting");
}

TEST_F(CalibrationFileTest, MountingRejectsBadFilesNamingTheKey) {
  const auto error = [&](const std::string& text) {
    std::ofstream(dir_ / "m.yaml") << text;
    try {
      loadMountingCalibration((dir_ / "m.yaml").string());
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(error("mounting: {gamma_rad: 0, beta_rad: 0}\n").find("mounting.alpha_rad"),
            std::string::npos);
  EXPECT_NE(
      error("mounting: {gamma_rad: x, beta_rad: 0, alpha_rad: 0}\n").find("mounting.gamma_rad"),
      std::string::npos);
  EXPECT_NE(
      error("mounting: {gamma_rad: 0, beta_rad: .nan, alpha_rad: 0}\n").find("mounting.beta_rad"),
      std::string::npos);
  EXPECT_NE(error("mounting: {gamma_rad: 0, beta_rad: 0, alpha_rad: 0, delta_rad: 0}\n")
                .find("mounting.delta_rad"),
            std::string::npos);
  EXPECT_NE(error("plate: {alpha_deg: 30}\n").find("'plate'"), std::string::npos);
  EXPECT_NE(error("mounting: [1\n").find("m.yaml"), std::string::npos);
  EXPECT_EQ(error("mounting: {gamma_rad: 0.01, beta_rad: 0, alpha_rad: -0.02}\n"), "");
}

}  // namespace
}  // namespace sweepmap
