#include "tools/offline/sim_mobile.hpp"

#include <algorithm>
#include <cmath>

#include "core/rig_components.hpp"
#include "processes/channels.hpp"
#include "processes/convert.hpp"
#include "processes/sim_car.hpp"
#include "processes/sim_setup.hpp"
#include "sim/mobile.hpp"
#include "tools/offline/simulation.hpp"

namespace sweepmap {

namespace {

// One stream's event in the merged log: its time, its stream (the tie-break at equal
// times) and its index in that stream.
struct Stamped {
  int64_t utime;
  int order;  // -1 TRUTH_MOUNTING (and TRUTH_MOBILE_RIG), 0 TRUTH_POSE, 1 WHEEL_TICKS, 2 IMU, 3
              // LIDAR_SCAN
  size_t index;
};

}  // namespace

SimMobileResult simulateMobile(const SimMobileOptions& options,
                               const std::function<void(const Message&)>& sink) {
  const MobileLidarConfig& rig = options.rig;
  const Scene scene(options.scene, PlateConfig{});
  const int64_t t0 = kSimEpochUtime;
  const std::unique_ptr<SimMobile> simulated = makeSimCar(rig, scene, options.seed, t0);
  SimMobile& car = *simulated;

  // Each stream is generated whole, then the streams are merged by event time.
  std::vector<Stamped> events;
  const auto truth = car.truth();
  // TRUTH_MOUNTING at start and at 1 Hz (order -1: before anything else at the same time).
  const int64_t truth_mounting_count = static_cast<int64_t>(std::floor(rig.sim.duration_s)) + 1;
  for (int64_t i = 0; i < truth_mounting_count; ++i) {
    events.push_back({t0 + i * 1000000, -1, static_cast<size_t>(i)});
  }
  const auto ticks = car.wheelTicks();
  const auto imu = car.imu();
  const auto scans = car.scans();
  for (size_t i = 0; i < truth.size(); ++i) events.push_back({truth[i].utime, 0, i});
  for (size_t i = 0; i < ticks.size(); ++i) events.push_back({ticks[i].utime, 1, i});
  for (size_t i = 0; i < imu.size(); ++i) events.push_back({imu[i].utime, 2, i});
  for (size_t i = 0; i < scans.size(); ++i)
    events.push_back({car.scanDeliveryUtime(scans[i]), 3, i});
  std::stable_sort(events.begin(), events.end(), [](const Stamped& a, const Stamped& b) {
    return a.utime != b.utime ? a.utime < b.utime : a.order < b.order;
  });

  SimMobileResult result;
  for (const Stamped& e : events) {
    Outbox out;
    if (e.order == -1) {
      out.publish(channels::kTruthMounting, e.utime,
                  truthMountingMessage(rig, options.scene, car, e.utime));
      out.publish(channels::kTruthMobileRig, e.utime, truthMobileRigMessage(rig, car, e.utime));
    } else if (e.order == 0) {
      out.publish(channels::kTruthPose, e.utime, truthPoseMessage(truth[e.index]));
    } else if (e.order == 1) {
      out.publish(channels::kWheelTicks, e.utime, toLcm(ticks[e.index]));
    } else if (e.order == 2) {
      out.publish(channels::kImu, e.utime, toLcm(imu[e.index]));
    } else {
      out.publish(channels::kLidarScan, e.utime, toLcm(scans[e.index]));
      ++result.scans;
    }
    for (auto& m : out.take()) {
      ++result.messages;
      sink(m);
    }
  }
  result.slip_events = static_cast<int>(car.slips().size());
  result.duration_s = rig.sim.duration_s;
  result.path_length_m = car.distanceAt(rig.sim.duration_s);
  return result;
}

}  // namespace sweepmap
