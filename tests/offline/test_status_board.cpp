// The status board of `sweepmap status` fed synthetic bus traffic: health and counters from
// STATUS_*, a process marked stale when its status stops, message rates per channel, the
// mapper's progress and the last sweep, malformed status messages counted.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

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

// The status of node `node` running in process `process` (STATUS_<NODE>).
Message nodeStatus(const std::string& process, const std::string& node, int health,
                   const std::string& detail, int64_t scans) {
  process_status_t s{};
  s.process = process;
  s.health = static_cast<int8_t>(health);
  s.detail = detail;
  s.ncounters = 1;
  s.counter_names = {"scans"};
  s.counter_values = {scans};
  std::string channel = "STATUS_" + node;
  for (char& c : channel) c = static_cast<char>(std::toupper(c));
  return encode(channel, s);
}

// A process of one node named after it.
Message status(const std::string& process, int health, const std::string& detail, int64_t scans) {
  return nodeStatus(process, process, health, detail, scans);
}

// The words of the table line that starts with `first` ("" when there is none).
std::vector<std::string> rowOf(const std::string& text, const std::string& first) {
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);) {
    std::istringstream words(line);
    std::vector<std::string> w;
    for (std::string x; words >> x;) w.push_back(x);
    if (!w.empty() && w[0] == first) return w;
  }
  return {};
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
  EXPECT_EQ(j["processes"]["lidar"]["status"], "OK");
  EXPECT_EQ(j["processes"]["lidar"]["nodes"]["lidar"]["counters"]["scans"], 360);
  EXPECT_EQ(j["processes"]["odometry"]["status"], "STALE");
  EXPECT_NEAR(j["processes"]["odometry"]["age_s"].get<double>(), 7.0, 0.01);
  EXPECT_EQ(j["processes"]["odometry"]["detail"], "EKF on wheels alone");
  EXPECT_NEAR(j["channels"]["LIDAR_SCAN"]["rate_hz"].get<double>(), 40.0, 0.5);
  EXPECT_EQ(j["channels"]["LIDAR_SCAN"]["messages"], 400);
  EXPECT_EQ(j["mapper"]["sweeps"], 3);
  EXPECT_EQ(j["mapper"]["occupied_voxels"], 1234);
  EXPECT_TRUE(j["last_sweep"]["corrected"].get<bool>());
  EXPECT_NEAR(j["last_sweep"]["phi_offset_deg"].get<double>(), 0.573, 0.001);
  EXPECT_EQ(j["malformed"], 1);
  EXPECT_EQ(board.unhealthy(now), 1);  // the stale odometry

  // The table says the same: STATUS the state, AGE the age of the last status.
  const std::string text = board.text(now);
  EXPECT_EQ(rowOf(text, "PROCESS"),
            (std::vector<std::string>{"PROCESS", "STATUS", "AGE", "DETAIL"}));
  EXPECT_EQ(rowOf(text, "odometry"), (std::vector<std::string>{"odometry", "STALE", "7.0", "s",
                                                               "EKF", "on", "wheels", "alone"}))
      << text;
  EXPECT_EQ(rowOf(text, "lidar"), (std::vector<std::string>{"lidar", "OK", "1.0", "s"})) << text;
  EXPECT_NE(text.find("mapper: 3 sweeps"), std::string::npos) << text;
  EXPECT_NE(text.find("last sweep: #2 corrected"), std::string::npos) << text;
}

// A process running several nodes (sweepmap-lidar --device sim: the lidar, the simulated
// shaft's follower and the truth sweeps) is one row; its nodes are detail beneath it, and its
// state is the worst of theirs.
TEST(StatusBoard, OneRowPerProcessNodesAsDetail) {
  StatusBoard board;
  const int64_t t0 = 1'000'000'000;
  board.add(nodeStatus("lidar", "lidar", process_status_t::OK, "", 40), t0);
  board.add(nodeStatus("lidar", "truth_follower", process_status_t::OK, "", 0), t0);
  board.add(nodeStatus("lidar", "truth_sweep", process_status_t::DEGRADED, "no shaft yet", 0),
            t0 + 500'000);
  board.add(status("mapper", process_status_t::OK, "", 3), t0 + 500'000);
  const int64_t now = t0 + 1'000'000;

  const auto j = nlohmann::json::parse(board.json(now));
  ASSERT_EQ(j["processes"].size(), 2u) << j.dump(2);
  const auto& lidar = j["processes"]["lidar"];
  EXPECT_EQ(lidar["status"], "DEGRADED");
  EXPECT_EQ(lidar["detail"], "no shaft yet");
  EXPECT_NEAR(lidar["age_s"].get<double>(), 0.5, 1e-9);  // its newest status
  EXPECT_EQ(lidar["nodes"].size(), 3u);
  EXPECT_EQ(lidar["nodes"]["truth_follower"]["status"], "OK");
  EXPECT_EQ(lidar["nodes"]["truth_follower"]["age_s"], 1.0);
  EXPECT_EQ(j["unhealthy"], 0);

  const std::string text = board.text(now);
  EXPECT_NE(text.find("sweepmap status: 2 processes"), std::string::npos) << text;
  EXPECT_EQ(rowOf(text, "lidar"),
            (std::vector<std::string>{"lidar", "DEGRADED", "0.5", "s", "no", "shaft", "yet"}))
      << text;
  EXPECT_TRUE(rowOf(text, "truth_follower").empty()) << text;  // not a process row
  EXPECT_NE(text.find("    node truth_follower OK, 1.0 s\n"), std::string::npos) << text;
  EXPECT_NE(text.find("    node truth_sweep DEGRADED, 0.5 s: no shaft yet\n"), std::string::npos)
      << text;
  EXPECT_EQ(rowOf(text, "mapper"), (std::vector<std::string>{"mapper", "OK", "0.5", "s"}));
  EXPECT_EQ(board.processes(), 2u);
}

// A status from a build before processes were named (no `process`): its node is its process.
TEST(StatusBoard, StatusWithoutProcessNameIsItsOwnProcess) {
  StatusBoard board;
  board.add(nodeStatus("", "assembler", process_status_t::FAILED, "bad plate", 1), 0);
  const auto j = nlohmann::json::parse(board.json(0));
  EXPECT_EQ(j["processes"]["assembler"]["status"], "FAILED");
  EXPECT_EQ(board.unhealthy(0), 1);
}

// Issue 21: a string length of INT32_MIN, 2^26 or 2^31-1 counters (2.2 GB, then a crash) and a
// detail that is not UTF-8 (--json printed nothing) are malformed: counted, never shown, and
// the board goes on with the good statuses.
TEST(StatusBoard, HostileStatusMessagesAreCountedNotDecoded) {
  StatusBoard board;
  auto patched = [](Message m, size_t at, uint32_t v) {
    for (int i = 0; i < 4; ++i) m.data[at + i] = static_cast<uint8_t>(v >> (24 - 8 * i));
    return m;
  };
  process_status_t s{};
  s.process = "intruder";
  const Message plain = encode("STATUS_INTRUDER", s);
  board.add(patched(plain, 16, 0x80000000u), 0);  // the process's length
  for (uint32_t n : {1u << 26, 0x7FFFFFFFu}) board.add(patched(plain, plain.data.size() - 4, n), 0);
  s.detail = "bad \xff\xfe text";
  board.add(encode("STATUS_INTRUDER", s), 0);
  sweep_status_t sweep{};
  const Message sweep_plain = encode("SWEEP_STATUS", sweep);
  board.add(patched(sweep_plain, sweep_plain.data.size() - 9, 0x80000000u), 0);
  board.add(status("assembler", process_status_t::OK, "", 3), 0);
  const auto j = nlohmann::json::parse(board.json(0));
  EXPECT_EQ(j["malformed"], 5);
  EXPECT_FALSE(j["processes"].contains("intruder"));
  EXPECT_EQ(j["processes"]["assembler"]["status"], "OK");
  EXPECT_NE(board.text(0).find("5 malformed status messages ignored"), std::string::npos);
}

TEST(StatusBoard, NothingSeenSaysSo) {
  StatusBoard board;
  EXPECT_NE(board.text(0).find("no STATUS_* message seen"), std::string::npos);
  EXPECT_EQ(board.unhealthy(0), 0);
  EXPECT_EQ(board.processes(), 0u);
}

}  // namespace
}  // namespace sweepmap
