// sweepmap-profiler (rig C, Zhao 2021): drives the turntable through its sweeps and
// publishes the profile sensor's raw profiles on PROFILE, one per message, numbered by the
// sweep they belong to. One process owns both devices, because the profiler latches the
// turntable's encoder count with each exposure (its encoder input) and a sweep needs both:
// as sweepmap-odometry owns rig B's IMU and wheel board.
//
// A sweep: the table moves to turntable.sweep_start_deg (speed_deg_s), waits `pause_s`
// (before every sweep but the first: the operator moves the calibration plate), turns to
// sweep_end_deg at speed_deg_s; the profiles exposed from that command until the encoder
// reads the end belong to the sweep (sweep_id 0, 1, ...). Profiles outside a sweep are
// counted, not published. A move that does not arrive within twice its time + 2 s fails
// the node. Decisions depend only on the devices' stamps and the tick times.
#pragma once

#include <cstdint>

#include "devices/profiler_device.hpp"
#include "devices/turntable_device.hpp"
#include "processes/node.hpp"
#include "sim/profile_devices.hpp"

namespace sweepmap {

struct ProfileScanOptions {
  int sweeps = 0;        // sweeps to make, then done(); 0 = until stopped
  double pause_s = 1.0;  // at the start angle before every sweep but the first
};

class ProfileScanNode : public Node {
 public:
  enum class Phase { kStart, kPositioning, kPausing, kSweeping, kDone };
  ProfileScanNode(const ProfilerConfig& profiler, const TurntableConfig& turntable,
                  TurntableDevice* table, ProfilerDevice* sensor,
                  const ProfileScanOptions& options);
  std::vector<std::string> subscriptions() const override { return {}; }
  bool done() const { return phase_ == Phase::kDone; }
  Phase phase() const { return phase_; }
  int sweepsDone() const { return sweeps_done_; }

 protected:
  void handle(const Message& msg, Outbox& out) override {}
  void advance(int64_t now_utime, Outbox& out) override;

 private:
  void readHealth();
  void readEncoder(int64_t now_utime);
  void step(int64_t now_utime);
  void move(int64_t now_utime, double target_deg);
  bool at(double target_deg) const;
  void publishProfiles(int64_t now_utime, Outbox& out);

  ProfilerConfig profiler_;
  TurntableConfig turntable_;
  TurntableDevice* table_;
  ProfilerDevice* sensor_;
  ProfileScanOptions options_;
  Phase phase_ = Phase::kStart;
  bool has_sample_ = false;
  EncoderSample last_;
  int64_t move_deadline_ = 0;
  int64_t pause_until_ = 0;
  int sweeps_done_ = 0;
  // The current or last sweep's profile window [start, end] (end open while sweeping).
  int32_t window_id_ = -1;
  int64_t window_start_ = 0, window_end_ = 0;
};

// Simulation only: publishes TRUTH_PROFILE_RIG when the simulated operator puts a scene in
// place (its index is the sweep that sees it).
class ProfileTruthNode : public Node {
 public:
  explicit ProfileTruthNode(SimProfileWorld* world);
  std::vector<std::string> subscriptions() const override { return {}; }

 protected:
  void handle(const Message& msg, Outbox& out) override {}
  void advance(int64_t now_utime, Outbox& out) override;

 private:
  SimProfileWorld* world_;
};

}  // namespace sweepmap
