#include "tools/import/import_mines.hpp"

#include <fstream>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "core/event_log.hpp"
#include "processes/channels.hpp"
#include "processes/node.hpp"
#include "sweepmap/lidar_scan_t.hpp"
#include "sweepmap/wheel_ticks_t.hpp"

namespace sweepmap {
namespace {

int64_t parseInt(const std::string& tok, const std::string& where) {
  size_t used = 0;
  long long v = 0;
  try {
    v = std::stoll(tok, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != tok.size() || tok.empty())
    throw std::runtime_error(where + ": not an integer: '" + tok + "'");
  return v;
}

}  // namespace

BreezySlamImport importBreezySlam(const std::string& in_path, const std::string& out_log) {
  std::ifstream in(in_path);
  if (!in) throw std::runtime_error(in_path + ": cannot open");
  EventLogWriter log(out_log);
  BreezySlamImport r;
  std::string line;
  int64_t previous_utime = INT64_MIN;
  while (std::getline(in, line)) {
    ++r.lines;
    const std::string at = in_path + ":" + std::to_string(r.lines);
    std::istringstream ss(line);
    std::vector<std::string> toks;
    for (std::string t; ss >> t;) toks.push_back(t);
    if (toks.empty()) continue;
    toks.pop_back();  // the loader ignores the last token
    if (toks.size() < 25) {
      throw std::runtime_error(at + ": " + std::to_string(toks.size() + 1) +
                               " tokens, expected a timestamp, odometry and ranges");
    }
    const int beams = static_cast<int>(toks.size() - 24);
    if (r.beams != 0 && beams != r.beams) {
      throw std::runtime_error(at + ": " + std::to_string(beams) + " ranges, earlier lines had " +
                               std::to_string(r.beams));
    }
    r.beams = beams;
    const int64_t utime = parseInt(toks[0], at + " token 1");
    if (utime <= previous_utime) throw std::runtime_error(at + ": timestamp goes back");
    previous_utime = utime;

    Outbox out;
    wheel_ticks_t w;
    w.utime = utime;
    w.left_ticks = parseInt(toks[2], at + " token 3");
    w.right_ticks = parseInt(toks[3], at + " token 4");
    out.publish(channels::kWheelTicks, utime, w);

    lidar_scan_t s{};  // no intensities, no per-ray angles
    s.utime = utime;
    s.device_stamp = -1;
    s.seq = r.scans;
    s.angle_increment_rad = static_cast<float>(kUrg04lxStepRad);
    s.angle_min_rad = static_cast<float>(-0.5 * (beams - 1) * kUrg04lxStepRad);
    s.time_increment_ns = static_cast<int32_t>(kUrg04lxScanPeriodS / 1024.0 * 1e9);
    s.range_min_m = static_cast<float>(kUrg04lxRangeMinM);
    s.range_max_m = static_cast<float>(kUrg04lxRangeMaxM);
    s.nranges = beams;
    s.ranges_m.resize(static_cast<size_t>(beams));
    for (int i = 0; i < beams; ++i) {
      const int64_t mm =
          parseInt(toks[24 + static_cast<size_t>(i)], at + " token " + std::to_string(25 + i));
      if (mm < 0)
        throw std::runtime_error(at + " token " + std::to_string(25 + i) + ": negative range");
      s.ranges_m[static_cast<size_t>(i)] = static_cast<float>(mm) * 1e-3f;
    }
    out.publish(channels::kLidarScan, utime, s);
    for (const auto& m : out.take()) log.write(m.utime, m.channel, m.data);
    if (r.scans == 0) r.first_utime = utime;
    r.last_utime = utime;
    ++r.scans;
  }
  log.close();
  return r;
}

}  // namespace sweepmap
