#include <gtest/gtest.h>

#include <stdexcept>

#include "devices/shaft_trajectory.hpp"

namespace sweepmap {
namespace {

// Three contiguous segments: accelerate from rest at 1 rad, cruise at 2 rad/s, decelerate.
class ShaftTrajectoryTest : public ::testing::Test {
 protected:
  void SetUp() override {
    trajectory_.apply({1'000'000, 1.0, 0.0, 2.0});
    trajectory_.apply({2'000'000, 2.0, 2.0, 0.0});
    trajectory_.apply({3'000'000, 4.0, 2.0, -1.0});
  }
  ShaftTrajectory trajectory_;
};

TEST_F(ShaftTrajectoryTest, EvaluatesEachSegment) {
  EXPECT_DOUBLE_EQ(trajectory_.angleAt(1'500'000), 1.25);
  EXPECT_DOUBLE_EQ(trajectory_.velocityAt(1'500'000), 1.0);
  EXPECT_DOUBLE_EQ(trajectory_.angleAt(2'000'000), 2.0);
  EXPECT_DOUBLE_EQ(trajectory_.angleAt(2'500'000), 3.0);
  EXPECT_DOUBLE_EQ(trajectory_.velocityAt(2'500'000), 2.0);
  EXPECT_DOUBLE_EQ(trajectory_.angleAt(4'000'000), 5.5);
  EXPECT_DOUBLE_EQ(trajectory_.velocityAt(4'000'000), 1.0);
}

TEST_F(ShaftTrajectoryTest, BeforeFirstSegmentGivesItsStartValues) {
  EXPECT_FALSE(trajectory_.covers(999'999));
  EXPECT_TRUE(trajectory_.covers(1'000'000));
  EXPECT_DOUBLE_EQ(trajectory_.angleAt(0), 1.0);
  EXPECT_DOUBLE_EQ(trajectory_.velocityAt(0), 0.0);
}

TEST_F(ShaftTrajectoryTest, ApplyReplacesThePlannedFuture) {
  trajectory_.apply({2'500'000, 3.0, 2.0, -2.0});
  ASSERT_EQ(trajectory_.segments().size(), 3u);
  EXPECT_DOUBLE_EQ(trajectory_.angleAt(3'000'000), 3.75);
  EXPECT_DOUBLE_EQ(trajectory_.velocityAt(3'000'000), 1.0);
  // A segment at exactly the start of another replaces it.
  trajectory_.apply({2'000'000, 2.0, 0.0, 0.0});
  ASSERT_EQ(trajectory_.segments().size(), 2u);
  EXPECT_DOUBLE_EQ(trajectory_.angleAt(9'000'000), 2.0);
}

TEST_F(ShaftTrajectoryTest, PruneKeepsTheActiveSegment) {
  trajectory_.pruneBefore(1'999'999);
  EXPECT_EQ(trajectory_.segments().size(), 3u);
  trajectory_.pruneBefore(2'500'000);
  ASSERT_EQ(trajectory_.segments().size(), 2u);
  EXPECT_EQ(trajectory_.segments().front().start_utime, 2'000'000);
  EXPECT_DOUBLE_EQ(trajectory_.angleAt(2'500'000), 3.0);
  trajectory_.pruneBefore(3'000'000);
  ASSERT_EQ(trajectory_.segments().size(), 1u);
  EXPECT_DOUBLE_EQ(trajectory_.angleAt(4'000'000), 5.5);
  trajectory_.pruneBefore(9'000'000);
  EXPECT_EQ(trajectory_.segments().size(), 1u);
}

TEST(ShaftTrajectory, EmptyCoversNothingAndRefusesEvaluation) {
  ShaftTrajectory empty;
  EXPECT_TRUE(empty.empty());
  EXPECT_FALSE(empty.covers(0));
  EXPECT_THROW(empty.angleAt(0), std::logic_error);
}

}  // namespace
}  // namespace sweepmap
