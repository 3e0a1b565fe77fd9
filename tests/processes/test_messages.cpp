// Encoding and decoding of the message types, including into value-initialised structs:
// LCM 1.3.1 decodes doubles through int64_t pointers, which needs -fno-strict-aliasing
// (lcmtypes/CMakeLists.txt); without it this test reads back zeros at -O2.
#include <gtest/gtest.h>

#include <cmath>

#include "processes/node.hpp"
#include "sweepmap/cloud_chunk_t.hpp"
#include "sweepmap/lidar_scan_t.hpp"
#include "sweepmap/profile_t.hpp"
#include "sweepmap/scan_window_t.hpp"
#include "sweepmap/truth_sweep_t.hpp"

namespace sweepmap {
namespace {

template <class T>
T roundTrip(const T& in) {
  Outbox o;
  o.publish("X", 0, in);
  T out{};
  EXPECT_TRUE(decodeMessage(o.take().front(), &out));
  return out;
}

TEST(Messages, DoublesAndFloatsSurviveDecodingIntoFreshStructs) {
  truth_sweep_t t{};
  t.sweep_id = 3;
  t.phi_offset_true_rad = -0.0450773;
  t.alpha_true_rad = 0.512425;
  const truth_sweep_t r = roundTrip(t);
  EXPECT_EQ(r.sweep_id, 3);
  EXPECT_EQ(r.phi_offset_true_rad, -0.0450773);
  EXPECT_EQ(r.alpha_true_rad, 0.512425);

  scan_window_t w{};
  w.angular_velocity_rad_s = M_PI / 16;
  w.sweep_angle_rad = M_PI;
  EXPECT_EQ(roundTrip(w).angular_velocity_rad_s, M_PI / 16);

  lidar_scan_t s{};
  s.angle_increment_rad = 0.0043633f;
  s.ranges_m = {1.5f, 0.0f, 2.25f};
  s.nranges = 3;
  const lidar_scan_t rs = roundTrip(s);
  EXPECT_EQ(rs.angle_increment_rad, 0.0043633f);
  EXPECT_EQ(rs.ranges_m, s.ranges_m);

  cloud_chunk_t c{};
  c.xyz_m = {{1.0f, 2.0f, 3.0f}};
  c.npoints = 1;
  c.phi_offset_rad = 0.01;
  EXPECT_EQ(roundTrip(c).xyz_m, c.xyz_m);
  EXPECT_EQ(roundTrip(c).phi_offset_rad, 0.01);
}

TEST(Messages, ScanIntensitiesAnglesAndDeviceStampRoundTrip) {
  lidar_scan_t s{};
  s.ranges_m = {1.5f, 0.0f};
  s.nranges = 2;
  s.device_stamp = 16777215;
  s.intensities = {1200.0f, 0.0f};
  s.nintensities = 2;
  s.angles_rad = {-0.5f, 0.25f};
  s.nangles = 2;
  const lidar_scan_t r = roundTrip(s);
  EXPECT_EQ(r.device_stamp, 16777215);
  EXPECT_EQ(r.intensities, s.intensities);
  EXPECT_EQ(r.angles_rad, s.angles_rad);
}

// A hostile count in either trailing array is refused before LCM would allocate it.
TEST(Messages, ScanWithHugeTrailingCountIsRefused) {
  lidar_scan_t s{};
  s.ranges_m = {1.5f};
  s.nranges = 1;
  Outbox o;
  o.publish("X", 0, s);
  Message m = o.take().front();
  const size_t at_nintensities = 48 + 4 + 8;
  ASSERT_EQ(m.data.size(), at_nintensities + 4 + 4);
  lidar_scan_t out{};
  ASSERT_TRUE(decodeMessage(m, &out));
  Message bad = m;
  bad.data[at_nintensities] = 0x7f;  // nintensities = 2^31 - something
  EXPECT_FALSE(decodeMessage(bad, &out));
  bad = m;
  bad.data[at_nintensities + 4] = 0x40;  // nangles
  EXPECT_FALSE(decodeMessage(bad, &out));
}

// The codec takes exactly one whole message: a byte short or a byte over is refused.
TEST(Messages, CodecRefusesShortAndTrailingBytes) {
  profile_t p{};
  p.counts_per_revolution = 262144;
  p.column_count = 1280;
  p.point_count = 1;
  p.column = {7};
  p.y_mm = {1.5f};
  p.z_mm = {-2.5f};
  std::vector<uint8_t> bytes = encodeMessage(p);
  ASSERT_EQ(bytes.size(), 48u + 10u);  // as lcmtypes/profile_t.lcm lays it out
  profile_t out{};
  ASSERT_TRUE(decodeMessage(bytes.data(), bytes.size(), &out));
  EXPECT_EQ(out.column, p.column);
  EXPECT_EQ(out.z_mm, p.z_mm);
  EXPECT_FALSE(decodeMessage(bytes.data(), bytes.size() - 1, &out));
  bytes.push_back(0);
  EXPECT_FALSE(decodeMessage(bytes.data(), bytes.size(), &out));
}

}  // namespace
}  // namespace sweepmap
