// What the benchmarks read about processes: wall and CPU time, a child process's CPU time,
// thread switches and memory from /proc.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

namespace sweepmap {

using BenchClock = std::chrono::steady_clock;
double secondsSince(BenchClock::time_point t0);
// getrusage(who): user + system seconds (RUSAGE_SELF, RUSAGE_CHILDREN).
double cpuSeconds(int who);
// utime + stime of a running process from /proc/<pid>/stat; -1 if it cannot be read.
double processCpuSeconds(pid_t pid);
// Voluntary + involuntary context switches of every thread of `pid`.
int64_t contextSwitches(pid_t pid);
// A "Key:   value kB" line of /proc/<pid>/status, in KiB (0 if absent).
int64_t statusKib(pid_t pid, const std::string& key);

// A command run to its end as a child process: its wall time (start-up included), its CPU
// time (user + system, every thread; exact from wait4) and its peak RSS (VmHWM polled every
// 5 ms: the rusage of a spawned child would report this process's own peak, which the
// child's image inherits through exec).
struct ChildRun {
  bool ok = false;  // started and exited with status 0
  double wall_s = 0.0, cpu_s = 0.0;
  int64_t peak_kib = 0;
};
// Runs `args` (args[0]: the executable's path) with its stdout into `stdout_path` and its
// stderr into `stderr_path` (the same file when equal).
ChildRun runChild(const std::vector<std::string>& args, const std::string& stdout_path,
                  const std::string& stderr_path);

// The reference workload for comparing CPUs: sysbench 1.0's `cpu` test (every number below
// 10000 tested for primality by trial division; one event = one pass), run on this thread for
// at least `min_cpu_s` of its CPU time. Returns events per CPU second, which machine load
// does not change much (sysbench prints events per wall second).
double referenceEventsPerCpuSecond(double min_cpu_s);

}  // namespace sweepmap
