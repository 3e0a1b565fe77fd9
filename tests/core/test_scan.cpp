#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/scan.hpp"

namespace sweepmap {
namespace {

Scan2D goodScan() {
  Scan2D s;
  s.utime = 1000;
  s.angle_min_rad = -2.0;
  s.angle_increment_rad = 0.01;
  s.time_increment_ns = 17361;
  s.range_min_m = 0.06;
  s.range_max_m = 10.0;
  s.ranges_m.assign(5, 2.0f);
  s.ranges_m[1] = 0.0f;  // no return
  return s;
}

TEST(ValidateScan, AcceptsGoodScan) { EXPECT_EQ(validateScan(goodScan(), 5), ""); }

TEST(ValidateScan, RejectsWrongLength) {
  EXPECT_NE(validateScan(goodScan(), 6).find("wrong length"), std::string::npos);
}

// One turn of a 360° lidar carries its own angles and as many samples as the turn had: the
// rig's ray count is not its length; its angles must still match its ranges.
TEST(ValidateScan, ATurnWithItsOwnAnglesHasItsOwnLength) {
  Scan2D s = goodScan();
  s.angles_rad = {0.1f, 0.2f, 0.3f, 0.4f, 0.5f};
  EXPECT_EQ(validateScan(s, 714), "");
  s.angles_rad.pop_back();
  EXPECT_NE(validateScan(s, 714).find("wrong length"), std::string::npos);
}

TEST(ValidateScan, RejectsNonFiniteAndOutOfRange) {
  Scan2D s = goodScan();
  s.ranges_m[3] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_NE(validateScan(s, 5).find("ray 3"), std::string::npos);
  s = goodScan();
  s.ranges_m[2] = std::numeric_limits<float>::infinity();
  EXPECT_NE(validateScan(s, 5), "");
  s = goodScan();
  s.ranges_m[2] = -1.0f;
  EXPECT_NE(validateScan(s, 5), "");
  s = goodScan();
  s.ranges_m[2] = 1e6f;
  EXPECT_NE(validateScan(s, 5), "");
  s = goodScan();
  s.angle_increment_rad = std::nan("");
  EXPECT_NE(validateScan(s, 5), "");
}

TEST(Scan2D, RayTiming) {
  const Scan2D s = goodScan();
  EXPECT_EQ(s.rayUtime(0), 1000);
  EXPECT_EQ(s.rayUtime(1000), 1000 + 17361);
  EXPECT_DOUBLE_EQ(s.rayAngle(2), -1.98);
}

}  // namespace
}  // namespace sweepmap
