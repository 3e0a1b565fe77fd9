#include "processes/stamp_guard.hpp"

#include <cstdio>
#include <cstdlib>

#include "processes/channels.hpp"

namespace sweepmap {
namespace {

// Raw sensor streams: a latency of milliseconds, 10 s of slack for a stalled machine.
constexpr StampGuard::Policy kSensor{10'000'000, 3};
// Sweep-level messages are stamped with the sweep's start and sent when it ends (16 s in
// rig A's mode 7): two minutes of slack.
constexpr StampGuard::Policy kSweep{120'000'000, 3};

std::string seconds(int64_t us) {
  char text[32];
  std::snprintf(text, sizeof text, "%+.3f s", static_cast<double>(us) * 1e-6);
  return text;
}

}  // namespace

std::optional<int64_t> StampGuard::peerOffset(const std::string& channel,
                                              int64_t tolerance_us) const {
  for (const auto& [name, stream] : streams_) {
    if (name != channel && stream.tolerance_us == tolerance_us) return stream.offset_us;
  }
  return std::nullopt;
}

std::optional<StampGuard::Policy> StampGuard::policyFor(const std::string& channel) {
  namespace c = channels;
  for (const char* sensor : {c::kLidarScan, c::kImu, c::kWheelTicks, c::kProfile, c::kMotorState,
                             c::kMotorSwitch, c::kOdometryPose, c::kWheelOdometry, c::kWheelCmd}) {
    if (channel == sensor) return kSensor;
  }
  for (const char* sweep : {c::kScanWindow, c::kSweepCloud, c::kSweepStatus}) {
    if (channel == sweep) return kSweep;
  }
  return std::nullopt;
}

bool StampGuard::admit(const std::string& channel, int64_t stamp_us, int64_t arrival_us,
                       std::string* why) {
  const std::optional<Policy> policy = policyFor(channel);
  if (!policy) return true;
  const int64_t offset = stamp_us - arrival_us;
  const std::optional<int64_t> peer =
      streams_.count(channel) ? std::nullopt : peerOffset(channel, policy->tolerance_us);
  auto [it, first] = streams_.try_emplace(channel);
  Stream& s = it->second;
  if (first) {
    s.tolerance_us = policy->tolerance_us;
    s.offset_us = peer.value_or(offset);  // judged against its peers until confirmed
  }
  if (std::llabs(offset - s.offset_us) <= policy->tolerance_us) {
    s.offset_us = offset;
    s.pending = 0;
    return true;
  }
  const bool agrees =
      s.pending > 0 && std::llabs(offset - s.pending_offset_us) <= policy->tolerance_us;
  s.pending = agrees ? s.pending + 1 : 1;
  s.pending_offset_us = offset;
  if (s.pending >= policy->confirmations) {
    s.offset_us = offset;
    s.pending = 0;
    return true;
  }
  *why = channel + " stamped " + seconds(offset - s.offset_us) +
         " off its stream (stamp minus arrival " + seconds(offset) + " against " +
         seconds(s.offset_us) + "): refused until " + std::to_string(policy->confirmations) +
         " messages in a row confirm the jump";
  return false;
}

}  // namespace sweepmap
