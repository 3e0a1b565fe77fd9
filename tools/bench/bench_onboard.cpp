#include "tools/bench/bench_onboard.hpp"

#include <iomanip>

#include "tools/bench/proc_stats.hpp"

namespace sweepmap {

void printOnboardEstimate(const std::vector<ProcessLoad>& loads, double step_thread_share,
                          std::ostream& out) {
  out << "on-board processes at full sensor rates, and a Raspberry Pi 3B's estimated load:\n";
  if (loads.empty()) {
    out << "  skipped: no process measured\n";
    return;
  }
  // Measured now, under the same load as the processes: CPU seconds, not wall seconds.
  const double here = referenceEventsPerCpuSecond(3.0);
  const double factor = here / kPi3bReferenceEventsPerS;
  out << std::fixed << std::setprecision(1) << "  reference: sysbench 1.0's cpu loop (primes to "
      << "10000), one thread: " << here << " events per CPU second here, "
      << kPi3bReferenceEventsPerS << " on a Pi 3B (published 687.45 for a Pi 3B+ at 1.4 GHz, "
      << "scaled to 1.2 GHz) -> factor " << std::setprecision(2) << factor << "\n";
  const auto line = [&](const std::string& name, const std::string& what, double share,
                        double rss_mib) {
    out << "  " << std::left << std::setw(38) << (name + " (" + what + ")") << std::right
        << std::setprecision(2) << std::setw(7) << share * 100.0 << " % of a core here, peak RSS "
        << std::setprecision(1) << std::setw(5) << rss_mib << " MiB -> Pi 3B ~" << std::setw(6)
        << share * factor * 100.0 << " % of one core\n";
  };
  double total = 0.0, total_rss = 0.0;
  for (const ProcessLoad& l : loads) {
    line(l.name, l.what, l.cpu_share, double(l.rss_kib) / 1024.0);
    total += l.cpu_share;
    total_rss += double(l.rss_kib) / 1024.0;
    if (l.name == "sweepmap-motor" && step_thread_share >= 0.0) {
      // The real stepper: the generator thread in place of the simulated stepper (whose own
      // cost stays counted: an upper bound).
      line("  + GPIO step generator thread", "mode 7", step_thread_share, 0.0);
      total += step_thread_share;
    }
  }
  out << "  all together: " << std::setprecision(2) << total * 100.0 << " % of a core here, "
      << std::setprecision(1) << total_rss << " MiB peak RSS -> Pi 3B ~" << total * factor * 100.0
      << " % of one of its 4 cores (" << total * factor * 25.0
      << " % of the whole CPU); an estimate from one single-thread ratio, not a measurement "
      << "on a Pi\n";
}

}  // namespace sweepmap
