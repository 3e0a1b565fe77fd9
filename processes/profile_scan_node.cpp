#include "processes/profile_scan_node.hpp"

#include <cmath>
#include <cstdlib>

#include "processes/channels.hpp"
#include "processes/convert.hpp"
#include "processes/sim_setup.hpp"

namespace sweepmap {

ProfileScanNode::ProfileScanNode(const ProfilerConfig& profiler, const TurntableConfig& turntable,
                                 TurntableDevice* table, ProfilerDevice* sensor,
                                 const ProfileScanOptions& options)
    : Node("profiler"),
      profiler_(profiler),
      turntable_(turntable),
      table_(table),
      sensor_(sensor),
      options_(options) {}

void ProfileScanNode::advance(int64_t now_utime, Outbox& out) {
  readHealth();
  // Devices first, then the decisions: the profiles up to now are judged against the window
  // the encoder samples up to now define.
  readEncoder(now_utime);
  step(now_utime);
  publishProfiles(now_utime, out);
}

void ProfileScanNode::readHealth() {
  for (auto [device, prefix] :
       {std::pair<DeviceHealth, const char*>{table_->health(), "turntable_"},
        {sensor_->health(), "profiler_"}}) {
    for (const auto& [name, value] : device.counters) setCounter(prefix + name, value);
    for (const std::string& e : device.events) reportEvent(e);
    if (!device.fatal.empty() && !failed()) setFailed(device.fatal);
  }
}

void ProfileScanNode::readEncoder(int64_t now_utime) {
  for (const EncoderSample& s : table_->poll(now_utime)) {
    if (has_sample_ && s.utime <= last_.utime) {
      reportError("invalid", "encoder sample out of order, dropped");
      continue;
    }
    has_sample_ = true;
    last_ = s;
    count("encoder_samples");
  }
}

bool ProfileScanNode::at(double target_deg) const {
  const double target_counts = target_deg / 360.0 * table_->countsPerRevolution();
  return has_sample_ && std::fabs(static_cast<double>(last_.counts) - target_counts) <= 1.0;
}

void ProfileScanNode::move(int64_t now_utime, double target_deg) {
  const double from_deg =
      has_sample_ ? 360.0 * static_cast<double>(last_.counts) / table_->countsPerRevolution()
                  : turntable_.sweep_start_deg;
  const double time_s = std::fabs(target_deg - from_deg) / turntable_.speed_deg_s;
  move_deadline_ = now_utime + static_cast<int64_t>((2 * time_s + 2.0) * 1e6);
  table_->command(now_utime, {target_deg, turntable_.speed_deg_s});
}

void ProfileScanNode::step(int64_t now_utime) {
  if (failed()) return;
  const bool moving = phase_ == Phase::kPositioning || phase_ == Phase::kSweeping;
  if (moving && now_utime > move_deadline_) {
    setFailed("the turntable did not reach " +
              std::to_string(phase_ == Phase::kSweeping ? turntable_.sweep_end_deg
                                                        : turntable_.sweep_start_deg) +
              " deg in time (encoder at " + std::to_string(last_.counts) + " counts)");
    return;
  }
  switch (phase_) {
    case Phase::kStart:
      move(now_utime, turntable_.sweep_start_deg);
      phase_ = Phase::kPositioning;
      break;
    case Phase::kPositioning:
      if (!at(turntable_.sweep_start_deg)) break;
      pause_until_ =
          last_.utime + (sweeps_done_ == 0 ? 0 : static_cast<int64_t>(options_.pause_s * 1e6));
      phase_ = Phase::kPausing;
      [[fallthrough]];
    case Phase::kPausing:
      if (now_utime < pause_until_) break;
      window_id_ = sweeps_done_;
      window_start_ = now_utime;
      window_end_ = INT64_MAX;
      move(now_utime, turntable_.sweep_end_deg);
      phase_ = Phase::kSweeping;
      reportEvent("sweep " + std::to_string(window_id_) + " started");
      break;
    case Phase::kSweeping:
      if (!at(turntable_.sweep_end_deg)) break;
      window_end_ = last_.utime;
      ++sweeps_done_;
      count("sweeps");
      if (options_.sweeps > 0 && sweeps_done_ >= options_.sweeps) {
        phase_ = Phase::kDone;
        reportEvent("done: " + std::to_string(sweeps_done_) + " sweeps");
      } else {
        move(now_utime, turntable_.sweep_start_deg);
        phase_ = Phase::kPositioning;
      }
      break;
    case Phase::kDone:
      break;
  }
}

void ProfileScanNode::publishProfiles(int64_t now_utime, Outbox& out) {
  for (Profile& p : sensor_->poll(now_utime)) {
    if (window_id_ < 0 || p.utime < window_start_ || p.utime > window_end_) {
      count("profiles_outside_sweeps");
      continue;
    }
    p.sweep_id = window_id_;
    const profile_t m = toLcm(p);
    if (const std::string why = validateProfile(m); !why.empty()) {
      reportError("invalid", "device profile " + std::to_string(p.sequence) + " dropped: " + why);
      continue;
    }
    count("profiles");
    out.publish(channels::kProfile, now_utime, m);
  }
}

ProfileTruthNode::ProfileTruthNode(SimProfileWorld* world) : Node("profile_truth"), world_(world) {}

void ProfileTruthNode::advance(int64_t now_utime, Outbox& out) {
  for (const auto& [utime, k] : world_->takePlacements(now_utime)) {
    out.publish(channels::kTruthProfileRig, now_utime,
                makeTruthProfileRig(world_->sim(), k, utime, world_->plate(k)));
    if (const auto frame = world_->scene(k).testPieceFrame()) {
      out.publish(channels::kTruthTestPiece, now_utime,
                  makeTruthTestPiece(world_->sim().test_piece, *frame, k, utime));
    }
    count("truths");
  }
}

}  // namespace sweepmap
