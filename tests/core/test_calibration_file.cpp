#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
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

std::string readBytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

// The bytes every kind writes, as the tools wrote them before the kinds shared one writer: a
// calibration file is a config file under version control, so its text must not drift.
TEST_F(CalibrationFileTest, EveryKindWritesTheSameBytesAsBefore) {
  const std::map<std::string, std::string> source{
      {"tool", "sweepmap calib"}, {"date", "2026-11-22T04:00:00Z"}, {"seed", "7"}};
  const std::vector<std::string> logs{"a.lcmlog", "b.lcmlog"};
  const std::string provenance =
      "source:\n  date: 2026-11-22T04:00:00Z\n  seed: 7\n  tool: sweepmap calib\n"
      "  logs:\n    - a.lcmlog\n    - b.lcmlog\n";

  PlateCalibration plate;
  plate.alpha_deg = 29.359812345;
  plate.source = source;
  plate.logs = logs;
  const std::string p = (dir_ / "plate.yaml").string();
  writePlateCalibration(p, plate);
  EXPECT_EQ(readBytes(p),
            "# Plate-angle calibration (Yuan 2021 Algorithm A1); read via "
            "plate.calibration_file\nplate:\n  alpha_deg: 29.359812345\n" +
                provenance);

  MountingCalibration mounting;
  mounting.gamma_rad = 0.0355;
  mounting.beta_rad = -0.0126;
  mounting.alpha_rad = 1e-7;
  mounting.source = source;
  mounting.logs = logs;
  const std::string m = (dir_ / "mounting.yaml").string();
  writeMountingCalibration(m, mounting);
  EXPECT_EQ(readBytes(m),
            "# Lidar mounting calibration (Miao 2022 section 4.2); read via "
            "mounting.calibration_file\nmounting:\n  gamma_rad: 0.0355\n  beta_rad: -0.0126\n"
            "  alpha_rad: 1e-07\n" +
                provenance);

  AxisOffsetCalibration axis;
  axis.m_mm = 123.0;
  axis.n_mm = 409.123456789012;
  axis.laser_tilt_deg = 0.2;
  axis.source = source;
  const std::string a = (dir_ / "axis.yaml").string();
  writeAxisOffsetCalibration(a, axis);
  EXPECT_EQ(readBytes(a),
            "# Axis-offset calibration of a rotating profile sensor (Zhao 2021, plane "
            "constraints); read via geometry.calibration_file\naxis_offset:\n  m_mm: 123\n"
            "  n_mm: 409.123456789\n  laser_tilt_deg: 0.2\n  encoder_zero_deg: 0\nsource:\n"
            "  date: 2026-11-22T04:00:00Z\n  seed: 7\n  tool: sweepmap calib\n  logs:\n    []\n");

  LidarOffsetCalibration lidar;
  lidar.lidar_offset_x_mm = 16.0;
  lidar.logs = {"only.lcmlog"};
  const std::string l = (dir_ / "lidar.yaml").string();
  writeLidarOffsetCalibration(l, lidar);
  EXPECT_EQ(readBytes(l),
            "# Lidar-to-axis offset of a rotating 2D lidar (t_L^O', plane constraints); read via "
            "geometry.calibration_file\ngeometry:\n  lidar_offset_x_mm: 16\nsource:\n  logs:\n"
            "    - only.lcmlog\n");
}

}  // namespace
}  // namespace sweepmap
