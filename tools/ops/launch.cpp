#include "tools/ops/launch.hpp"

#include <poll.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <thread>

#include "core/config.hpp"
#include "processes/live_runner.hpp"
#include "tools/ops/deploy.hpp"
#include "tools/ops/process_group.hpp"

namespace sweepmap {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double secondsBetween(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

// The children's $NOTIFY_SOCKET: an abstract datagram socket that receives each sender's pid
// with its message (SO_PASSCRED).
class NotifyServer {
 public:
  NotifyServer() {
    name_ = "@sweepmap-launch-" + std::to_string(::getpid());
    fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
    if (fd_ < 0) return;
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::memcpy(addr.sun_path + 1, name_.data() + 1, name_.size() - 1);
    const int on = 1;
    if (::setsockopt(fd_, SOL_SOCKET, SO_PASSCRED, &on, sizeof on) != 0 ||
        ::bind(fd_, reinterpret_cast<sockaddr*>(&addr),
               static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + name_.size())) != 0) {
      ::close(fd_);
      fd_ = -1;
    }
  }
  ~NotifyServer() {
    if (fd_ >= 0) ::close(fd_);
  }
  bool ok() const { return fd_ >= 0; }
  const std::string& name() const { return name_; }

  // Waits up to timeout_ms for messages; calls on_message(pid, text) for each one.
  template <class F>
  void receive(int timeout_ms, F on_message) {
    if (fd_ < 0) {
      std::this_thread::sleep_for(std::chrono::milliseconds(timeout_ms));
      return;
    }
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, timeout_ms) <= 0) return;
    for (;;) {
      char data[4096];
      alignas(cmsghdr) char control[CMSG_SPACE(sizeof(ucred))];
      iovec iov{data, sizeof data};
      msghdr msg{};
      msg.msg_iov = &iov;
      msg.msg_iovlen = 1;
      msg.msg_control = control;
      msg.msg_controllen = sizeof control;
      const ssize_t n = ::recvmsg(fd_, &msg, MSG_DONTWAIT);
      if (n < 0) return;
      pid_t pid = -1;
      for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c != nullptr; c = CMSG_NXTHDR(&msg, c)) {
        if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_CREDENTIALS) {
          ucred cred{};
          std::memcpy(&cred, CMSG_DATA(c), sizeof cred);
          pid = cred.pid;
        }
      }
      on_message(pid, std::string(data, static_cast<size_t>(n)));
    }
  }

 private:
  std::string name_;
  int fd_ = -1;
};

class Supervisor {
 public:
  Supervisor(const Deployment& d, const LaunchOptions& o) : deploy_(d), options_(o) {
    log_dir_ = fs::absolute(o.log_dir);
    bin_dir_ =
        o.bin_dir.empty() ? fs::read_symlink("/proc/self/exe").parent_path().string() : o.bin_dir;
    for (const auto& spec : d.processes(o.host)) {
      Proc p;
      p.spec = spec;
      p.argv = processArgv(d, spec, bin_dir_, o.secure);
      procs_.push_back(std::move(p));
    }
    events_.open(log_dir_ / "launch.txt", std::ios::app);
  }

  int run() {
    event("launch", "",
          deploy_.path + (options_.host.empty() ? " (every host)" : " --host " + options_.host) +
              ": " + std::to_string(procs_.size()) + " processes, logs in " + log_dir_.string() +
              (notify_.ok() && options_.watchdog
                   ? ", watchdog " + fmt(deploy_.restart.watchdog_s) + " s"
                   : ", no watchdog"));
    installStopSignals();
    const auto t0 = Clock::now();
    for (auto& p : procs_) p.next_start = t0;
    while (!stopRequested()) {
      notify_.receive(50, [&](pid_t pid, const std::string& text) { onNotify(pid, text); });
      if (stopRequested()) break;
      const auto now = Clock::now();
      bool all_finished = true;
      for (auto& p : procs_) {
        if (p.pid > 0 && !group_.running(p.pid)) onExit(p, now);
        if (p.pid > 0) checkWatchdog(p, now);
        if (p.pid <= 0 && !p.finished && now >= p.next_start) start(p, now);
        all_finished = all_finished && p.finished;
      }
      if (all_finished) {
        event("launch", "", "every process has finished");
        return 0;
      }
    }
    return stopAll();
  }

 private:
  struct Proc {
    DeployProcess spec;
    std::vector<std::string> argv;
    pid_t pid = -1;
    int starts = 0;
    int failures_in_row = 0;
    bool finished = false;
    bool ready = false;
    bool watchdog_killed = false;
    Clock::time_point started, last_alive, next_start;
  };

  static std::string fmt(double v) {
    std::ostringstream o;
    o << std::setprecision(3) << v;
    return o.str();
  }

  // "launch 12:34:56.789 start     mapper (pid 123): ..." on stdout and in launch.txt.
  void event(const std::string& what, const std::string& name, const std::string& detail) {
    const auto now = std::chrono::system_clock::now();
    const std::time_t t = std::chrono::system_clock::to_time_t(now);
    const int ms = static_cast<int>(
        std::chrono::duration_cast<std::chrono::milliseconds>(now.time_since_epoch()).count() %
        1000);
    std::tm tm{};
    ::localtime_r(&t, &tm);
    std::ostringstream line;
    line << "launch " << std::put_time(&tm, "%H:%M:%S") << "." << std::setw(3) << std::setfill('0')
         << ms << std::setfill(' ') << " " << std::left << std::setw(9) << what
         << (name.empty() ? "" : name + " ") << detail;
    std::cout << line.str() << std::endl;
    if (events_) events_ << line.str() << std::endl;
  }

  std::string pidText(const Proc& p) const { return "(pid " + std::to_string(p.pid) + ")"; }

  void start(Proc& p, Clock::time_point now) {
    SpawnOptions o;
    o.log_path = (log_dir_ / (p.spec.name + ".txt")).string();
    o.append_log = true;
    o.new_process_group = true;
    o.parent_death_signal = SIGTERM;  // launch killed (even by SIGKILL): its children stop
    o.env = {"LCM_DEFAULT_URL=" + deploy_.lcm_url};
    if (p.spec.notify && notify_.ok()) {
      o.env.push_back("NOTIFY_SOCKET=" + notify_.name());
      if (options_.watchdog) {
        o.env.push_back("WATCHDOG_USEC=" +
                        std::to_string(std::llround(deploy_.restart.watchdog_s * 1e6)));
      }
    }
    {
      std::ofstream log(o.log_path, std::ios::app);
      log << "=== sweepmap launch: start " << p.starts + 1 << " of " << p.spec.name << ":";
      for (const auto& a : p.argv) log << " " << a;
      log << "\n";
    }
    ++p.starts;
    try {
      p.pid = group_.start(p.spec.name, p.argv, o);
    } catch (const std::exception& e) {
      event("error", p.spec.name, e.what());
      scheduleRestart(p, now);
      return;
    }
    p.started = p.last_alive = now;
    p.ready = p.watchdog_killed = false;
    event("start", p.spec.name,
          pidText(p) + (p.starts > 1 ? " restart " + std::to_string(p.starts - 1) : ""));
  }

  void scheduleRestart(Proc& p, Clock::time_point now) {
    const RestartPolicy& r = deploy_.restart;
    const double delay = std::min(r.max_delay_s, r.delay_s * std::pow(2.0, p.failures_in_row));
    ++p.failures_in_row;
    p.next_start = now + std::chrono::microseconds(std::llround(delay * 1e6));
    event("restart", p.spec.name,
          "in " + fmt(delay) + " s (failure " + std::to_string(p.failures_in_row) + " in a row)");
  }

  void onExit(Proc& p, Clock::time_point now) {
    const int status = group_.wait(p.pid, 0);
    ProcessGroup::killGroup(p.pid);  // what it left running (systemd kills its cgroup)
    const double ran_s = secondsBetween(p.started, now);
    event("exit", p.spec.name,
          pidText(p) + " " + group_.describeExit(p.pid) + " after " + fmt(ran_s) + " s" +
              (p.watchdog_killed ? " (watchdog)" : ""));
    p.pid = -1;
    if (ran_s >= deploy_.restart.stable_s) p.failures_in_row = 0;
    if (status == 0 && !p.spec.restart_always) {
      p.finished = true;
      event("finished", p.spec.name, "exited 0: not restarted (restart: on-failure)");
      return;
    }
    if (status == 0) p.failures_in_row = 0;  // restart: always, after a clean exit
    scheduleRestart(p, now);
  }

  void checkWatchdog(Proc& p, Clock::time_point now) {
    if (!options_.watchdog || !notify_.ok() || !p.spec.notify || p.watchdog_killed) return;
    const double silent_s = secondsBetween(p.last_alive, now);
    if (silent_s < deploy_.restart.watchdog_s) return;
    event("watchdog", p.spec.name,
          pidText(p) + ": no WATCHDOG=1 for " + fmt(silent_s) + " s: killing it (SIGKILL)");
    p.watchdog_killed = true;
    group_.signal(p.pid, SIGKILL);
  }

  void onNotify(pid_t pid, const std::string& text) {
    for (auto& p : procs_) {
      if (p.pid != pid || pid <= 0) continue;
      p.last_alive = Clock::now();
      if (!p.ready && text.find("READY=1") != std::string::npos) {
        p.ready = true;
        event("ready", p.spec.name,
              pidText(p) + " after " + fmt(secondsBetween(p.started, p.last_alive)) + " s");
      }
    }
  }

  // SIGINT, then SIGKILL after timeout_s; the notify socket is served meanwhile, so that no
  // child (the one stopping, or one stopped later) blocks on a full socket and misses its own
  // stop timeout. Returns the exit status (128 + signal if killed).
  int stopServingNotify(pid_t pid, double timeout_s) {
    if (!group_.running(pid)) return group_.wait(pid, 0);
    group_.signal(pid, SIGINT);
    const auto deadline = Clock::now() + std::chrono::duration<double>(timeout_s);
    while (group_.running(pid) && Clock::now() < deadline) {
      notify_.receive(20, [&](pid_t from, const std::string& text) { onNotify(from, text); });
    }
    if (group_.running(pid)) group_.signal(pid, SIGKILL);
    return group_.wait(pid, 5.0);
  }

  // In reverse file order: SIGINT, then SIGKILL after the stop timeout.
  int stopAll() {
    int killed = 0;
    for (auto it = procs_.rbegin(); it != procs_.rend(); ++it) {
      Proc& p = *it;
      if (p.pid <= 0) continue;
      event("stop", p.spec.name,
            pidText(p) + ": SIGINT, SIGKILL after " + fmt(deploy_.stopTimeout(p.spec)) + " s");
      const int status = stopServingNotify(p.pid, deploy_.stopTimeout(p.spec));
      ProcessGroup::killGroup(p.pid);
      killed += status == 128 + SIGKILL;
      event("exit", p.spec.name, pidText(p) + " " + group_.describeExit(p.pid));
      p.pid = -1;
    }
    event("launch", "",
          killed ? std::to_string(killed) + " processes had to be killed" : "stopped");
    return killed ? 1 : 0;
  }

  const Deployment& deploy_;
  LaunchOptions options_;
  fs::path log_dir_;
  std::string bin_dir_;
  std::vector<Proc> procs_;
  ProcessGroup group_;
  NotifyServer notify_;
  std::ofstream events_;
};

}  // namespace

int runLaunch(const LaunchOptions& o) {
  Deployment d;
  try {
    d = loadDeployment(o.deploy);
    if (!o.host.empty()) d.host(o.host);  // an unknown host is an error
  } catch (const ConfigError& e) {
    std::cerr << "launch: " << e.what() << "\n";
    return 2;
  }
  std::error_code ec;
  fs::create_directories(o.log_dir, ec);
  if (ec) {
    std::cerr << "launch: cannot create " << o.log_dir << ": " << ec.message() << "\n";
    return 2;
  }
  // Our own supervisor's variables are not our children's.
  ::unsetenv("NOTIFY_SOCKET");
  ::unsetenv("WATCHDOG_PID");
  ::unsetenv("WATCHDOG_USEC");
  Supervisor s(d, o);
  return s.run();
}

}  // namespace sweepmap
