#include "tests/e2e/test_support.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <limits>
#include <sstream>

#include "core/event_log.hpp"
#include "mapping/cloud_io.hpp"
#include "sweepmap/truth_profile_rig_t.hpp"

extern char** environ;

namespace sweepmap {
namespace test {

std::string sourcePath(const std::string& rel) {
  return std::string(SWEEPMAP_SOURCE_DIR) + "/" + rel;
}
std::string binPath(const std::string& name) {
  return std::string(SWEEPMAP_BINARY_DIR) + "/bin/" + name;
}

fs::path scratchDir(const std::string& name) {
  const fs::path p = fs::path(SWEEPMAP_BINARY_DIR) / "test_scratch" / name;
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}

int sweepmap(const std::vector<std::string>& args, const fs::path& out_file) {
  return sweepmapIn({}, args, out_file);
}

int sweepmapIn(const fs::path& cwd, const std::vector<std::string>& args,
               const fs::path& out_file) {
  return runIn(cwd, "sweepmap", args, out_file);
}

int runIn(const fs::path& cwd, const std::string& exe, const std::vector<std::string>& args,
          const fs::path& out_file) {
  std::vector<std::string> argv = {binPath(exe)};
  argv.insert(argv.end(), args.begin(), args.end());
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  const std::string out = out_file.empty() ? "/dev/null" : out_file.string();
  posix_spawn_file_actions_addopen(&fa, 1, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&fa, 1, 2);
  if (!cwd.empty()) posix_spawn_file_actions_addchdir_np(&fa, cwd.c_str());
  std::vector<char*> cargs;
  for (auto& a : argv) cargs.push_back(a.data());
  cargs.push_back(nullptr);
  pid_t pid;
  if (posix_spawn(&pid, cargs[0], &fa, nullptr, cargs.data(), environ) != 0) return -1;
  posix_spawn_file_actions_destroy(&fa);
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string readFile(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::ostringstream s;
  s << f.rdbuf();
  return s.str();
}

nlohmann::json readJson(const fs::path& p) { return nlohmann::json::parse(readFile(p)); }

std::vector<Message> readChannel(const std::string& log, const std::string& channel) {
  std::vector<Message> out;
  EventLogReader r(log);
  LogEvent e;
  while (r.next(&e)) {
    if (e.channel == channel) out.push_back({e.utime, e.channel, e.data});
  }
  return out;
}

std::vector<pose2d_t> poses(const std::string& log, const std::string& channel) {
  std::vector<pose2d_t> out;
  for (const auto& m : readChannel(log, channel)) {
    pose2d_t p;
    if (decodeMessage(m, &p)) out.push_back(p);
  }
  return out;
}

double pathLength(const std::vector<pose2d_t>& p) {
  double l = 0;
  for (size_t i = 1; i < p.size(); ++i) {
    l += std::hypot(p[i].x_m - p[i - 1].x_m, p[i].y_m - p[i - 1].y_m);
  }
  return l;
}

TrackError trackError(const std::vector<pose2d_t>& track, const std::vector<pose2d_t>& truth) {
  TrackError e;
  double sum2 = 0.0;
  for (const pose2d_t& p : track) {
    const auto it = std::lower_bound(truth.begin(), truth.end(), p.utime,
                                     [](const pose2d_t& t, int64_t u) { return t.utime < u; });
    if (it == truth.begin() || it == truth.end()) continue;
    const pose2d_t& a = *(it - 1);
    const pose2d_t& b = *it;
    const double f = double(p.utime - a.utime) / double(std::max<int64_t>(1, b.utime - a.utime));
    const double d =
        std::hypot(p.x_m - (a.x_m + f * (b.x_m - a.x_m)), p.y_m - (a.y_m + f * (b.y_m - a.y_m)));
    ++e.compared;
    e.max_m = std::max(e.max_m, d);
    sum2 += d * d;
    e.final_m = d;
  }
  if (e.compared > 0) e.rms_m = std::sqrt(sum2 / double(e.compared));
  return e;
}

double pathErrorMax(const std::vector<pose2d_t>& track, const std::vector<pose2d_t>& truth,
                    int64_t window_us) {
  const auto before = [](const pose2d_t& t, int64_t u) { return t.utime < u; };
  double worst = 0.0;
  for (const pose2d_t& p : track) {
    auto it = std::lower_bound(truth.begin(), truth.end(), p.utime - window_us, before);
    const auto end = std::lower_bound(truth.begin(), truth.end(), p.utime + window_us, before);
    if (it == end) continue;
    double best = std::numeric_limits<double>::infinity();
    for (; it != end; ++it) {
      const pose2d_t& a = *it;
      const pose2d_t& b = (it + 1 == truth.end()) ? *it : *(it + 1);
      const double dx = b.x_m - a.x_m, dy = b.y_m - a.y_m, l2 = dx * dx + dy * dy;
      const double f =
          l2 > 0 ? std::clamp(((p.x_m - a.x_m) * dx + (p.y_m - a.y_m) * dy) / l2, 0.0, 1.0) : 0.0;
      best = std::min(best, std::hypot(p.x_m - (a.x_m + f * dx), p.y_m - (a.y_m + f * dy)));
    }
    worst = std::max(worst, best);
  }
  return worst;
}

double rmsToTruePlane(const std::string& log, const fs::path& pcd, int sweep) {
  for (const Message& m : readChannel(log, "TRUTH_PROFILE_RIG")) {
    truth_profile_rig_t t;
    if (t.decode(m.data.data(), 0, static_cast<int>(m.data.size())) < 0) continue;
    if (t.sweep_id != sweep) continue;
    const Eigen::Vector3d n(t.plane_normal[0], t.plane_normal[1], t.plane_normal[2]);
    double sum = 0;
    const auto points = readPcd(pcd.string());
    for (const auto& p : points) {
      const double d = n.dot(p.cast<double>() * 1e3) - t.plane_distance_mm;
      sum += d * d;
    }
    return std::sqrt(sum / points.size());
  }
  return -1;
}

}  // namespace test
}  // namespace sweepmap

#include <sys/file.h>
#include <unistd.h>

namespace sweepmap {
namespace test {
namespace {

std::string binaryStamp() {
  const auto t = fs::last_write_time(binPath("sweepmap")).time_since_epoch().count();
  return std::to_string(t);
}

// Runs `make` once per stamp under an exclusive lock on `dir/.lock`.
void onceUnderLock(const fs::path& dir, const std::string& key, const std::function<void()>& make) {
  fs::create_directories(dir);
  const int fd = ::open((dir / ".lock").c_str(), O_CREAT | O_RDWR, 0644);
  ::flock(fd, LOCK_EX);
  const fs::path marker = dir / ".done";
  const std::string stamp = binaryStamp() + " " + key;
  if (!fs::exists(marker) || readFile(marker) != stamp) {
    fs::remove(marker);
    make();
    std::ofstream(marker) << stamp;
  }
  ::flock(fd, LOCK_UN);
  ::close(fd);
}

std::string joined(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& a : v) s += a + " ";
  return s;
}

}  // namespace

namespace {

std::string cachedLog(const std::string& command, const std::string& name,
                      const std::vector<std::string>& sim_args) {
  const fs::path dir = fs::path(SWEEPMAP_BINARY_DIR) / "test_cache" / name;
  const std::string log = (dir / "sim.lcmlog").string();
  onceUnderLock(dir, (command == "sim" ? "" : command + " ") + joined(sim_args), [&] {
    std::vector<std::string> args = {command};
    args.insert(args.end(), sim_args.begin(), sim_args.end());
    args.insert(args.end(), {"--out", log});
    if (sweepmap(args, dir / "sim.txt") != 0) {
      throw std::runtime_error("sweepmap " + command + " failed: " + readFile(dir / "sim.txt"));
    }
  });
  return log;
}

}  // namespace

std::string cachedSimLog(const std::string& name, const std::vector<std::string>& sim_args) {
  return cachedLog("sim", name, sim_args);
}

CachedRun cachedRun(const std::string& name, const std::vector<std::string>& args) {
  const fs::path dir = fs::path(SWEEPMAP_BINARY_DIR) / "test_cache" / name;
  CachedRun run{dir / "out", -1, dir / "output.txt"};
  onceUnderLock(dir, joined(args), [&] {
    std::vector<std::string> a = args;
    a.insert(a.end(), {"--out", run.out.string()});
    fs::remove_all(run.out);
    std::ofstream(dir / "status.txt") << sweepmap(a, run.output);
  });
  run.status = std::stoi(readFile(dir / "status.txt"));
  return run;
}

fs::path cachedReplay(const std::string& name, const std::string& log,
                      const std::vector<std::string>& extra_args) {
  std::vector<std::string> args = {"replay", log};
  args.insert(args.end(), extra_args.begin(), extra_args.end());
  const CachedRun run = cachedRun(name, args);
  if (run.status != 0) throw std::runtime_error("sweepmap replay failed: " + readFile(run.output));
  return run.out;
}

}  // namespace test
}  // namespace sweepmap
