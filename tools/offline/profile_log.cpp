#include "tools/offline/profile_log.hpp"

#include <map>

#include "core/event_log.hpp"
#include "processes/channels.hpp"
#include "processes/convert.hpp"
#include "sweepmap/truth_profile_rig_t.hpp"
#include "sweepmap/truth_test_piece_t.hpp"

namespace sweepmap {

namespace {

template <class T>
T decodeOrThrow(const std::string& path, uint64_t offset, const LogEvent& e) {
  T msg;
  if (msg.decode(e.data.data(), 0, static_cast<int>(e.data.size())) < 0) {
    throw ProfileLogError(path + ": " + e.channel + " message at byte " + std::to_string(offset) +
                          " does not decode");
  }
  return msg;
}

TestPieceTruth testPieceTruth(const truth_test_piece_t& t) {
  TestPieceTruth p;
  p.sweep_id = t.sweep_id;
  p.origin = Eigen::Vector3d(t.origin[0], t.origin[1], t.origin[2]);
  p.u = Eigen::Vector3d(t.u_axis[0], t.u_axis[1], t.u_axis[2]);
  p.v = Eigen::Vector3d(t.v_axis[0], t.v_axis[1], t.v_axis[2]);
  p.w = Eigen::Vector3d(t.w_axis[0], t.w_axis[1], t.w_axis[2]);
  TestPieceConfig& c = p.sizes;
  c.distance_mm = 0.0;
  c.block_length_mm = t.block_length_mm;
  c.block_width_mm = t.block_width_mm;
  c.spacing_mm = t.spacing_mm;
  c.left_diameter_mm = t.left_diameter_mm;
  c.left_depth_mm = t.left_depth_mm;
  c.right_diameter_mm = t.right_diameter_mm;
  c.right_depth_mm = t.right_depth_mm;
  c.rect_length_mm = t.rect_length_mm;
  c.rect_width_mm = t.rect_width_mm;
  c.rect_depth_mm = t.rect_depth_mm;
  return p;
}

}  // namespace

ProfileLog readProfileLog(const std::string& path) {
  ProfileLog out;
  std::map<int32_t, size_t> index;  // sweep id -> out.sweeps
  try {
    EventLogReader reader(path);
    LogEvent e;
    for (uint64_t offset = reader.offset(); reader.next(&e); offset = reader.offset()) {
      if (e.channel == channels::kTruthProfileRig && !out.truth) {
        const auto t = decodeOrThrow<truth_profile_rig_t>(path, offset, e);
        out.truth = ProfileLogTruth{
            {t.offset_m_mm, t.offset_n_mm, t.laser_tilt_rad, t.encoder_zero_rad}, t.scene};
      }
      if (e.channel == channels::kTruthTestPiece && !out.test_piece) {
        out.test_piece = testPieceTruth(decodeOrThrow<truth_test_piece_t>(path, offset, e));
      }
      if (e.channel != channels::kProfile) continue;
      const auto msg = decodeOrThrow<profile_t>(path, offset, e);
      if (const std::string why = validateProfile(msg); !why.empty()) {
        throw ProfileLogError(path + ": PROFILE at byte " + std::to_string(offset) + " (sequence " +
                              std::to_string(msg.sequence) + "): " + why);
      }
      ++out.profiles;
      auto [it, added] = index.emplace(msg.sweep_id, out.sweeps.size());
      if (added) {
        out.sweeps.push_back({path + " sweep " + std::to_string(msg.sweep_id), {}});
      }
      PlanePoints& plane = out.sweeps[it->second];
      const double encoder_rad =
          turntableAngleRad(msg.encoder_counts, msg.counts_per_revolution, 0.0);
      for (int32_t i = 0; i < msg.point_count; ++i) {
        plane.samples.push_back({msg.y_mm[i], msg.z_mm[i], encoder_rad});
      }
    }
  } catch (const LogError& err) {
    throw ProfileLogError(err.what());
  }
  if (out.profiles == 0) {
    throw ProfileLogError(path + ": no " + std::string(channels::kProfile) +
                          " messages (not a rig C log?)");
  }
  return out;
}

}  // namespace sweepmap
