// What the benchmarks read about processes: wall and CPU time, a child process's CPU time,
// thread switches and memory from /proc.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <cstdint>
#include <string>

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

// The reference workload for comparing CPUs: sysbench 1.0's `cpu` test (every number below
// 10000 tested for primality by trial division; one event = one pass), run on this thread for
// at least `min_cpu_s` of its CPU time. Returns events per CPU second, which machine load
// does not change much (sysbench prints events per wall second).
double referenceEventsPerCpuSecond(double min_cpu_s);

}  // namespace sweepmap
