#include "tools/offline/calibrate_logs.hpp"

#include <algorithm>
#include <filesystem>
#include <iostream>

#include "core/event_log.hpp"
#include "tools/offline/calibrate_common.hpp"

namespace sweepmap {

namespace {

// One log's sweeps into *in.
void takePlateSweeps(ProfileLog& l, const PlateSweepLimits& limits, bool say_each,
                     PlateSweeps* in) {
  if (l.truth && !in->truth) in->truth = l.truth;
  for (auto& sweep : l.sweeps) {
    if (static_cast<int>(sweep.samples.size()) < limits.min_points) {
      in->rejected.push_back(sweep.source + ": " + std::to_string(sweep.samples.size()) +
                             " points (< " + std::to_string(limits.min_points) + ")");
      if (say_each) std::cerr << "  " << in->rejected.back() << ": rejected\n";
      continue;
    }
    in->full_points.push_back(sweep.samples.size());
    in->planes.push_back(subsample(sweep, limits.max_points));
    if (say_each) {
      std::cerr << "  " << sweep.source << ": " << sweep.samples.size() << " points, "
                << in->planes.back().samples.size() << " used\n";
    }
  }
}

}  // namespace

bool readPlateSweeps(const std::vector<std::string>& logs, const PlateSweepLimits& limits,
                     const std::string& what, bool say_each, PlateSweeps* in) {
  const auto t0 = calib_workflow::Clock::now();
  for (const auto& log : logs) {
    ProfileLog l;
    try {
      l = readProfileLog(log);
    } catch (const ProfileLogError& e) {
      std::cerr << what << ": " << e.what() << "\n";
      return false;
    }
    takePlateSweeps(l, limits, say_each, in);
  }
  in->read_s = calib_workflow::seconds(calib_workflow::Clock::now() - t0);
  return true;
}

bool readLidarLogs(const std::vector<std::string>& logs, const RotatingLidarConfig& rig,
                   const std::string& what, const LidarLogReading& r,
                   std::vector<std::string>* log_errors) {
  for (const auto& log : logs) {
    LogSweepOptions opts;
    opts.on_window_scans = [&](const AssembledSweep& s, const std::vector<Scan2D>& scans) {
      r.take_sweep(log, s, scans);
    };
    if (r.progress) {
      r.progress->stage("reading " + std::filesystem::path(log).filename().string());
      const auto size = std::max<uint64_t>(1, std::filesystem::file_size(log));
      opts.progress = [&r, size](uint64_t offset, uint64_t) {
        r.progress->update(double(offset) / size);
      };
    }
    LogReadResult result;
    try {
      result = forEachSweep(
          log, rig, [](const AssembledSweep&, const SweepTruth&) {}, opts);
    } catch (const LogError& e) {
      std::cerr << what << ": cannot read log '" << log << "': " << e.what() << "\n";
      return false;
    }
    if (result.log_error) {
      std::cerr << what << ": " << result.error << " (the sweeps before it are used)\n";
      log_errors->push_back(result.error);
    }
    if (r.took_log) r.took_log(result);
  }
  return true;
}

}  // namespace sweepmap
