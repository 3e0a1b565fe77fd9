// The status board of `sweepmap status` fed synthetic bus traffic: health and counters from
// STATUS_*, a process marked stale when its status stops, message rates per channel, the
// mapper's progress and the last sweep, malformed status messages counted.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "sweepmap/map_stats_t.hpp"
#include "sweepmap/process_status_t.hpp"
#include "sweepmap/sweep_status_t.hpp"
#include "tools/ops/status.hpp"

namespace sweepmap {
namespace {

template <class T>
Message encode(const std::string& channel, const T& m) {
  Outbox o;
  o.publish(channel, 0, m);
  return o.take().front();
}

Message status(const std::string& process, int health, const std::string& detail, int64_t scans) {
  process_status_t s{};
  s.process = process;
  s.health = static_cast<int8_t>(health);
  s.detail = detail;
  s.ncounters = 1;
  s.counter_names = {"scans"};
  s.counter_values = {scans};
  std::string channel = "STATUS_" + process;
  for (char& c : channel) c = static_cast<char>(std::toupper(c));
  return encode(channel, s);
}

TEST(StatusBoard, HealthRatesStaleMapperAndLastSweep) {
  StatusBoardOptions o;
  o.stale_s = 3.0;
  o.rate_window_s = 5.0;
  StatusBoard board(o);
  const int64_t t0 = 1'000'000'000;
  // 10 s: the lidar at 40 Hz with a 1 Hz status; the odometry's status stops after 4 s.
  for (int k = 0; k < 400; ++k) {
    const int64_t t = t0 + k * 25'000;
    board.add(Message{t, "LIDAR_SCAN", std::vector<uint8_t>(100)}, t);
    if (k % 40 == 0) {
      board.add(status("lidar", process_status_t::OK, "", k), t);
      if (t - t0 < 4'000'000) {
        board.add(status("odometry", process_status_t::DEGRADED, "EKF on wheels alone", k), t);
      }
    }
  }
  map_stats_t m{};
  m.sweeps_inserted = 3;
  m.occupied_voxels = 1234;
  m.resolution_m = 0.05;
  board.add(encode("MAP_STATS", m), t0 + 9'000'000);
  sweep_status_t s{};
  s.sweep_id = 2;
  s.corrected = true;
  s.phi_offset_rad = 0.01;
  board.add(encode("SWEEP_STATUS", s), t0 + 9'000'000);
  board.add(Message{t0, "STATUS_BROKEN", {1, 2, 3}}, t0 + 9'500'000);

  const int64_t now = t0 + 10'000'000;
  const auto j = nlohmann::json::parse(board.json(now));
  EXPECT_EQ(j["processes"]["lidar"]["health"], "OK");
  EXPECT_FALSE(j["processes"]["lidar"]["stale"].get<bool>());
  EXPECT_EQ(j["processes"]["lidar"]["counters"]["scans"], 360);
  EXPECT_EQ(j["processes"]["odometry"]["health"], "DEGRADED");
  EXPECT_TRUE(j["processes"]["odometry"]["stale"].get<bool>());
  EXPECT_EQ(j["processes"]["odometry"]["detail"], "EKF on wheels alone");
  EXPECT_NEAR(j["channels"]["LIDAR_SCAN"]["rate_hz"].get<double>(), 40.0, 0.5);
  EXPECT_EQ(j["channels"]["LIDAR_SCAN"]["messages"], 400);
  EXPECT_EQ(j["mapper"]["sweeps"], 3);
  EXPECT_EQ(j["mapper"]["occupied_voxels"], 1234);
  EXPECT_TRUE(j["last_sweep"]["corrected"].get<bool>());
  EXPECT_NEAR(j["last_sweep"]["phi_offset_deg"].get<double>(), 0.573, 0.001);
  EXPECT_EQ(j["malformed"], 1);
  EXPECT_EQ(board.unhealthy(now), 1);  // the stale odometry

  const std::string text = board.text(now);
  EXPECT_NE(text.find("STALE"), std::string::npos) << text;
  EXPECT_NE(text.find("mapper: 3 sweeps"), std::string::npos) << text;
  EXPECT_NE(text.find("last sweep: #2 corrected"), std::string::npos) << text;
}

TEST(StatusBoard, NothingSeenSaysSo) {
  StatusBoard board;
  EXPECT_NE(board.text(0).find("no STATUS_* message seen"), std::string::npos);
  EXPECT_EQ(board.unhealthy(0), 0);
}

}  // namespace
}  // namespace sweepmap
