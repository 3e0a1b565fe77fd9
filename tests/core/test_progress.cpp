// The progress reporter (core/progress.hpp): shown on a terminal only, after its delay, with
// the stage, the fraction and the time left. The terminal test and the clock are injected.
#include <gtest/gtest.h>

#include <sstream>

#include "core/progress.hpp"

namespace sweepmap {
namespace {

struct Fixture {
  std::ostringstream out;
  double now = 0;
  ProgressOptions options(bool terminal) {
    ProgressOptions o;
    o.is_terminal = [terminal] { return terminal; };
    o.now_s = [this] { return now; };
    o.out = &out;
    return o;
  }
};

TEST(Progress, QuietWhenStderrIsNotATerminal) {
  Fixture f;
  {
    Progress p("replay", f.options(false));
    f.now = 10;
    p.update(0.5);
    EXPECT_FALSE(p.active());
  }
  EXPECT_EQ(f.out.str(), "");
}

TEST(Progress, QuietWhenDisabled) {  // --json, --quiet
  Fixture f;
  ProgressOptions o = f.options(true);
  o.enabled = false;
  {
    Progress p("replay", o);
    f.now = 10;
    p.update(0.5);
  }
  EXPECT_EQ(f.out.str(), "");
}

TEST(Progress, OnATerminalAfterTheDelayWithTheTimeLeft) {
  Fixture f;
  {
    Progress p("replay", f.options(true));
    f.now = 1;
    p.update(0.2);
    EXPECT_EQ(f.out.str(), "") << "a short command prints nothing";
    f.now = 3;
    p.update(0.5);  // half done in 3 s: 3 s left
    EXPECT_EQ(f.out.str(), "\rreplay: 50%, 3 s left");
  }
  EXPECT_EQ(f.out.str().back(), '\n') << "the line is ended";
}

TEST(Progress, StagesAndUnknownFractions) {
  Fixture f;
  Progress p("calib mounting", f.options(true));
  f.now = 5;
  p.stage("ours");
  f.now = 9;
  p.update(-1);  // unknown: the stage's time so far
  EXPECT_NE(f.out.str().find("calib mounting: ours, 4 s"), std::string::npos) << f.out.str();
  f.now = 9.05;
  const std::string before = f.out.str();
  p.update(-1);
  EXPECT_EQ(f.out.str(), before) << "redrawn at most every min_interval_s";
}

}  // namespace
}  // namespace sweepmap
