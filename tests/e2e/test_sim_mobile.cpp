// `sweepmap sim --rig rig_b` (rig B simulation): determinism, the log's content, and a replay of a
// 60 s circle through `sweepmap replay` against the ground truth.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iostream>
#include <regex>

#include "core/event_log.hpp"
#include "core/set_arguments.hpp"
#include "processes/channels.hpp"
#include "sweepmap/imu_t.hpp"
#include "sweepmap/lidar_scan_t.hpp"
#include "sweepmap/pose2d_t.hpp"
#include "sweepmap/truth_mobile_rig_t.hpp"
#include "sweepmap/truth_mounting_t.hpp"
#include "sweepmap/wheel_ticks_t.hpp"
#include "tests/e2e/test_support.hpp"

namespace sweepmap {
namespace test {
namespace {

std::vector<std::string> simArgs(const std::string& out, const std::string& seed,
                                 const std::vector<std::string>& sets = {}) {
  std::vector<std::string> a = {"sim",
                                "--rig",
                                sourcePath("config/rig_b.yaml"),
                                "--scene",
                                sourcePath("config/scene_lab.yaml"),
                                "--seed",
                                seed,
                                "--out",
                                out};
  appendSetArguments(&a, sets);
  return a;
}

TEST(SimMobile, SameSeedGivesByteIdenticalLogs) {
  const auto dir = scratchDir("sim_mobile_determinism");
  const std::vector<std::string> sets = {"sim.duration_s=8", "sim.path=loop"};
  const std::string a = (dir / "a.lcmlog").string(), b = (dir / "b.lcmlog").string(),
                    c = (dir / "c.lcmlog").string();
  ASSERT_EQ(sweepmap(simArgs(a, "3", sets), dir / "a.txt"), 0) << readFile(dir / "a.txt");
  ASSERT_EQ(sweepmap(simArgs(b, "3", sets), dir / "b.txt"), 0) << readFile(dir / "b.txt");
  ASSERT_EQ(sweepmap(simArgs(c, "4", sets), dir / "c.txt"), 0) << readFile(dir / "c.txt");
  const std::string la = readFile(a);
  EXPECT_GT(la.size(), 100000u);
  EXPECT_TRUE(la == readFile(b)) << "same seed, different bytes";
  EXPECT_FALSE(la == readFile(c)) << "different seeds, same bytes";
}

TEST(SimMobile, ReplayMobileTwiceIsByteIdentical) {
  const auto dir = scratchDir("replay_mobile_determinism");
  const std::string log = (dir / "sim.lcmlog").string();
  ASSERT_EQ(sweepmap(simArgs(log, "3", {"sim.duration_s=8", "sim.path=loop"}), dir / "sim.txt"), 0)
      << readFile(dir / "sim.txt");
  for (const char* name : {"a", "b"}) {
    ASSERT_EQ(sweepmap({"replay", log, "--rig", sourcePath("config/rig_b.yaml"), "--out",
                        (dir / name).string()},
                       dir / (std::string(name) + ".txt")),
              0)
        << readFile(dir / (std::string(name) + ".txt"));
  }
  for (const char* f : {"map.bt", "cloud.pcd", "summary.json", "derived.lcmlog"}) {
    const std::string a = readFile(dir / "a" / f);
    EXPECT_FALSE(a.empty()) << f;
    EXPECT_TRUE(a == readFile(dir / "b" / f)) << f << " differs between two replays";
  }
  EXPECT_TRUE(fs::exists(dir / "a" / "top_view.png"));
}

TEST(SimMobile, DrivesAPathFromAFile) {
  const auto dir = scratchDir("sim_mobile_path_file");
  const std::string log = (dir / "file.lcmlog").string();
  ASSERT_EQ(
      sweepmap(simArgs(log, "2",
                       {"sim.duration_s=20", "sim.path=file", "sim.path_file=path_lab_table.yaml"}),
               dir / "o.txt"),
      0)
      << readFile(dir / "o.txt");
  // The truth follows the file: start heading +X, a left turn of 0.5 m radius after 3 m.
  const auto truth = poses(log, channels::kTruthPose);
  ASSERT_GT(truth.size(), 1000u);
  double max_y = -1e9;
  for (const auto& p : truth) max_y = std::max(max_y, p.y_m);  // world = start pose
  EXPECT_GT(max_y, 0.3);                                       // it turned left
  EXPECT_NEAR(pathLength(truth), 0.2 * (20 - 0.4), 1e-3);
  // A path that leaves the room, an open path shorter than the drive, a bad segment.
  const auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir / name) << text;
    return (dir / name).string();
  };
  const std::string out = (dir / "x.lcmlog").string();
  const std::string wall = write(
      "wall.yaml", "start: {x_m: 0, y_m: 0, heading_deg: 0}\nsegments:\n  - {length_m: 20}\n");
  EXPECT_EQ(sweepmap(simArgs(out, "1", {"sim.path=file", "sim.path_file=" + wall}), dir / "w.txt"),
            2);
  EXPECT_NE(readFile(dir / "w.txt").find("leaves the room"), std::string::npos)
      << readFile(dir / "w.txt");
  const std::string open_path =
      write("open.yaml", "start: {x_m: 0, y_m: 0, heading_deg: 0}\nsegments:\n  - {length_m: 2}\n");
  EXPECT_EQ(
      sweepmap(simArgs(out, "1", {"sim.path=file", "sim.path_file=" + open_path}), dir / "o2.txt"),
      2);
  EXPECT_NE(readFile(dir / "o2.txt").find("is open"), std::string::npos)
      << readFile(dir / "o2.txt");
  const std::string bad =
      write("bad.yaml", "start: {x_m: 0, y_m: 0, heading_deg: 0}\nsegments:\n  - {length_m: -1}\n");
  EXPECT_EQ(sweepmap(simArgs(out, "1", {"sim.path=file", "sim.path_file=" + bad}), dir / "b.txt"),
            2);
  EXPECT_NE(readFile(dir / "b.txt").find("segment 0 'length_m'"), std::string::npos)
      << readFile(dir / "b.txt");
}

TEST(SimMobile, BadConfigurationIsAConfigError) {
  const auto dir = scratchDir("sim_mobile_bad");
  EXPECT_EQ(
      sweepmap(simArgs((dir / "x.lcmlog").string(), "1", {"sim.path=figure9"}), dir / "o.txt"), 2);
  EXPECT_NE(readFile(dir / "o.txt").find("sim.path"), std::string::npos) << readFile(dir / "o.txt");
  EXPECT_EQ(
      sweepmap(simArgs((dir / "x.lcmlog").string(), "1", {"sim.no_such_key=1"}), dir / "p.txt"), 2);
}

TEST(SimMobile, CircleLogReplaysWithEkfBetterThanWheelOdometry) {
  const auto dir = scratchDir("sim_mobile_circle");
  const std::string log = (dir / "circle.lcmlog").string();
  ASSERT_EQ(sweepmap(simArgs(log, "1", {"sim.path=circle", "sim.duration_s=60"}), dir / "sim.txt"),
            0)
      << readFile(dir / "sim.txt");
  const std::string sim_out = readFile(dir / "sim.txt");
  std::smatch m;
  ASSERT_TRUE(std::regex_search(sim_out, m, std::regex("([0-9]+) slip events"))) << sim_out;
  const int slips = std::stoi(m[1]);
  EXPECT_GT(slips, 0) << "seed 1 should slip in 60 s (mean interval 10 s)";

  // Log content: counts, event time order, first-ray time of scans.
  {
    EventLogReader r(log);
    LogEvent ev;
    int64_t last = INT64_MIN;
    std::map<std::string, int> n;
    while (r.next(&ev)) {
      EXPECT_GE(ev.utime, last);
      last = ev.utime;
      ++n[ev.channel];
      if (ev.channel == channels::kTruthMounting) {
        truth_mounting_t t;
        ASSERT_TRUE(decodeMessage(Message{ev.utime, ev.channel, ev.data}, &t));
        EXPECT_DOUBLE_EQ(t.gamma_true_rad, 0.0355);
        EXPECT_DOUBLE_EQ(t.beta_true_rad, 0.0126);
        EXPECT_DOUBLE_EQ(t.alpha_true_rad, -0.0058);
        EXPECT_DOUBLE_EQ(t.t_BL_m[2], 0.30 + 0.004);  // the true centre: h + sim.lever_error_z_m
        EXPECT_DOUBLE_EQ(t.room_size_m[0], 10.0);
        EXPECT_EQ(t.scene, "lab");
      }
      if (ev.channel == channels::kTruthMobileRig) {
        truth_mobile_rig_t t;
        ASSERT_TRUE(decodeMessage(Message{ev.utime, ev.channel, ev.data}, &t));
        EXPECT_DOUBLE_EQ(t.wheel_radius_left_m, 0.0325 * 1.008);
        EXPECT_DOUBLE_EQ(t.wheel_radius_right_m, 0.0325 * (1 - 0.011));
        EXPECT_DOUBLE_EQ(t.wheel_distance_m, 0.2 + 0.004);
        EXPECT_DOUBLE_EQ(t.lidar_time_offset_s, 0.003);
        EXPECT_DOUBLE_EQ(t.gyro_bias_z_rad_s, 0.01);
        EXPECT_DOUBLE_EQ(t.mixed_pixel_probability, 0.5);  // the scene's artefacts
        EXPECT_DOUBLE_EQ(t.dropout_dark_probability, 0.3);
        EXPECT_DOUBLE_EQ(t.dropout_glancing_probability, 0.5);
        EXPECT_EQ(t.people, 2);
        EXPECT_DOUBLE_EQ(t.window_width_m, 1.5);
        EXPECT_DOUBLE_EQ(t.whiteboard_proud_m, 0.02);
      }
      if (ev.channel == channels::kLidarScan) {
        lidar_scan_t s;
        ASSERT_TRUE(decodeMessage(Message{ev.utime, ev.channel, ev.data}, &s));
        EXPECT_EQ(s.nranges, 714);
        EXPECT_EQ(s.time_increment_ns, 200000);
        EXPECT_EQ(ev.utime, s.utime + 713 * 200 + 10000);  // delivered after the last ray
      }
    }
    EXPECT_EQ(n[channels::kTruthPose], 6001);
    EXPECT_EQ(n[channels::kTruthMounting], 61);  // start and 1 Hz
    EXPECT_EQ(n[channels::kTruthMobileRig], 61);
    EXPECT_EQ(n[channels::kWheelTicks], 3001);
    EXPECT_EQ(n[channels::kImu], 12001);
    EXPECT_EQ(n[channels::kLidarScan], 420);
  }

  const auto out = dir / "replay";
  ASSERT_EQ(sweepmap({"replay", log, "--rig", sourcePath("config/rig_b.yaml"), "--out",
                      out.string(), "--no-plots"},
                     dir / "replay.txt"),
            0)
      << readFile(dir / "replay.txt");
  const auto truth = poses(log, channels::kTruthPose);
  const std::string derived = (out / "derived.lcmlog").string();
  const auto ekf = poses(derived, channels::kOdometryPose);
  const auto odo = poses(derived, channels::kWheelOdometry);
  ASSERT_FALSE(truth.empty());
  ASSERT_FALSE(ekf.empty());
  ASSERT_FALSE(odo.empty());
  const double l_truth = pathLength(truth), l_ekf = pathLength(ekf), l_odo = pathLength(odo);
  const pose2d_t& t_end = truth.back();
  const double e_ekf = std::hypot(ekf.back().x_m - t_end.x_m, ekf.back().y_m - t_end.y_m);
  const double e_odo = std::hypot(odo.back().x_m - t_end.x_m, odo.back().y_m - t_end.y_m);
  std::cout << "60 s circle, seed 1, " << slips << " slip events: path length truth " << l_truth
            << " m, EKF " << l_ekf << " m, wheels " << l_odo << " m; final position error EKF "
            << e_ekf << " m, wheel odometry " << e_odo << " m; final heading error EKF "
            << std::remainder(ekf.back().theta_rad - t_end.theta_rad, 2 * M_PI) << " rad, wheels "
            << std::remainder(odo.back().theta_rad - t_end.theta_rad, 2 * M_PI)
            << " rad; EKF gyro bias " << ekf.back().gyro_bias_rad_s << " rad/s (true "
            << t_end.gyro_bias_rad_s << ")\n";
  EXPECT_NEAR(l_truth, 0.2 * (60 - 0.4), 1e-3);
  EXPECT_NEAR(l_ekf, l_truth, 0.05 * l_truth);
  EXPECT_LT(e_ekf, e_odo);
  const auto summary = readJson(out / "summary.json");
  EXPECT_EQ(summary["scans"].get<int>(), 420);
  EXPECT_GT(summary["points"].get<int>(), 100000);
}

}  // namespace
}  // namespace test
}  // namespace sweepmap
