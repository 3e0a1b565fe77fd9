// Two hosts on one link: the drivers (sweepmap-motor, sweepmap-lidar, simulated devices,
// rig A) in a "pi" network namespace; sweepmap-assembler, sweepmap-mapper and lcm-logger in
// a "laptop" one; joined by a veth pair with a multicast route on each side, LCM with
// ttl=1. Once on a clean link and once with 1 % packet loss and reordering from the Pi to
// the laptop (`tc netem` where the kernel has it, else an iptables NFQUEUE rule and the
// test-only tests/e2e/impair_link). Nothing crashes, the laptop's log replays to the live
// mapper's map byte for byte, and every sweep with scans missing is counted as incomplete:
// checked against what the Pi sent (an lcm-logger on the Pi side, where nothing is lost).
#include <gtest/gtest.h>

#include <map>
#include <set>

#include "processes/channels.hpp"
#include "sweepmap/lidar_scan_t.hpp"
#include "sweepmap/scan_window_t.hpp"
#include "tests/e2e/fixtures.hpp"

namespace sweepmap {
namespace test {
namespace {

const std::string kRig = sourcePath("config/rig_a.yaml");
const std::string kScene = sourcePath("config/scene_conference_room.yaml");
// What the README's real setup uses, with sweepmap's larger receive buffer.
const std::string kUrl = "udpm://239.255.76.67:7667?ttl=1&recv_buf_size=2097152";
const VethEnd kPiEnd{"veth-pi", "10.77.0.1/24"};
const VethEnd kLaptopEnd{"veth-laptop", "10.77.0.2/24"};
constexpr int kQueue = 7;

// How the link was impaired.
enum class Impairment { kNone, kNetem, kNfqueue };

struct RunResult {
  fs::path dir;
  Impairment impairment = Impairment::kNone;
  std::string impair_output;  // impair_link's counts
};

class TwoHostsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string why;
    pi_ = NetworkNamespace::create(&why);
    if (pi_) laptop_ = NetworkNamespace::create(&why);
    if (!pi_ || !laptop_) GTEST_SKIP() << "no network namespaces: " << why;
    ASSERT_TRUE(joinByVeth(*pi_, kPiEnd, *laptop_, kLaptopEnd, &why)) << why;
  }

  // 1 % loss and reordering of the frames the Pi sends to the laptop: netem on the Pi's
  // side of the veth where the kernel has it, else impair_link behind an NFQUEUE rule on
  // the laptop's, matching the Pi's address only (the laptop's own multicast, looped back
  // to it, stays whole, as on a real laptop). The rule is in PREROUTING, before IP
  // reassembly (nothing in this namespace asks for conntrack's early defragmentation), so
  // it sees frames as netem does: a scan of ~9 frames is lost when any of them is, and a
  // held frame makes its scan complete after the next one.
  Impairment impair(pid_t* helper) {
    // netem sends `reorder` of the packets at once and delays the rest: 2 % arrive 40 ms
    // late, after the next scan (25 ms apart).
    if (pi_->command({"tc", "qdisc", "add", "dev", kPiEnd.interface, "root", "netem", "loss", "1%",
                      "delay", "40ms", "reorder", "98%"}) == 0) {
      return Impairment::kNetem;
    }
#ifdef SWEEPMAP_IMPAIR_LINK
    *helper = procs_.start("impair_link",
                           {SWEEPMAP_IMPAIR_LINK, "--queue", std::to_string(kQueue), "--loss",
                            "0.01", "--reorder", "0.02", "--seed", "5"},
                           laptop_.get());
    // Bound to its queue once it has said so; until then the rule would drop everything.
    for (int i = 0; i < 100 && procs_.said(*helper).empty(); ++i) sleepS(0.05);
    EXPECT_FALSE(procs_.said(*helper).empty()) << "impair_link did not start";
    const std::vector<std::string> rule = {
        "iptables-legacy",     "-t", "raw",       "-A", "PREROUTING", "-i",
        kLaptopEnd.interface,  "-s", "10.77.0.1", "-j", "NFQUEUE",    "--queue-num",
        std::to_string(kQueue)};
    if (laptop_->command(rule) != 0) {
      ADD_FAILURE() << "iptables-legacy NFQUEUE rule refused (tools/ops/setup.sh installs "
                       "iptables)";
    }
    return Impairment::kNfqueue;
#else
    return Impairment::kNone;
#endif
  }

  // The run: loggers and the laptop's processes first, then the Pi's drivers; `sweeps`
  // sweeps in `mode`; everything stopped upstream first; the laptop's log replayed.
  RunResult run(const std::string& name, bool impaired, const std::string& mode, int sweeps) {
    RunResult r;
    r.dir = scratchDir(name);
    const fs::path& dir = r.dir;
    procs_.setDir(dir);
    pid_t helper = -1;
    if (impaired) r.impairment = impair(&helper);
    const ProcessCommand proc({"--rig", kRig, "--set", "motor.mode=" + mode, "--lcm-url", kUrl});
    NetworkNamespace* pi = pi_.get();
    NetworkNamespace* laptop = laptop_.get();
    const pid_t pi_logger = procs_.start(
        "pi_logger", loggerCommand(kUrl, (dir / "pi.lcmlog").string(), "LIDAR_SCAN|SCAN_WINDOW"),
        pi);
    const pid_t logger = procs_.start(
        "laptop_logger", loggerCommand(kUrl, (dir / "laptop.lcmlog").string()), laptop);
    const pid_t assembler = procs_.start("assembler", proc("assembler"), laptop);
    const pid_t mapper =
        procs_.start("mapper", proc("mapper", {"--save", (dir / "live_map.bt").string()}), laptop);
    const pid_t lidar =
        procs_.start("lidar", proc("lidar", {"--sim", "--scene", kScene, "--seed", "4"}), pi);
    sleepS(0.7);  // subscribers ready
    const pid_t motor = procs_.start(
        "motor", proc("motor", {"--sim", "--sweeps", std::to_string(sweeps), "--seed", "4"}), pi);
    EXPECT_EQ(procs_.wait(motor, 120.0), 0) << procs_.said(motor);
    std::vector<Stop> stops = {
        {lidar, 5.0}, {assembler, 10.0}, {mapper, 60.0}, {logger, 10.0}, {pi_logger, 10.0}};
    if (helper > 0) stops.push_back({helper, 5.0});
    procs_.stopInOrder(stops, 0.8);  // after the last scans are delivered
    if (helper > 0) r.impair_output = procs_.said(helper);
    EXPECT_EQ(replayInto(dir / "offline", (dir / "laptop.lcmlog").string(),
                         {"--rig", kRig, "--set", "motor.mode=" + mode}),
              0)
        << readFile(dir / "replay.txt");
    return r;
  }

  std::unique_ptr<NetworkNamespace> pi_, laptop_;
  Launcher procs_;
};

// What the Pi sent: each window's scans, from the Pi side's log.
struct Sent {
  std::map<int64_t, std::pair<int64_t, int64_t>> windows;  // sweep id -> [start, end)
  std::vector<int64_t> scan_utimes;
  int scansIn(int64_t id) const {
    const auto [start, end] = windows.at(id);
    int n = 0;
    for (int64_t t : scan_utimes) n += t >= start && t < end;
    return n;
  }
};

Sent readSent(const std::string& log) {
  Sent s;
  for (const auto& m : readChannel(log, channels::kScanWindow)) {
    scan_window_t w;
    EXPECT_TRUE(decodeMessage(m, &w));
    s.windows[w.sweep_id] = {w.start_utime, w.end_utime};
  }
  for (const auto& m : readChannel(log, channels::kLidarScan)) {
    lidar_scan_t scan;
    EXPECT_TRUE(decodeMessage(m, &scan));
    s.scan_utimes.push_back(scan.utime);
  }
  return s;
}

std::set<int64_t> windowIds(const std::string& log) {
  std::set<int64_t> ids;
  for (const auto& m : readChannel(log, channels::kScanWindow)) {
    scan_window_t w;
    if (decodeMessage(m, &w)) ids.insert(w.sweep_id);
  }
  return ids;
}

// Every sweep's missing scans against what the Pi sent; returns the number of sweeps
// that lost scans.
int checkSweepsAgainstSent(const fs::path& dir, const nlohmann::json& summary) {
  const Sent sent = readSent((dir / "pi.lcmlog").string());
  int incomplete = 0;
  int64_t missing = 0;
  for (const auto& s : summary["sweeps"]) {
    const int64_t id = s["id"].get<int64_t>();
    EXPECT_TRUE(sent.windows.count(id)) << "sweep " << id << " was never sent";
    if (!sent.windows.count(id)) continue;
    const int lost = sent.scansIn(id) - s["scans"].get<int>();
    EXPECT_EQ(s["missing_scans"].get<int>(), lost) << "sweep " << id << ": " << sent.scansIn(id)
                                                   << " scans sent, " << s["scans"] << " assembled";
    incomplete += lost > 0;
    missing += lost;
  }
  const auto& a = summary["assembler"];
  EXPECT_EQ(a["sweeps_incomplete"].get<int>(), incomplete);
  EXPECT_EQ(a["scans_missing"].get<int64_t>(), missing);
  // Lost windows show between the first and the last that arrived.
  const std::set<int64_t> got = windowIds((dir / "laptop.lcmlog").string());
  int64_t lost_windows = 0;
  if (!got.empty()) {
    for (const auto& [id, span] : sent.windows) {
      lost_windows += id > *got.begin() && id < *got.rbegin() && !got.count(id);
    }
  }
  EXPECT_EQ(a["windows_missing"].get<int64_t>(), lost_windows);
  // The live assembler counted the same as its replay (in its last STATUS_ASSEMBLER: it
  // publishes one when it stops).
  const LastStatus live = lastStatus((dir / "laptop.lcmlog").string(), "STATUS_ASSEMBLER");
  EXPECT_TRUE(live.found);
  EXPECT_EQ(live.counter("sweeps_incomplete"), incomplete);
  EXPECT_EQ(live.counter("scans_missing"), missing);
  return incomplete;
}

void expectLiveMapEqualsReplay(const fs::path& dir) {
  ASSERT_TRUE(fs::exists(dir / "live_map.bt")) << readFile(dir / "mapper.txt");
  EXPECT_TRUE(sameBytes(dir / "live_map.bt", dir / "offline" / "map.bt"))
      << "the live mapper's map differs from the replay of the laptop's log";
}

TEST_F(TwoHostsTest, CleanLinkLaptopLogReplaysToTheLiveMap) {
  const RunResult r = run("two_hosts_clean", false, "1", 2);
  const nlohmann::json summary = readJson(r.dir / "offline" / "summary.json");
  ASSERT_EQ(summary["sweeps"].size(), 2u) << readFile(r.dir / "replay.txt");
  EXPECT_EQ(checkSweepsAgainstSent(r.dir, summary), 0);
  EXPECT_EQ(summary["assembler"]["dropped"].get<int>(), 0);
  // Every scan the Pi sent reached the laptop.
  EXPECT_EQ(readChannel((r.dir / "laptop.lcmlog").string(), channels::kLidarScan).size(),
            readChannel((r.dir / "pi.lcmlog").string(), channels::kLidarScan).size());
  expectLiveMapEqualsReplay(r.dir);
}

TEST_F(TwoHostsTest, LossAndReorderingIncompleteSweepsCountedAndLogReplaysToTheLiveMap) {
#ifndef SWEEPMAP_IMPAIR_LINK
  if (pi_->command(
          {"tc", "qdisc", "add", "dev", kPiEnd.interface, "root", "netem", "loss", "1%"}) != 0) {
    GTEST_SKIP() << "no tc netem in this kernel and impair_link not built (needs "
                    "libnetfilter-queue-dev: tools/ops/setup.sh)";
  }
  pi_->command({"tc", "qdisc", "del", "dev", kPiEnd.interface, "root"});
#endif
  const RunResult r = run("two_hosts_lossy", true, "4", 3);
  std::cout << "two hosts: link impaired by "
            << (r.impairment == Impairment::kNetem ? "tc netem" : "iptables NFQUEUE + impair_link")
            << "\n"
            << r.impair_output;
  RecordProperty("impairment", r.impairment == Impairment::kNetem ? "netem" : "nfqueue");
  const nlohmann::json summary = readJson(r.dir / "offline" / "summary.json");
  ASSERT_GE(summary["sweeps"].size(), 2u) << readFile(r.dir / "replay.txt");
  const std::string pi_log = (r.dir / "pi.lcmlog").string();
  const std::string laptop_log = (r.dir / "laptop.lcmlog").string();
  const size_t sent = readChannel(pi_log, channels::kLidarScan).size();
  const size_t received = readChannel(laptop_log, channels::kLidarScan).size();
  EXPECT_LT(received, sent) << "no scan was lost: the impairment did not work";
  // Reordered scans arrive after a later one: the assembler drops them as out of order.
  EXPECT_GT(summary["assembler"]["dropped"].get<int>(), 0) << "no scan was reordered";
  const int incomplete = checkSweepsAgainstSent(r.dir, summary);
  EXPECT_GT(incomplete, 0) << "600 scans in windows, 1 % of frames lost, no sweep incomplete";
  // The replay's one-line summary says so.
  EXPECT_NE(readFile(r.dir / "replay.txt").find("sweeps incomplete"), std::string::npos)
      << readFile(r.dir / "replay.txt");
  expectLiveMapEqualsReplay(r.dir);
}

}  // namespace
}  // namespace test
}  // namespace sweepmap
