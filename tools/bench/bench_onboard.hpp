// The on-board processes' load in one table (`sweepmap bench`, after the device benches):
// each process's CPU share and peak RSS here at full sensor rates, and the estimate of its
// load on a Raspberry Pi 3B from a reference workload measured in the same run.
#pragma once

#include <ostream>
#include <vector>

#include "tools/bench/bench_devices.hpp"

namespace sweepmap {

// The reference workload's published single-core figure for the Pi 3B: sysbench 1.0.20
// `sysbench cpu --threads=1 --time=60 run` gave 687.45 events/s on a Pi 3B+ (Cortex-A53 at
// 1.4 GHz, 64-bit OS; leoncode.co.uk "Raspberry Pi CPU Benchmarks"); the Pi 3B has the same
// core at 1.2 GHz, so 687.45 * 1.2 / 1.4.
constexpr double kPi3bReferenceEventsPerS = 687.45 * 1.2 / 1.4;

// `step_thread_share`: the GPIO step generator's thread (benchStepper), < 0 if not measured.
void printOnboardEstimate(const std::vector<ProcessLoad>& loads, double step_thread_share,
                          std::ostream& out);

}  // namespace sweepmap
