#include "tools/bench/proc_stats.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

namespace sweepmap {

double secondsSince(BenchClock::time_point t0) {
  return std::chrono::duration<double>(BenchClock::now() - t0).count();
}

double cpuSeconds(int who) {
  rusage u{};
  getrusage(who, &u);
  return u.ru_utime.tv_sec + u.ru_stime.tv_sec + (u.ru_utime.tv_usec + u.ru_stime.tv_usec) * 1e-6;
}

// utime + stime of a running process from /proc/<pid>/stat (fields 14 and 15, after the
// parenthesised command name); -1 if it cannot be read.
double processCpuSeconds(pid_t pid) {
  std::ifstream f("/proc/" + std::to_string(pid) + "/stat");
  std::string line;
  if (!std::getline(f, line)) return -1.0;
  const size_t close = line.rfind(')');
  if (close == std::string::npos) return -1.0;
  std::istringstream rest(line.substr(close + 2));
  std::string field;
  long long utime = 0, stime = 0;
  for (int i = 3; i <= 15 && rest >> field; ++i) {
    if (i == 14) utime = std::stoll(field);
    if (i == 15) stime = std::stoll(field);
  }
  return static_cast<double>(utime + stime) / static_cast<double>(sysconf(_SC_CLK_TCK));
}

// Voluntary + involuntary context switches of every thread of `pid` (thread wake-ups are
// what a cheap process spends most of its CPU on).
int64_t contextSwitches(pid_t pid) {
  namespace fs = std::filesystem;
  int64_t total = 0;
  std::error_code ec;
  for (const auto& task : fs::directory_iterator("/proc/" + std::to_string(pid) + "/task", ec)) {
    std::ifstream f(task.path() / "status");
    std::string key;
    int64_t value = 0;
    while (f >> key) {
      if (key == "voluntary_ctxt_switches:" || key == "nonvoluntary_ctxt_switches:") {
        if (f >> value) total += value;
      }
    }
  }
  return total;
}

// A "Key:   value kB" line of /proc/<pid>/status, in KiB (0 if absent).
int64_t statusKib(pid_t pid, const std::string& key) {
  std::ifstream f("/proc/" + std::to_string(pid) + "/status");
  std::string word;
  while (f >> word) {
    if (word == key) {
      int64_t kib = 0;
      f >> kib;
      return kib;
    }
  }
  return 0;
}

ChildRun runChild(const std::vector<std::string>& args, const std::string& stdout_path,
                  const std::string& stderr_path) {
  std::vector<std::string> copy = args;
  std::vector<char*> argv;
  for (std::string& a : copy) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  const int flags = O_WRONLY | O_CREAT | O_TRUNC;
  posix_spawn_file_actions_addopen(&actions, 1, stdout_path.c_str(), flags, 0644);
  if (stderr_path == stdout_path) {
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
  } else {
    posix_spawn_file_actions_addopen(&actions, 2, stderr_path.c_str(), flags, 0644);
  }
  ChildRun run;
  const auto t0 = BenchClock::now();
  pid_t child = -1;
  const int spawn_rc = posix_spawn(&child, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  int status = 0;
  rusage usage{};
  bool ok = spawn_rc == 0;
  while (ok) {
    const pid_t r = wait4(child, &status, WNOHANG, &usage);
    if (r == child) break;
    if (r < 0) ok = false;
    run.peak_kib = std::max(run.peak_kib, statusKib(child, "VmHWM:"));
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  run.wall_s = secondsSince(t0);
  run.ok = ok && WIFEXITED(status) && WEXITSTATUS(status) == 0;
  run.cpu_s = usage.ru_utime.tv_sec + usage.ru_stime.tv_sec +
              (usage.ru_utime.tv_usec + usage.ru_stime.tv_usec) * 1e-6;
  return run;
}

namespace {

double threadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + double(ts.tv_nsec) * 1e-9;
}

// sysbench 1.0.20's cpu_execute_event (src/tests/cpu/sb_cpu.c), max_prime 10000 (read
// through a volatile so the compiler cannot fold the loop away).
volatile unsigned long long g_max_prime = 10000;

uint64_t primeEvent() {
  const unsigned long long max_prime = g_max_prime;
  uint64_t n = 0;
  for (unsigned long long c = 3; c < max_prime; c++) {
    const double t = std::sqrt(static_cast<double>(c));
    unsigned long long l;
    for (l = 2; l <= t; l++) {
      if (c % l == 0) break;
    }
    if (l > t) n++;
  }
  return n;
}

}  // namespace

double referenceEventsPerCpuSecond(double min_cpu_s) {
  const double t0 = threadCpuSeconds();
  int64_t events = 0;
  uint64_t primes = 0;
  double spent = 0.0;
  do {
    primes += primeEvent();
    ++events;
    if (events % 16 == 0) spent = threadCpuSeconds() - t0;
  } while (spent < min_cpu_s);
  return primes > 0 ? double(events) / spent : 0.0;
}

}  // namespace sweepmap
