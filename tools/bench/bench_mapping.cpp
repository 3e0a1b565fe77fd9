// bench_mapping: speed of OccupancyMap::insertCloud on a synthetic mode-7 sweep (640 scan
// planes x 1081 beams = 691,840 points, sensor at the centre of an 8 x 6 x 3 m room,
// 12 mm range noise), discretized vs every-ray insertion. Prints figures; asserts nothing.
//
//   bench_mapping [--sweeps N] [--resolution M]
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "mapping/occupancy_map.hpp"
#include "mapping/synthetic_room.hpp"

namespace {

using sweepmap::InsertMode;

// Peak resident set size of this process in MiB (VmHWM), or -1 if unknown.
double peakRssMiB() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("VmHWM:", 0) == 0) return std::atof(line.c_str() + 6) / 1024.0;
  }
  return -1.0;
}

// Resets the peak to the current RSS (Linux >= 4.0), so each mode reports its own peak.
bool resetPeakRss() {
  std::ofstream out("/proc/self/clear_refs");
  out << "5";
  out.close();
  return static_cast<bool>(out);
}

void runMode(const char* name, InsertMode mode,
             const std::vector<std::vector<Eigen::Vector3f>>& sweeps, const Eigen::Vector3f& origin,
             double resolution_m) {
  const bool reset = resetPeakRss();
  sweepmap::MapperConfig config;
  config.resolution_m = resolution_m;
  sweepmap::OccupancyMap map(config);
  double total_s = 0.0;
  size_t total_points = 0;
  std::printf("%s insertion:\n", name);
  for (size_t i = 0; i < sweeps.size(); ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    map.insertCloud(sweeps[i], origin, mode);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    total_s += s;
    total_points += sweeps[i].size();
    std::printf("  sweep %zu: %.3f s, %.0f points/s\n", i + 1, s, sweeps[i].size() / s);
  }
  const sweepmap::MapStats st = map.stats();
  std::printf("  mean: %.3f s per sweep, %.0f points/s\n", total_s / sweeps.size(),
              total_points / total_s);
  std::printf("  map: %lld occupied, %lld free voxels, %.1f MiB tree; peak RSS %.1f MiB%s\n",
              static_cast<long long>(st.occupied_voxels), static_cast<long long>(st.free_voxels),
              st.memory_bytes / 1048576.0, peakRssMiB(),
              reset ? "" : " (process-wide: could not reset the peak)");
}

}  // namespace

int main(int argc, char** argv) {
  int sweep_count = 3;
  double resolution_m = 0.05;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--sweeps" && i + 1 < argc) {
      sweep_count = std::atoi(argv[++i]);
    } else if (arg == "--resolution" && i + 1 < argc) {
      resolution_m = std::atof(argv[++i]);
    } else {
      std::fprintf(stderr, "usage: %s [--sweeps N] [--resolution M]\n", argv[0]);
      return 2;
    }
  }
  if (sweep_count < 1 || !(resolution_m > 0.0)) {
    std::fprintf(stderr, "bench_mapping: need --sweeps >= 1 and --resolution > 0\n");
    return 2;
  }

  sweepmap::RoomSweepSpec spec;  // 8 x 6 x 3 m room, sensor at its centre, mode 7
  spec.range_noise_sigma_m = 0.012;
  std::vector<std::vector<Eigen::Vector3f>> sweeps;
  for (int i = 0; i < sweep_count; ++i) {
    spec.seed = static_cast<uint32_t>(i + 1);  // new noise each sweep, same geometry
    sweeps.push_back(sweepmap::syntheticRoomSweep(spec));
  }
  std::printf("bench_mapping: %d sweeps of %zu points, resolution %.3f m, max range %.1f m\n",
              sweep_count, sweeps[0].size(), resolution_m, sweepmap::MapperConfig{}.max_range_m);
  std::printf("baseline RSS peak (clouds generated): %.1f MiB\n", peakRssMiB());
  runMode("discretized", InsertMode::kDiscretized, sweeps, spec.sensor_m, resolution_m);
  runMode("octomap-discretized", InsertMode::kOctomapDiscretized, sweeps, spec.sensor_m,
          resolution_m);
  runMode("every-ray", InsertMode::kEveryRay, sweeps, spec.sensor_m, resolution_m);
  return 0;
}
