// sweepmap-mapper: SWEEP_CLOUD -> OctoMap, MAP_STATS; saves .bt on MAP_SAVE, after every
// --save-every map updates and at exit.
#include <chrono>
#include <ctime>
#include <filesystem>
#include <lcm/lcm-cpp.hpp>

#include "processes/cli_common.hpp"
#include "processes/live_runner.hpp"
#include "processes/mapper_node.hpp"

namespace {

// A map left at `path` by an earlier run (one killed and restarted by its supervisor) is
// renamed <path without .bt>.<UTC time>.bt: this run's first save must not replace it.
bool keepEarlierMap(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (path.empty() || !fs::exists(path, ec)) return true;
  const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm tm{};
  ::gmtime_r(&now, &tm);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "%Y%m%dT%H%M%SZ", &tm);
  fs::path stem = path;
  stem.replace_extension();
  fs::path kept = stem.string() + "." + stamp + ".bt";
  for (int n = 2; fs::exists(kept, ec); ++n) {
    kept = stem.string() + "." + stamp + "-" + std::to_string(n) + ".bt";
  }
  fs::rename(path, kept, ec);
  if (ec) {
    std::cerr << "sweepmap-mapper: cannot keep the earlier map " << path << " as " << kept.string()
              << ": " << ec.message() << "\n";
    return false;
  }
  std::cerr << "sweepmap-mapper: kept the earlier map " << path << " as " << kept.string() << "\n";
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace sweepmap;
  CLI::App app{
      "sweepmap-mapper: inserts assembled sweeps (rotating_lidar rigs) or world-frame "
      "scans (mobile_lidar rigs) or profiles (rotating_profile rigs), in mapper.batch_s "
      "batches, "
      "into an OctoMap OcTree, publishes after every map update the voxels it made occupied or "
      "freed (MAP_UPDATE) and MAP_STATS, saves the map (.bt, atomically) on "
      "MAP_SAVE, after every --save-every map updates and on shutdown. With --save-every, a map "
      "file left by an earlier run (one killed and restarted) is kept, renamed "
      "NAME.<UTC time>.bt"};
  CommonOptions common;
  std::string save_path = "map.bt";
  addCommonOptions(app, common,
                   {RigKind::kRotatingLidar, RigKind::kMobileLidar, RigKind::kRotatingProfile});
  app.add_option("--save", save_path, "map file written at shutdown and on empty MAP_SAVE")
      ->capture_default_str();
  int save_every = 0;
  app.add_option("--save-every", save_every,
                 "also save after every N map updates (a sweep; a batch for mobile rigs), so that "
                 "a killed mapper leaves its last map; 0 = only on MAP_SAVE and at shutdown")
      ->capture_default_str()
      ->check(atLeast(0));
  if (const auto code = parseCommandLine(app, argc, argv)) return *code;
  const std::optional<Rig> rig = loadRigOrReport(common);
  if (!rig) return kExitUsage;
  const MapperConfig config = std::visit([](const auto& c) { return c.mapper; }, rig->config);

  if (save_every > 0 && !keepEarlierMap(save_path)) return kExitDeviceIo;
  lcm::LCM lcm(common.lcm_url);
  MapperNode node(config, save_path, save_every);
  installStopSignals();
  const int rc = runLive(lcm, {&node}, liveOptions(common));
  if (rc == 0 && node.counter("save_errors") > 0) {
    std::cerr << "sweepmap-mapper: " << node.counter("save_errors")
              << " saves failed (see above); the map file holds the last good save\n";
    return kExitDeviceIo;
  }
  return rc;
}
