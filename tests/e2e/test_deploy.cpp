// Deployment faults, in a private network namespace this test creates:
// - `sweepmap systemd` units pass `systemd-analyze verify`;
// - under `sweepmap launch`, kill -9 of each process of a live rig-A run: restarted within
//   2 s, the last saved map still loads, sweeps resume; a hung process (SIGSTOP) is killed by
//   the watchdog and restarted; a failing one backs off; one that exits 0 is not restarted;
// - a message storm (a log played at 10x speed) into the assembler and mapper: bounded
//   queues, drops counted in STATUS, memory bounded;
// - disk full while saving a map (a small tmpfs in a private mount namespace): a clear error
//   naming the file, the previous map intact.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/mount.h>
#include <sys/statvfs.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <iostream>
#include <lcm/lcm-cpp.hpp>
#include <regex>
#include <thread>

#include "core/event_log.hpp"
#include "mapping/occupancy_map.hpp"
#include "processes/channels.hpp"
#include "sweepmap/map_save_t.hpp"
#include "sweepmap/map_stats_t.hpp"
#include "tests/e2e/fixtures.hpp"
#include "tools/ops/deploy.hpp"
#include "tools/ops/systemd_units.hpp"

namespace sweepmap {
namespace test {
namespace {

using Clock = std::chrono::steady_clock;
const std::string kRig = sourcePath("config/rig_a.yaml");
const std::string kScene = sourcePath("config/scene_conference_room.yaml");
const std::string kUrl = kDefaultLcmUrl;

double since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// Polls `done` every 20 ms for up to timeout_s.
bool waitFor(const std::function<bool()>& done, double timeout_s) {
  const auto t0 = Clock::now();
  while (!done()) {
    if (since(t0) > timeout_s) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return true;
}

// Output of a shell command (stdout and stderr) and its exit status.
std::pair<int, std::string> shell(const std::string& command) {
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  std::string out;
  char buffer[512];
  while (pipe && fgets(buffer, sizeof buffer, pipe) != nullptr) out += buffer;
  const int status = pipe ? pclose(pipe) : -1;
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

// Resident memory of a process [MB] from /proc (0 if it is gone).
double rssMb(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("VmRSS:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  }
  return 0.0;
}

class DeployTest : public PrivateNetworkTest {
 protected:
  // A rig-A process for a deployment file: sweepmap-NAME args in YAML flow syntax.
  static std::string rigProcess(const std::string& name, const std::string& extra) {
    return "      - {name: " + name + ", command: sweepmap-" + name + ", args: [--rig, " + kRig +
           ", --set, motor.mode=1, --set, motor.rehome_every_sweep=false" + extra + "]}\n";
  }
  static std::string deployFile(const fs::path& dir, const std::string& processes,
                                double watchdog_s = 3.0) {
    const fs::path path = dir / "deploy.yaml";
    std::ofstream(path) << "lcm_url: " << kUrl << "\n"
                        << "restart: {delay_s: 0.5, max_delay_s: 10, stable_s: 60, watchdog_s: "
                        << watchdog_s << ", stop_timeout_s: 10}\n"
                        << "hosts:\n  bench:\n    address: 127.0.0.1\n    processes:\n"
                        << processes;
    return path.string();
  }

  // `sweepmap launch DEPLOY --log-dir DIR/logs` in the background.
  void startLaunch(const fs::path& dir, const std::string& deploy) {
    dir_ = dir;
    procs_.setDir(dir);
    launch_ = procs_.start("launch_out", {binPath("sweepmap"), "launch", deploy, "--log-dir",
                                          (dir / "logs").string()});
  }
  std::string events() const { return readFile(dir_ / "logs" / "launch.txt"); }
  // The pid of `name`'s latest start (-1 if none).
  pid_t pidOf(const std::string& name) const {
    const std::string text = events();
    const std::regex start("start +" + name + " \\(pid ([0-9]+)\\)");
    pid_t pid = -1;
    for (auto it = std::sregex_iterator(text.begin(), text.end(), start);
         it != std::sregex_iterator(); ++it) {
      pid = std::stoi((*it)[1]);
    }
    return pid;
  }
  bool saidReady(const std::string& name, pid_t pid) const {
    return events().find("ready    " + name + " (pid " + std::to_string(pid) + ")") !=
           std::string::npos;
  }

  fs::path dir_;
  Launcher procs_;
  pid_t launch_ = -1;
};

// The units of every host of the shipped deployment files pass `systemd-analyze verify`
// (which also checks that ExecStart's executables exist: those of this build), with nothing
// said: verify exits 0 on unknown keys and bad values but warns about them.
TEST_F(DeployTest, SystemdUnitsPassSystemdAnalyzeVerify) {
  const auto dir = scratchDir("deploy_systemd");
  ASSERT_EQ(shell("command -v systemd-analyze").first, 0)
      << "systemd-analyze is missing (package systemd, tools/ops/setup.sh)";
  for (const std::string file : {"deploy_rig_a", "deploy_rig_b"}) {
    const Deployment d = loadDeployment(sourcePath("config/" + file + ".yaml"));
    for (const auto& host : d.hosts) {
      const fs::path out = dir / file / host.name;
      ASSERT_EQ(sweepmap({"systemd", d.path, "--host", host.name, "--out", out.string(),
                          "--bin-dir", fs::path(binPath("sweepmap")).parent_path().string()},
                         dir / "systemd.txt"),
                0)
          << readFile(dir / "systemd.txt");
      std::string units;
      for (const auto& p : host.processes)
        units += " " + (out / ("sweepmap-" + p.name + ".service")).string();
      units += " " + (out / ("sweepmap-" + host.name + ".target")).string();
      const auto [status, said] = shell("systemd-analyze verify" + units);
      EXPECT_EQ(status, 0) << file << " " << host.name << ": " << said;
      EXPECT_EQ(said, "") << file << " " << host.name;
    }
  }
  // A unit verify rejects, so the check above can fail: an executable that is not there.
  const Deployment d = loadDeployment(sourcePath("config/deploy_rig_a.yaml"));
  writeSystemdUnits(d, "pi", "/nonexistent/bin", (dir / "bad").string());
  const auto [status, said] =
      shell("systemd-analyze verify " + (dir / "bad" / "sweepmap-motor.service").string());
  EXPECT_NE(status, 0);
  EXPECT_NE(said.find("/nonexistent/bin/sweepmap-motor"), std::string::npos) << said;
}

TEST_F(DeployTest, LaunchRejectsABadFileNamingTheKey) {
  const auto dir = scratchDir("deploy_bad");
  std::ofstream(dir / "deploy.yaml") << "lcm_url: x\nrestart: {delay_s: 1}\nhosts: {}\n";
  EXPECT_EQ(sweepmap({"launch", (dir / "deploy.yaml").string()}, dir / "out.txt"), 2);
  EXPECT_NE(readFile(dir / "out.txt").find("deploy.yaml:2:10: key 'restart.max_delay_s': missing"),
            std::string::npos)
      << readFile(dir / "out.txt");
  EXPECT_EQ(sweepmap({"launch", sourcePath("config/deploy_rig_a.yaml"), "--host", "robot"},
                     dir / "host.txt"),
            2);
  EXPECT_NE(readFile(dir / "host.txt").find("no host 'robot' (hosts: laptop, pi)"),
            std::string::npos);
}

// A process that fails at once is restarted after 0.5, 1, 2 s...; one that exits 0 has
// finished and is not restarted; a program that is not there is retried the same way.
TEST_F(DeployTest, LaunchBacksOffAFailingProcessAndLeavesAFinishedOne) {
  const auto dir = scratchDir("deploy_backoff");
  startLaunch(dir, deployFile(dir,
                              "      - {name: failing, command: \"false\"}\n"
                              "      - {name: done, command: \"true\"}\n"
                              "      - {name: missing, command: /nonexistent/program}\n"));
  ASSERT_TRUE(waitFor(
      [&] {
        const std::string e = events();
        return e.find("restart  failing in 2 s") != std::string::npos &&
               e.find("restart  missing in 2 s") != std::string::npos;
      },
      20))
      << events();
  EXPECT_EQ(procs_.stop(launch_, 10), 0);
  const std::string e = events();
  const auto first = e.find("restart  failing in 0.5 s (failure 1 in a row)");
  const auto second = e.find("restart  failing in 1 s (failure 2 in a row)");
  const auto third = e.find("restart  failing in 2 s (failure 3 in a row)");
  EXPECT_TRUE(first < second && second < third && third != std::string::npos) << e;
  EXPECT_NE(e.find("exit status 1"), std::string::npos) << e;
  EXPECT_NE(e.find("finished done exited 0: not restarted"), std::string::npos) << e;
  // A program that is not there is one error per attempt, retried with the same backoff.
  EXPECT_NE(e.find("error    missing cannot start missing (/nonexistent/program)"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("restart  missing in 1 s (failure 2 in a row)"), std::string::npos) << e;
  const std::regex starts("start +done ");
  EXPECT_EQ(std::distance(std::sregex_iterator(e.begin(), e.end(), starts), std::sregex_iterator()),
            1);
}

// A closed ssh session (SIGHUP to launch) stops every child in order; launch killed outright
// (SIGKILL, no chance to stop anything) still leaves no child running: each gets SIGTERM
// from the kernel when its parent dies (PR_SET_PDEATHSIG).
TEST_F(DeployTest, LaunchStopsItsChildrenOnHangUpAndWhenKilled) {
  for (const int signal : {SIGHUP, SIGKILL}) {
    const auto dir = scratchDir(signal == SIGHUP ? "deploy_hup" : "deploy_kill_launch");
    startLaunch(dir, deployFile(dir, rigProcess("assembler", "") + rigProcess("mapper", "")));
    pid_t assembler = -1, mapper = -1;
    ASSERT_TRUE(waitFor(
        [&] {
          assembler = pidOf("assembler");
          mapper = pidOf("mapper");
          return assembler > 0 && mapper > 0 && saidReady("assembler", assembler) &&
                 saidReady("mapper", mapper);
        },
        15))
        << events();
    ASSERT_EQ(::kill(launch_, signal), 0);
    const int status = procs_.wait(launch_, 20);
    EXPECT_EQ(status, signal == SIGHUP ? 0 : 128 + SIGKILL) << events();
    for (const pid_t child : {assembler, mapper}) {
      EXPECT_TRUE(waitFor([&] { return ::kill(child, 0) != 0; }, 10))
          << "child " << child << " outlived launch (" << strsignal(signal) << ")";
    }
    if (signal == SIGHUP) {
      EXPECT_NE(events().find("launch   stopped"), std::string::npos) << events();
    }
  }
}

// A process whose worker stops (SIGSTOP: no more WATCHDOG=1) is killed after watchdog_s and
// restarted; while it runs normally its pings keep the watchdog quiet.
TEST_F(DeployTest, LaunchWatchdogRestartsAHungProcess) {
  const auto dir = scratchDir("deploy_watchdog");
  startLaunch(dir, deployFile(dir, rigProcess("assembler", ""), 2.0));
  pid_t pid = -1;
  ASSERT_TRUE(
      waitFor([&] { return (pid = pidOf("assembler")) > 0 && saidReady("assembler", pid); }, 10))
      << events();
  std::this_thread::sleep_for(std::chrono::milliseconds(4500));  // 2.25 watchdog intervals
  EXPECT_EQ(events().find("watchdog assembler"), std::string::npos) << events();
  ::kill(pid, SIGSTOP);
  const auto t0 = Clock::now();
  ASSERT_TRUE(waitFor([&] { return pidOf("assembler") != pid; }, 10)) << events();
  const double restart_s = since(t0);
  const pid_t next = pidOf("assembler");
  EXPECT_TRUE(waitFor([&] { return saidReady("assembler", next); }, 10)) << events();
  EXPECT_EQ(procs_.stop(launch_, 20), 0);
  const std::string e = events();
  EXPECT_NE(e.find("watchdog assembler (pid " + std::to_string(pid) + "): no WATCHDOG=1 for"),
            std::string::npos)
      << e;
  EXPECT_NE(
      e.find("exit     assembler (pid " + std::to_string(pid) + ") killed by signal 9 (SIGKILL)"),
      std::string::npos)
      << e;
  std::cout << "watchdog: hung assembler restarted " << restart_s
            << " s after SIGSTOP (watchdog 2 s, restart delay 0.5 s)\n";
}

// The processes whose command line has `program` and `needle` (scanning /proc).
int processesWith(const std::string& program, const std::string& needle) {
  int n = 0;
  for (const auto& entry : fs::directory_iterator("/proc")) {
    const std::string pid = entry.path().filename().string();
    if (pid.find_first_not_of("0123456789") != std::string::npos) continue;
    std::string cmdline = readFile(entry.path() / "cmdline");
    std::replace(cmdline.begin(), cmdline.end(), '\0', ' ');
    n += cmdline.find(program) != std::string::npos && cmdline.find(needle) != std::string::npos;
  }
  return n;
}

// kill -9 of each process of a live rig-A run (mode 1, simulated devices) under `sweepmap
// launch`: each is restarted within 2 s (the bound; measured from the kill to
// launch's `start` line and to the new process's READY=1); the map the mapper saved before
// its kill is kept and loads; sweeps resume through the restarted processes (the restarted
// mapper saves a new map); no second recorder outlives the killed one (launch kills
// its process group), and its file reads to its last complete event.
TEST_F(DeployTest, KillNineOfEachProcessUnderLaunch) {
  const auto dir = scratchDir("deploy_kill");
  const std::string map = (dir / "map.bt").string();
  const fs::path rec = dir / "rec";
  const std::string processes =
      "      - {name: recorder, command: sweepmap, notify: true, args: [record, --preset, all, "
      "--out, " +
      rec.string() + ", --split-mb, \"1000\", --min-free-mb, \"1\"]}\n" +
      rigProcess("mapper", ", --save, " + map + ", --save-every, \"1\"") +
      rigProcess("assembler", "") +
      rigProcess("lidar", ", --sim, --scene, " + kScene + ", --seed, \"3\"") +
      rigProcess("motor", ", --sim, --seed, \"3\"");
  startLaunch(dir, deployFile(dir, processes));
  ASSERT_TRUE(waitFor([&] { return fs::exists(map); }, 60)) << "no map saved\n" << events();
  EXPECT_EQ(processesWith("sweepmap record", rec.string()), 1);

  for (const std::string name : {"motor", "lidar", "assembler", "recorder", "mapper"}) {
    const pid_t pid = pidOf(name);
    ASSERT_GT(pid, 0) << name;
    ASSERT_EQ(::kill(pid, SIGKILL), 0) << name;
    const auto t0 = Clock::now();
    ASSERT_TRUE(waitFor([&] { return pidOf(name) != pid; }, 10)) << name << "\n" << events();
    const double start_s = since(t0);
    const pid_t next = pidOf(name);
    EXPECT_TRUE(waitFor([&] { return saidReady(name, next); }, 10)) << name << "\n" << events();
    const double ready_s = since(t0);
    std::cout << "kill -9 " << name << ": restarted after " << start_s << " s, READY=1 after "
              << ready_s << " s\n";
    EXPECT_LE(start_s, 2.0) << name;
    EXPECT_LE(ready_s, 2.0) << name;
    EXPECT_NE(events().find("exit     " + name + " (pid " + std::to_string(pid) +
                            ") killed by signal 9 (SIGKILL)"),
              std::string::npos)
        << events();
  }
  // One recorder: the killed one is gone, its successor records.
  EXPECT_EQ(processesWith("sweepmap record", rec.string()), 1);
  // The map of the killed mapper: kept by its successor under a dated name, and it loads.
  std::vector<fs::path> kept;
  for (const auto& f : fs::directory_iterator(dir)) {
    const std::string n = f.path().filename().string();
    if (n.rfind("map.", 0) == 0 && n != "map.bt" && f.path().extension() == ".bt") {
      kept.push_back(f.path());
    }
  }
  ASSERT_EQ(kept.size(), 1u) << "the killed mapper's map was not kept";
  EXPECT_GT(OccupancyMap::loadBinary(kept[0].string()).stats().occupied_voxels, 1000);
  // Sweeps resume: the restarted motor, lidar and assembler feed the restarted mapper, which
  // saves its first sweep.
  EXPECT_TRUE(waitFor([&] { return fs::exists(map); }, 60)) << "no sweep after the restarts";
  EXPECT_EQ(procs_.stop(launch_, 60), 0) << events();
  EXPECT_GT(OccupancyMap::loadBinary(map).stats().occupied_voxels, 1000);
  // Both recordings, the killed recorder's and its successor's, read to their last complete
  // event (with --split-mb the restarted one writes the next file, as lcm-logger -i).
  for (const char* log : {"run.00", "run.01"}) {
    EventLogReader r((rec / log).string());
    r.setResync(true);
    LogEvent e;
    int events_read = 0;
    while (r.next(&e)) ++events_read;
    EXPECT_GT(events_read, 100) << log;
  }
  EXPECT_EQ(lastStatus((rec / "run.01").string(), "STATUS_MAPPER").message.process, "mapper");
}

// The rig-A log of both message tests: 8 sweeps in mode 1, made once per build.
std::string stormLog() {
  return cachedSimLog("storm_rig_a",
                      {"--rig", kRig, "--scene", kScene, "--mode", "1", "--sweeps", "8", "--seed",
                       "6", "--set", "motor.rehome_every_sweep=false"});
}

// Resident memory of the assembler and the mapper [MB], every 50 ms while the player plays
// (120 s at most), and how long it played.
struct RssTrace {
  std::vector<double> assembler, mapper;
  double play_s = 0.0;
};
RssTrace traceRss(Launcher& procs, pid_t player, pid_t assembler, pid_t mapper) {
  RssTrace rss;
  const auto t0 = Clock::now();
  while (procs.running(player) && since(t0) < 120) {
    rss.assembler.push_back(rssMb(assembler));
    rss.mapper.push_back(rssMb(mapper));
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  rss.play_s = since(t0);
  return rss;
}

// The last total a process said in "receive queue full: N messages dropped so far" (0: none).
int64_t droppedSaid(const std::string& said) {
  const std::regex total("receive queue full: ([0-9]+) messages dropped so far");
  int64_t last = 0;
  for (auto it = std::sregex_iterator(said.begin(), said.end(), total);
       it != std::sregex_iterator(); ++it) {
    last = std::stoll((*it)[1]);
  }
  return last;
}

double peak(const std::vector<double>& v) { return *std::max_element(v.begin(), v.end()); }

// A log played at 10x speed into the assembler and mapper, each with a receive queue of 2
// messages: both keep running and publishing their status; what the full queue refuses is
// counted (`dropped` in STATUS, the same total as printed); whether it overflows depends on the
// machine's load, so the count is checked, not its size (tests/processes/test_live_runner.cpp
// overflows a queue deterministically); memory stays bounded and flat.
TEST_F(DeployTest, MessageStormAtTenTimesSpeed) {
  const auto dir = scratchDir("deploy_storm");
  procs_.setDir(dir);
  const std::string sim_log = stormLog();
  const std::string rec = (dir / "status.lcmlog").string();
  const ProcessCommand proc({"--rig", kRig, "--set", "motor.mode=1", "--set",
                             "motor.rehome_every_sweep=false", "--lcm-url", kUrl,
                             "--queue-capacity", "20"});
  // Each is waited for until it listens, however loaded the machine is.
  const pid_t logger = procs_.startSubscriber(
      "logger", loggerCommand(kUrl, rec, "STATUS_.*|MAP_STATS"), kDefaultLcmPort);
  const pid_t assembler = procs_.startSubscriber("assembler", proc("assembler"), kDefaultLcmPort);
  const pid_t mapper = procs_.startSubscriber(
      "mapper", proc("mapper", {"--save", (dir / "map.bt").string()}), kDefaultLcmPort);
  const pid_t player = procs_.start("logplayer", playerCommand(kUrl, sim_log, {"--speed=10"}));
  const RssTrace rss = traceRss(procs_, player, assembler, mapper);
  ASSERT_EQ(procs_.wait(player, 1), 0) << procs_.said(player);
  sleepS(1.5);
  EXPECT_TRUE(procs_.running(assembler)) << procs_.said(assembler);
  EXPECT_TRUE(procs_.running(mapper)) << procs_.said(mapper);
  procs_.stopInOrder({{assembler, 10}, {mapper, 30}, {logger, 10}});

  ASSERT_GT(rss.assembler.size(), 10u);
  const size_t third = rss.assembler.size() / 3;
  const double assembler_early =
      *std::max_element(rss.assembler.begin(), rss.assembler.begin() + third);
  const LastStatus a = lastStatus(rec, "STATUS_ASSEMBLER"), m = lastStatus(rec, "STATUS_MAPPER");
  const int64_t a_dropped = a.counter("dropped"), m_dropped = m.counter("dropped");
  std::cout << "storm: " << rss.play_s
            << " s of play at 10x; assembler: " << a.counter("messages_in") << " messages in, "
            << a_dropped << " dropped, peak RSS " << peak(rss.assembler) << " MB (first third "
            << assembler_early << " MB); mapper: " << m.counter("messages_in") << " in, "
            << m_dropped << " dropped, peak RSS " << peak(rss.mapper) << " MB\n";
  // Statuses kept coming while the storm lasted (1 Hz each).
  EXPECT_GE(readChannel(rec, "STATUS_ASSEMBLER").size(), static_cast<size_t>(rss.play_s) - 1);
  // Handled + dropped by the full queue never exceed what was played; the rest was lost before
  // it reached the process (the socket's or LCM's own buffer under load: not ours to count).
  int64_t played = 0;
  for (const char* ch : {channels::kLidarScan, channels::kScanWindow}) {
    played += static_cast<int64_t>(readChannel(sim_log, ch).size());
  }
  const int64_t reached = a.counter("messages_in") + a_dropped;
  std::cout << "storm: " << played << " messages played to the assembler, " << reached
            << " reached it\n";
  EXPECT_LE(reached, played);
  EXPECT_GT(reached, played / 2);
  // Drops are counted in STATUS and said on stderr with the same total.
  EXPECT_EQ(droppedSaid(procs_.said(assembler)), a_dropped) << "assembler";
  EXPECT_EQ(droppedSaid(procs_.said(mapper)), m_dropped) << "mapper";
  // Bounded: a queue of 2 messages; the map of 8 sweeps. Flat: the assembler's memory at the
  // end of the storm is within 50 MB of its first third's peak.
  EXPECT_LT(peak(rss.assembler), 300.0);
  EXPECT_LT(peak(rss.mapper), 600.0);
  EXPECT_LT(rss.assembler.back(), assembler_early + 50.0);
}

// Disk full while saving a map: the mapper's map on a 4 MB tmpfs in a private mount
// namespace; once the disk has less room than a map, MAP_SAVE and the save at shutdown fail
// with one clear error naming the file, the mapper goes on (exit status 1 at the end, saying
// so), and the map saved before is intact: the same bytes, no temporary left, it loads.
TEST_F(DeployTest, DiskFullWhileSavingAMapKeepsThePreviousMap) {
  const auto dir = scratchDir("deploy_disk_full");
  procs_.setDir(dir);
  const fs::path disk = dir / "disk";
  fs::create_directories(disk);
  std::string why;
  if (!mountPrivateTmpfs(disk, "4m", &why)) GTEST_SKIP() << "no private mount namespace: " << why;
  const fs::path replayed = cachedReplay("deploy_disk_full_replay", stormLog(),
                                         {"--rig", kRig, "--set", "motor.mode=1", "--set",
                                          "motor.rehome_every_sweep=false", "--no-plots"});
  const std::string map = (disk / "map.bt").string();
  const pid_t mapper = procs_.startSubscriber(
      "mapper", {binPath("sweepmap-mapper"), "--rig", kRig, "--lcm-url", kUrl, "--save", map},
      kDefaultLcmPort);
  ASSERT_EQ(procs_.play(kUrl, (replayed / "derived.lcmlog").string(), 120,
                        {"--speed=10", "--regexp=SWEEP_.*"}),
            0);
  sleepS(0.5);
  lcm::LCM lcm(kUrl);
  ASSERT_TRUE(lcm.good());
  map_save_t save;
  save.utime = 0;
  lcm.publish(channels::kMapSave, &save);
  ASSERT_TRUE(waitFor([&] { return fs::exists(map); }, 20)) << procs_.said(mapper);
  const std::string saved = readFile(map);
  ASSERT_GT(saved.size(), 10000u);

  // Fill the disk, leaving room for half a map.
  struct statvfs fsinfo {};
  ASSERT_EQ(::statvfs(disk.c_str(), &fsinfo), 0);
  const size_t free_bytes = fsinfo.f_bavail * fsinfo.f_frsize;
  ASSERT_GT(free_bytes, saved.size() / 2);
  std::ofstream(disk / "filler", std::ios::binary)
      << std::string(free_bytes - saved.size() / 2, 'x');
  sleepS(1.1);  // MAP_SAVE is a request from the network: at most one a second is honoured
  lcm.publish(channels::kMapSave, &save);
  const std::string error = "cannot save " + map + ": write failed: No space left on device";
  EXPECT_TRUE(waitFor([&] { return procs_.said(mapper).find(error) != std::string::npos; }, 20))
      << procs_.said(mapper);
  EXPECT_TRUE(procs_.running(mapper));
  EXPECT_EQ(procs_.stop(mapper, 30), 4);  // the save at shutdown failed too: an I/O failure
  const std::string said = procs_.said(mapper);
  EXPECT_NE(said.find("saves failed (see above); the map file holds the last good save"),
            std::string::npos)
      << said;
  EXPECT_TRUE(readFile(map) == saved) << "the previous map changed";
  EXPECT_FALSE(fs::exists(map + ".tmp"));
  EXPECT_GT(OccupancyMap::loadBinary(map).stats().occupied_voxels, 1000);
  ::umount(disk.c_str());
}

}  // namespace
}  // namespace test
}  // namespace sweepmap
