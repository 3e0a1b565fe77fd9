// The stamp guard on its own: a stream's offset, a single message far off refused, a real
// jump accepted once confirmed, channels that are no time series passed.
#include <gtest/gtest.h>

#include "processes/stamp_guard.hpp"

namespace sweepmap {
namespace {

constexpr int64_t kS = 1'000'000;

TEST(StampGuard, AStreamWithAConstantOffsetPassesWhateverTheOffset) {
  StampGuard g;
  std::string why;
  // A log played by lcm-logplayer: stamps from last year, arriving now.
  for (int64_t k = 0; k < 100; ++k) {
    EXPECT_TRUE(
        g.admit("LIDAR_SCAN", 1000 * kS + 25000 * k, 9000000 * kS + 25000 * k + k % 7, &why));
  }
}

TEST(StampGuard, OneMessageFarOffIsRefusedAndTheStreamGoesOn) {
  StampGuard g;
  std::string why;
  EXPECT_TRUE(g.admit("IMU", 10 * kS, 10 * kS, &why));
  EXPECT_FALSE(g.admit("IMU", 10 * kS + 86400 * kS, 10 * kS, &why));
  EXPECT_NE(why.find("+86400.000 s off its stream"), std::string::npos) << why;
  EXPECT_TRUE(g.admit("IMU", 10 * kS + 5000, 10 * kS + 5000, &why));        // not frozen
  EXPECT_FALSE(g.admit("IMU", 10 * kS - 3600 * kS, 10 * kS + 7500, &why));  // an hour behind
  EXPECT_TRUE(g.admit("IMU", 10 * kS + 10000, 10 * kS + 10000, &why));
  // Within the sensor tolerance (a stalled machine delays arrival by seconds): passes.
  EXPECT_TRUE(g.admit("IMU", 10 * kS + 12500, 15 * kS, &why));
}

TEST(StampGuard, AJumpIsAcceptedOnceConfirmedByTheFollowingMessages) {
  StampGuard g;
  std::string why;
  EXPECT_TRUE(g.admit("WHEEL_TICKS", 0, 0, &why));
  // The sender's clock stepped 1 h ahead (NTP at boot): two refused, the third confirms.
  const int64_t step = 3600 * kS;
  EXPECT_FALSE(g.admit("WHEEL_TICKS", step + 10000, 10000, &why));
  EXPECT_FALSE(g.admit("WHEEL_TICKS", step + 20000, 20000, &why));
  EXPECT_TRUE(g.admit("WHEEL_TICKS", step + 30000, 30000, &why));
  EXPECT_TRUE(g.admit("WHEEL_TICKS", step + 40000, 40000, &why));
  // Alternating forgeries never confirm each other.
  for (int k = 0; k < 10; ++k) {
    EXPECT_FALSE(g.admit("WHEEL_TICKS", (k % 2 ? 1 : -1) * 86400 * kS, 50000 + k, &why));
    EXPECT_TRUE(g.admit("WHEEL_TICKS", step + 60000 + k, 60000 + k, &why));
  }
}

TEST(StampGuard, SweepsHaveMinutesOfSlackAndOtherChannelsAreNotChecked) {
  StampGuard g;
  std::string why;
  EXPECT_TRUE(g.admit("SWEEP_CLOUD", 0, 1 * kS, &why));
  EXPECT_TRUE(g.admit("SWEEP_CLOUD", 20 * kS, 40 * kS, &why));  // a 16 s mode-7 sweep
  EXPECT_FALSE(g.admit("SWEEP_CLOUD", 86400 * kS, 41 * kS, &why));
  EXPECT_TRUE(g.admit("MAP_SAVE", 0, 5 * kS, &why));
  EXPECT_TRUE(g.admit("MAP_SAVE", 0, 5000 * kS, &why));
  EXPECT_TRUE(g.admit("STATUS_MAPPER", 86400 * kS, 0, &why));
}

TEST(StampGuard, ANewStreamIsJudgedAgainstTheNodesOtherStreams) {
  StampGuard g;
  std::string why;
  // A played log: every stream shifted by the same 9000 s.
  const int64_t shift = -9000 * kS;
  EXPECT_TRUE(g.admit("IMU", 10 * kS + shift, 10 * kS, &why));
  EXPECT_TRUE(g.admit("IMU", 10 * kS + 5000 + shift, 10 * kS + 5000, &why));
  // The first WHEEL_TICKS a day ahead of its peers cannot anchor the stream...
  EXPECT_FALSE(g.admit("WHEEL_TICKS", 10 * kS + 86400 * kS + shift, 10 * kS + 6000, &why));
  EXPECT_NE(why.find("WHEEL_TICKS"), std::string::npos) << why;
  // ...and the good ones after it pass at once.
  EXPECT_TRUE(g.admit("WHEEL_TICKS", 10 * kS + 20000 + shift, 10 * kS + 20000, &why));
  EXPECT_TRUE(g.admit("WHEEL_TICKS", 10 * kS + 40000 + shift, 10 * kS + 40000, &why));
  // Sweep-level streams are stamped at a sweep's start: they are not judged by sensors.
  EXPECT_TRUE(g.admit("SWEEP_CLOUD", 10 * kS + shift - 60 * kS, 10 * kS + 50000, &why));
}

}  // namespace
}  // namespace sweepmap
