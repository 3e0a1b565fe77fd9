#include "tools/offline/replay_profile.hpp"

#include <cstdio>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>

#include "core/atomic_file.hpp"
#include "core/event_log.hpp"
#include "mapping/cloud_io.hpp"
#include "processes/channels.hpp"
#include "processes/convert.hpp"

namespace sweepmap {

namespace fs = std::filesystem;

namespace {

struct Sweep {
  int64_t profiles = 0;
  std::vector<Eigen::Vector3f> points;  // [m], O_r
};

// One profile's points in O_r [m].
void assemble(const profile_t& msg, const ProfileGeometry& g, std::vector<Eigen::Vector3f>* out) {
  const double encoder_rad =
      2.0 * M_PI * static_cast<double>(msg.encoder_counts) / msg.counts_per_revolution;
  for (int32_t i = 0; i < msg.point_count; ++i) {
    out->push_back(
        (profilePointInRigFrame(g, msg.y_mm[i], msg.z_mm[i], encoder_rad) * 1e-3).cast<float>());
  }
}

void writeOutputs(const fs::path& out, const std::string& log_path, const ProfileGeometry& g,
                  const std::map<int32_t, Sweep>& sweeps, const ProfileReplayResult& r) {
  fs::create_directories(out / "sweeps");
  std::vector<Eigen::Vector3f> all;
  nlohmann::json list = nlohmann::json::array();
  for (const auto& [id, sweep] : sweeps) {
    char name[32];
    std::snprintf(name, sizeof name, "sweep_%06d.pcd", id);
    writePcdBinary((out / "sweeps" / name).string(), sweep.points);
    all.insert(all.end(), sweep.points.begin(), sweep.points.end());
    list.push_back({{"id", id}, {"profiles", sweep.profiles}, {"points", sweep.points.size()}});
  }
  writePcdBinary((out / "cloud.pcd").string(), all);
  nlohmann::json s;
  s["log"] = fs::path(log_path).filename().string();
  s["events"] = r.events;
  s["profiles"] = r.profiles;
  s["invalid_profiles"] = r.invalid;
  s["points"] = r.points;
  s["sweeps"] = list;
  s["geometry"] = {{"m_mm", g.m_mm},
                   {"n_mm", g.n_mm},
                   {"laser_tilt_rad", g.laser_tilt_rad},
                   {"encoder_zero_rad", g.encoder_zero_rad}};
  if (r.log_error) s["error"] = r.error;
  writeFileAtomic((out / "summary.json").string(), s.dump(2) + "\n");
}

}  // namespace

ProfileReplayResult replayProfileLog(const std::string& log_path, const RotatingProfileConfig& rig,
                                     const std::string& out_dir) {
  const ProfileGeometry g = rig.geometry.toGeometry();
  ProfileReplayResult r;
  std::map<int32_t, Sweep> sweeps;
  try {
    // Corrupt regions are skipped (resync at the next good event) and reported.
    EventLogReader reader(log_path);
    reader.setResync(true);
    LogEvent e;
    while (reader.next(&e)) {
      ++r.events;
      if (e.channel != channels::kProfile) continue;
      profile_t msg;
      if (msg.decode(e.data.data(), 0, static_cast<int>(e.data.size())) < 0 ||
          !validateProfile(msg).empty()) {
        ++r.invalid;  // a bad message is counted, never fatal
        continue;
      }
      ++r.profiles;
      Sweep& sweep = sweeps[msg.sweep_id];
      ++sweep.profiles;
      assemble(msg, g, &sweep.points);
      r.points += msg.point_count;
    }
    if (!reader.skipped().empty()) {
      r.log_error = true;
      r.error = describeSkipped(log_path, reader.skipped());
    }
  } catch (const LogError& err) {
    r.log_error = true;
    r.error = err.what();
  }
  r.sweeps = static_cast<int>(sweeps.size());
  writeOutputs(out_dir, log_path, g, sweeps, r);
  return r;
}

}  // namespace sweepmap
