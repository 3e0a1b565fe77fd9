// Two hosts on one link: the drivers (sweepmap-motor, sweepmap-lidar, simulated devices,
// rig A) in a "pi" network namespace; sweepmap-assembler, sweepmap-mapper and lcm-logger in
// a "laptop" one; joined by a veth pair with a multicast route on each side, LCM with
// ttl=1. Once on a clean link and once with 1 % packet loss and reordering from the Pi to
// the laptop (`tc netem` where the kernel has it, else an iptables NFQUEUE rule and the
// test-only tests/e2e/impair_link). Nothing crashes, the laptop's log replays to the live
// mapper's map byte for byte, and every sweep with scans missing is counted as incomplete:
// checked against what the Pi sent (an lcm-logger on the Pi side, where nothing is lost).
// Then with an intruder: a third namespace on the same segment (the three hosts on a bridge)
// that publishes forged and malformed traffic on the robot's channels while the rig runs,
// once with the allow-list on and once with the shared key on: none of it reaches a node,
// every refusal is counted in the status, no process dies, and the map equals replay.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <atomic>
#include <fstream>
#include <map>
#include <set>
#include <thread>

#include "processes/channels.hpp"
#include "sweepmap/lidar_scan_t.hpp"
#include "sweepmap/scan_window_t.hpp"
#include "tests/e2e/fixtures.hpp"
#include "tools/bench/hostile_traffic.hpp"

namespace sweepmap {
namespace test {
namespace {

const std::string kRig = sourcePath("config/rig_a.yaml");
const std::string kScene = sourcePath("config/scene_conference_room.yaml");
// What the README's real setup uses, with sweepmap's larger receive buffer.
const std::string kUrl = "udpm://239.255.76.67:7667?ttl=1&recv_buf_size=2097152";
const VethEnd kPiEnd{"veth-pi", "10.77.0.1/24"};
const VethEnd kLaptopEnd{"veth-laptop", "10.77.0.2/24"};
const VethEnd kIntruderEnd{"veth-intruder", "10.77.0.3/24"};
const std::string kGroup = "239.255.76.67";
constexpr uint16_t kPort = 7667;
constexpr int kQueue = 7;

// How the link was impaired.
enum class Impairment { kNone, kNetem, kNfqueue };

struct RunResult {
  fs::path dir;
  Impairment impairment = Impairment::kNone;
  std::string impair_output;  // impair_link's counts
};

// Joins `hosts` to one Ethernet segment: a bridge (IGMP snooping off, so every multicast frame
// reaches every port, as on a plain switch) in `link`, and a veth from each host to it, the
// host's end with its address and the multicast route. False with the failing command.
bool joinOnBridge(const NetworkNamespace& link,
                  const std::vector<std::pair<const NetworkNamespace*, VethEnd>>& hosts,
                  std::string* why) {
  auto run = [why](const NetworkNamespace& ns, const std::vector<std::string>& cmd) {
    if (ns.command(cmd) == 0) return true;
    *why = "'" + cmd[0] + " " + cmd[1] + " " + cmd[2] + " " + cmd[3] + " ...' failed";
    return false;
  };
  if (!run(link, {"ip", "link", "add", "br0", "type", "bridge", "mcast_snooping", "0"}) ||
      !run(link, {"ip", "link", "set", "br0", "up"})) {
    return false;
  }
  for (size_t i = 0; i < hosts.size(); ++i) {
    const auto& [ns, end] = hosts[i];
    const std::string port = "port" + std::to_string(i);
    if (!run(*ns, {"ip", "link", "add", end.interface, "type", "veth", "peer", "name", port,
                   "netns", link.path()}) ||
        !run(link, {"ip", "link", "set", port, "master", "br0"}) ||
        !run(link, {"ip", "link", "set", port, "up"}) ||
        !run(*ns, {"ip", "addr", "add", end.address, "dev", end.interface}) ||
        !run(*ns, {"ip", "link", "set", end.interface, "up"}) ||
        !run(*ns, {"ip", "route", "add", "224.0.0.0/4", "dev", end.interface})) {
      return false;
    }
  }
  return true;
}

// A host on the link that publishes `datagrams` to LCM's group, pass after pass, from the
// time start() returns (the first pass sent whole by then) until stop().
class Intruder {
 public:
  Intruder(const NetworkNamespace& ns, std::vector<hostile::Bytes> datagrams)
      : datagrams_(std::move(datagrams)) {
    ns.run([&] { sender_ = std::make_unique<hostile::MulticastSender>(kGroup, kPort); });
  }
  ~Intruder() { stop(); }
  void start() {
    sent_ = sender_->send(datagrams_, kBurst, kPauseUs);
    passes_ = 1;
    thread_ = std::thread([this] {
      while (!stop_) {
        sleepS(0.1);  // a pass every ~0.1 s: hostile, not a CPU benchmark
        sender_->send(datagrams_, kBurst, kPauseUs);
        ++passes_;
      }
    });
  }
  // The passes sent.
  int stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
    return passes_;
  }
  size_t datagramsPerPass() const { return datagrams_.size(); }
  size_t sentInFirstPass() const { return sent_; }

 private:
  // ~10 000 datagrams a second at most: hostile, not a test of socket buffers.
  static constexpr int kBurst = 10, kPauseUs = 1000;
  std::vector<hostile::Bytes> datagrams_;
  std::unique_ptr<hostile::MulticastSender> sender_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<int> passes_{0};
  size_t sent_ = 0;
};

// How a run differs from the plain one.
struct RunOptions {
  bool impaired = false;
  // --allow-senders and --key-file, given to every process and recorder.
  std::vector<std::string> security;
  // Publishes from the start of the drivers to their end. The logs are then written by
  // `sweepmap record`: lcm-logger runs liblcm 1.3.1's receiver, which the intruder's first
  // crash datagram would kill.
  Intruder* intruder = nullptr;
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
  RunResult run(const std::string& name, const std::string& mode, int sweeps,
                const RunOptions& o = {}) {
    RunResult r;
    r.dir = scratchDir(name);
    const fs::path& dir = r.dir;
    procs_.setDir(dir);
    pid_t helper = -1;
    if (o.impaired) r.impairment = impair(&helper);
    std::vector<std::string> shared = {"--rig",     kRig, "--set", "motor.mode=" + mode,
                                       "--lcm-url", kUrl};
    shared.insert(shared.end(), o.security.begin(), o.security.end());
    const ProcessCommand proc(shared);
    NetworkNamespace* pi = pi_.get();
    NetworkNamespace* laptop = laptop_.get();
    // Each subscriber has bound its socket before the next starts, and all before the motor
    // sweeps (the lidar follows the motor's TRUTH_SHAFT).
    const auto subscriber = [&](const std::string& name, const std::vector<std::string>& argv,
                                NetworkNamespace* ns) {
      return procs_.startSubscriber(name, argv, kPort, 30.0, ns);
    };
    const pid_t pi_logger = subscriber("pi_logger", logger(dir, "pi.lcmlog", o), pi);
    const pid_t laptop_logger =
        subscriber("laptop_logger", logger(dir, "laptop.lcmlog", o), laptop);
    const pid_t assembler = subscriber("assembler", proc("assembler"), laptop);
    const pid_t mapper =
        subscriber("mapper", proc("mapper", {"--save", (dir / "live_map.bt").string()}), laptop);
    const pid_t lidar =
        subscriber("lidar", proc("lidar", {"--sim", "--scene", kScene, "--seed", "4"}), pi);
    if (o.intruder) o.intruder->start();
    const pid_t motor = procs_.start(
        "motor", proc("motor", {"--sim", "--sweeps", std::to_string(sweeps), "--seed", "4"}), pi);
    EXPECT_EQ(procs_.wait(motor, 120.0), 0) << procs_.said(motor);
    if (o.intruder) o.intruder->stop();
    std::vector<Stop> stops = {
        {lidar, 5.0}, {assembler, 10.0}, {mapper, 60.0}, {laptop_logger, 10.0}, {pi_logger, 10.0}};
    if (helper > 0) stops.push_back({helper, 5.0});
    procs_.stopInOrder(stops, 0.8);  // after the last scans are delivered
    if (helper > 0) r.impair_output = procs_.said(helper);
    std::vector<std::string> replay = {"--rig", kRig, "--set", "motor.mode=" + mode};
    EXPECT_EQ(replayInto(dir / "offline", (dir / "laptop.lcmlog").string(), replay), 0)
        << readFile(dir / "replay.txt");
    return r;
  }

  // The Pi's log holds what it sent (its scans and windows), the laptop's everything: written
  // by lcm-logger, or by `sweepmap record` (with the run's --allow-senders and --key-file)
  // where an intruder sends.
  static std::vector<std::string> logger(const fs::path& dir, const std::string& name,
                                         const RunOptions& o) {
    const bool pi_side = name == "pi.lcmlog";
    if (!o.intruder) {
      return loggerCommand(kUrl, (dir / name).string(), pi_side ? "LIDAR_SCAN|SCAN_WINDOW" : "");
    }
    std::vector<std::string> argv = {binPath("sweepmap"),
                                     "record",
                                     "--preset",
                                     pi_side ? "raw" : "all",
                                     "--out",
                                     dir.string(),
                                     "--name",
                                     name,
                                     "--lcm-url",
                                     kUrl};
    argv.insert(argv.end(), o.security.begin(), o.security.end());
    return argv;
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
  const RunResult r = run("two_hosts_clean", "1", 2);
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
  RunOptions lossy;
  lossy.impaired = true;
  const RunResult r = run("two_hosts_lossy", "4", 3, lossy);
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

// ---- An intruder on the link -------------------------------------------------------------

// The Pi, the laptop and an intruder on one segment: a bridge in a fourth namespace.
class IntruderTest : public TwoHostsTest {
 protected:
  void SetUp() override {
    std::string why;
    for (auto* ns : {&pi_, &laptop_, &intruder_, &link_}) {
      *ns = NetworkNamespace::create(&why);
      if (!*ns) GTEST_SKIP() << "no network namespaces: " << why;
    }
    ASSERT_TRUE(joinOnBridge(
        *link_, {{pi_.get(), kPiEnd}, {laptop_.get(), kLaptopEnd}, {intruder_.get(), kIntruderEnd}},
        &why))
        << why;
  }

  // One pass of the intruder's traffic on the channels the robot uses: liblcm 1.3.1's crash
  // datagrams and other malformed ones; well-formed datagrams whose messages break decoders
  // (a string length of INT32_MIN, 2^26 counters, a detail that is not UTF-8, MAP_SAVE
  // requests); and another run's sweep, each message unsigned and signed with a wrong key.
  std::vector<hostile::Bytes> attack() {
    const std::vector<std::string> channels = {channels::kLidarScan,  channels::kScanWindow,
                                               channels::kSweepCloud, channels::kMapSave,
                                               channels::kMotorState, "STATUS_ASSEMBLER"};
    std::vector<hostile::Bytes> pass = hostile::malformedDatagrams(channels, 200, 21);
    malformed_ = pass.size();
    const std::string other_run = cachedSimLog(
        "intruder_other_run",
        {"--rig", kRig, "--scene", kScene, "--mode", "1", "--sweeps", "1", "--seed", "99"});
    std::vector<hostile::Forged> forged = hostile::messagesOfLog(
        other_run, {channels::kLidarScan, channels::kScanWindow, channels::kMotorState});
    for (hostile::Forged& m : hostile::decoderBreakers()) forged.push_back(std::move(m));
    const size_t unsigned_forged = forged.size();
    for (size_t i = 0; i < unsigned_forged; ++i)
      forged.push_back(hostile::wronglySigned(forged[i]));
    forged_ = forged.size();
    for (const hostile::Forged& m : forged) forged_payloads_.insert(m.payload);
    for (hostile::Bytes& d : hostile::datagramsOf(forged, 1000)) pass.push_back(std::move(d));
    return pass;
  }

  size_t malformed_ = 0;  // malformed datagrams per pass
  size_t forged_ = 0;     // well-formed messages per pass, each in one datagram or more
  std::set<hostile::Bytes> forged_payloads_;
  std::unique_ptr<NetworkNamespace> intruder_, link_;

  void expectNothingReachedANode(const fs::path& dir) const;
};

// Every process of the run, on both hosts: each hears the whole link.
const char* const kEveryStatus[] = {"STATUS_ASSEMBLER", "STATUS_MAPPER", "STATUS_LIDAR",
                                    "STATUS_MOTOR"};

// The laptop's scans come from the Pi's lidar alone: one scan counter, rising, and plenty of
// scans. (Not compared with the Pi's log one for one: a flood that fills a socket buffer on a
// loaded machine may cost either recorder a scan, and that is no forgery.)
::testing::AssertionResult scansOfOneLidar(const std::string& log) {
  int64_t last = -1;
  size_t n = 0;
  for (const auto& m : readChannel(log, channels::kLidarScan)) {
    lidar_scan_t scan;
    if (!decodeMessage(m, &scan)) return ::testing::AssertionFailure() << "scan " << n << " bad";
    if (scan.seq <= last) {
      return ::testing::AssertionFailure() << "scan " << n << ": counter " << scan.seq << " after "
                                           << last << ": another sender's scan";
    }
    last = scan.seq;
    ++n;
  }
  if (n < 100) return ::testing::AssertionFailure() << "only " << n << " scans";
  return ::testing::AssertionSuccess() << n << " scans of one lidar";
}

// Nothing the intruder sent reached a node: every process lived (stopInOrder checks their exit
// statuses); no message the intruder forged is in either host's log, and the laptop's scans
// are the Pi's; no node counted an invalid or refused message (those would have got past the
// transport); no MAP_SAVE was honoured; and the live map is the replay's (had a node taken
// what the recorder refused, it would differ).
void IntruderTest::expectNothingReachedANode(const fs::path& dir) const {
  const nlohmann::json summary = readJson(dir / "offline" / "summary.json");
  EXPECT_EQ(summary["sweeps"].size(), 2u) << readFile(dir / "replay.txt");
  for (const char* log : {"laptop.lcmlog", "pi.lcmlog"}) {
    size_t forged = 0;
    for (const hostile::Forged& m : hostile::messagesOfLog((dir / log).string(), {})) {
      forged += forged_payloads_.count(m.payload);
    }
    EXPECT_EQ(forged, 0u) << log << " holds forged messages";
  }
  EXPECT_TRUE(scansOfOneLidar((dir / "laptop.lcmlog").string()));
  for (const char* status : kEveryStatus) {
    const LastStatus s = lastStatus((dir / "laptop.lcmlog").string(), status);
    ASSERT_TRUE(s.found) << status;
    for (const auto& [name, value] : s.counters) {
      const bool node_refused = name.rfind("invalid", 0) == 0 ||
                                name.rfind("stamp_refused", 0) == 0 || name == "refused_saves" ||
                                name == "errors";
      EXPECT_FALSE(node_refused && value != 0) << status << ": " << name << " = " << value;
    }
  }
  for (const fs::path& p : {dir / "intruder.bt", dir.parent_path() / "intruder.bt"}) {
    EXPECT_FALSE(fs::exists(p)) << p;
  }
  expectLiveMapEqualsReplay(dir);
}

TEST_F(IntruderTest, WithTheAllowListNothingTheIntruderSendsReachesANode) {
  Intruder intruder(*intruder_, attack());
  RunOptions o;
  o.security = {"--allow-senders", "10.77.0.1,10.77.0.2"};
  o.intruder = &intruder;
  const RunResult r = run("two_hosts_intruder_allow_list", "1", 2, o);
  std::cout << "intruder: " << intruder.stop() << " passes of " << intruder.datagramsPerPass()
            << " datagrams\n";
  ASSERT_EQ(intruder.sentInFirstPass(), intruder.datagramsPerPass());
  expectNothingReachedANode(r.dir);
  // Every datagram from the intruder's address was dropped before it was read: none was
  // refused as malformed or unsigned, for none was looked at.
  for (const char* status : kEveryStatus) {
    const LastStatus s = lastStatus((r.dir / "laptop.lcmlog").string(), status);
    EXPECT_GE(s.counter("net_not_allowed"), static_cast<int64_t>(intruder.datagramsPerPass()))
        << status;
    EXPECT_EQ(s.counter("net_refused"), 0) << status;
    EXPECT_EQ(s.counter("net_not_signed"), 0) << status;
  }
}

TEST_F(IntruderTest, WithTheKeyNothingTheIntruderSendsReachesANode) {
  const fs::path key = scratchDir("two_hosts_intruder_key_file") / "lcm.key";
  std::ofstream(key) << std::string(64, 'c') << "\n";
  ASSERT_EQ(::chmod(key.c_str(), 0600), 0);
  Intruder intruder(*intruder_, attack());
  RunOptions o;
  o.security = {"--key-file", key.string()};
  o.intruder = &intruder;
  const RunResult r = run("two_hosts_intruder_key", "1", 2, o);
  std::cout << "intruder: " << intruder.stop() << " passes of " << intruder.datagramsPerPass()
            << " datagrams\n";
  ASSERT_EQ(intruder.sentInFirstPass(), intruder.datagramsPerPass());
  expectNothingReachedANode(r.dir);
  // Heard from every address: the malformed datagrams refused by the receive path (by
  // reason), every well-formed forged message refused as unsigned or wrongly signed.
  for (const char* status : kEveryStatus) {
    const LastStatus s = lastStatus((r.dir / "laptop.lcmlog").string(), status);
    EXPECT_EQ(s.counter("net_not_allowed"), 0) << status;
    EXPECT_GE(s.counter("net_refused_fragment_out_of_range"), 6) << status;
    EXPECT_GE(s.counter("net_refused_channel_unterminated"), 6) << status;
    EXPECT_GE(s.counter("net_not_signed"), static_cast<int64_t>(forged_)) << status;
  }
}

}  // namespace
}  // namespace test
}  // namespace sweepmap
