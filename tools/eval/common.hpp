// Small helpers every part of the evaluation shares: numbers as report text, progress lines
// on stderr and a stopwatch for the timings of report.json.
#pragma once

#include <chrono>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <string>

namespace sweepmap::eval {

// `v` with `digits` decimals (std::fixed), as the reports print their numbers.
inline std::string fixed(double v, int digits) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(digits) << v;
  return s.str();
}

// "eval: <line>" on stderr when `enabled`.
inline void progressLine(bool enabled, const std::string& line) {
  if (enabled) std::cerr << "eval: " << line << "\n";
}

class Stopwatch {
 public:
  double seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }

 private:
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

}  // namespace sweepmap::eval
