#include "tools/export/export_las.hpp"

#include <fstream>

#include "core/command_line.hpp"
#include "core/event_log.hpp"
#include "processes/channels.hpp"
#include "processes/convert.hpp"

namespace sweepmap {
namespace {

bool isPly(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  char magic[4] = {};
  in.read(magic, 4);
  return in && std::string(magic, 4) == "ply\n";
}

// Every SWEEP_CLOUD point of the log, with its chunk's time as GPS time.
void readLogClouds(const std::string& path, std::vector<LasPoint>* points, int64_t* last_unix_s,
                   ExportLasResult* r) {
  EventLogReader reader(path);
  reader.setResync(true);
  LogEvent e;
  while (reader.next(&e)) {
    if (e.channel != channels::kSweepCloud) continue;
    cloud_chunk_t c;
    if (!decodeMessage(e.data.data(), e.data.size(), &c) || !validateChunk(c).empty()) {
      ++r->chunks_rejected;
      continue;
    }
    ++r->chunks;
    const double gps = adjustedGpsTime(static_cast<double>(c.utime) * 1e-6);
    *last_unix_s = std::max(*last_unix_s, c.utime / 1000000);
    // validateChunk: nintensities is 0 (a lidar without intensity: LAS intensity 0) or npoints.
    const bool with_intensity = c.intensities.size() == c.xyz_m.size();
    for (size_t i = 0; i < c.xyz_m.size(); ++i) {
      const auto& p = c.xyz_m[i];
      points->push_back(
          {p[0], p[1], p[2], gps, with_intensity ? lasIntensity(c.intensities[i]) : uint16_t{0}});
    }
  }
  if (!reader.skipped().empty()) {
    r->log_error = true;
    r->error += (r->error.empty() ? "" : "; ") + describeSkipped(path, reader.skipped());
  }
}

}  // namespace

ExportLasResult exportLas(const ExportLasOptions& options) {
  ExportLasResult r;
  std::vector<LasPoint> points;
  int64_t last_unix_s = 0;
  for (const auto& in : options.inputs) {
    if (isPly(in)) {
      const auto ply = readPlyVertices(in);
      points.insert(points.end(), ply.begin(), ply.end());
    } else {
      readLogClouds(in, &points, &last_unix_s, &r);
    }
  }
  LasOptions lo;
  lo.creation_unix_s = last_unix_s > 946684800 ? last_unix_s : 0;  // a clock after 2000
  try {
    r.las = writeLas14(options.out, points, lo);
  } catch (const std::runtime_error& e) {  // inputs were read: the output failed
    throw CommandError(kExitDeviceIo, e.what());
  }
  return r;
}

}  // namespace sweepmap
