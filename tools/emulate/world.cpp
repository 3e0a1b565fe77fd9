#include "tools/emulate/world.hpp"

#include <cmath>
#include <limits>
#include <random>

#include "core/config.hpp"
#include "devices/shaft_trajectory.hpp"
#include "processes/channels.hpp"
#include "processes/lidar_node.hpp"
#include "processes/sim_car.hpp"
#include "processes/sim_setup.hpp"
#include "processes/truth_sweep_node.hpp"
#include "rigs/mobile_lidar.hpp"
#include "rigs/rotating_lidar.hpp"
#include "sim/car_devices.hpp"
#include "sim/lidar.hpp"
#include "sim/mobile.hpp"
#include "sim/scene.hpp"
#include "tools/offline/runs.hpp"

namespace sweepmap {
namespace {

// Runs `inner` under the world's mutex: the server thread reads the shaft truth that the
// LCM thread extends.
class LockedNode : public Node {
 public:
  LockedNode(Node* inner, std::mutex* mutex) : Node(inner->name()), inner_(inner), mutex_(mutex) {}
  std::vector<std::string> subscriptions() const override { return inner_->subscriptions(); }
  void finish(int64_t now_utime, Outbox& out) override {
    std::lock_guard<std::mutex> lock(*mutex_);
    inner_->finish(now_utime, out);
  }

 protected:
  void handle(const Message& msg, Outbox& out) override {
    std::lock_guard<std::mutex> lock(*mutex_);
    inner_->receive(msg, out);
  }
  void advance(int64_t now_utime, Outbox& out) override {
    std::lock_guard<std::mutex> lock(*mutex_);
    inner_->tick(now_utime, out);
  }

 private:
  Node* inner_;
  std::mutex* mutex_;
};

class RotatingWorld : public EmulatorWorld {
 public:
  RotatingWorld(const SimSetup& setup, const EmulatorWorldOptions& options, int64_t start_utime)
      : rig_(std::get<RotatingLidarConfig>(setup.rig.config)),
        scene_config_(setup.scene),
        scene_(setup.scene, rig_.plate),
        follow_(options.follow_lcm) {
    LidarConfig timed = rig_.lidar;
    timed.scan_rate_hz *= 1.0 + options.clock_drift_ppm * 1e-6;
    if (follow_) {
      // Until the simulated stepper's TRUTH_SHAFT arrives the shaft stands where it powers
      // up, and a real lidar measures all the same: those scans come from a second simulated
      // lidar, so that the main one draws its noise exactly as `sweepmap-lidar --device sim`
      // does (from the first scan the shaft's truth covers): the same seed, the same noise.
      idle_truth_.apply(ShaftSegment{start_utime, kSimInitialShaftAngleRad, 0.0, 0.0});
      idle_ = std::make_unique<SimLidar>(timed, rig_.sim, rig_.plate, scene_, &idle_truth_,
                                         lidarSeed(options.seed) + 1000003, start_utime);
    } else {
      truth_.apply(ShaftSegment{start_utime, 0.0, 0.0, 0.0});  // a shaft that stands still
    }
    lidar_ = std::make_unique<SimLidar>(timed, rig_.sim, rig_.plate, scene_, &truth_,
                                        lidarSeed(options.seed), start_utime);
    if (follow_) {
      follower_ = std::make_unique<TruthFollowerNode>(&truth_);
      truth_sweep_ =
          std::make_unique<TruthSweepNode>(&truth_, rig_.sim.alpha_true_deg * M_PI / 180.0);
      locked_follower_ = std::make_unique<LockedNode>(follower_.get(), &mutex_);
      locked_truth_sweep_ = std::make_unique<LockedNode>(truth_sweep_.get(), &mutex_);
    }
  }

  ScanSource source(const BeamOffset& beam) override {
    if (beam) {
      throw std::runtime_error(
          "a lidar whose beam looks off its motor angle (the X4) needs a mobile_lidar rig");
    }
    return [this](int64_t now_us) {
      std::lock_guard<std::mutex> lock(mutex_);
      std::vector<Scan2D> scans = lidar_->poll(now_us);
      if (idle_) {
        std::vector<Scan2D> idle = idle_->poll(now_us);
        if (scans.empty() && truth_.empty()) scans = std::move(idle);
      }
      // Each scan time once, in order (the two lidars share their scan times).
      std::vector<Scan2D> out;
      for (Scan2D& s : scans) {
        if (s.utime <= last_utime_) continue;
        last_utime_ = s.utime;
        out.push_back(std::move(s));
      }
      return out;
    };
  }
  std::vector<Node*> nodes() override {
    if (!follow_) return {};
    return {locked_follower_.get(), locked_truth_sweep_.get()};
  }
  std::vector<Message> startMessages(int64_t now_us) override {
    if (!follow_) return {};
    Outbox out;
    out.publish(channels::kTruthRig, now_us, makeTruthRig(rig_, scene_config_, scene_, now_us));
    return out.take();
  }

 private:
  std::string lidarModel() const override { return rig_.lidar.model; }
  RotatingLidarConfig rig_;
  SceneConfig scene_config_;
  Scene scene_;
  bool follow_;
  std::mutex mutex_;
  ShaftTrajectory truth_, idle_truth_;
  std::unique_ptr<SimLidar> lidar_, idle_;
  int64_t last_utime_ = std::numeric_limits<int64_t>::min();
  std::unique_ptr<TruthFollowerNode> follower_;
  std::unique_ptr<TruthSweepNode> truth_sweep_;
  std::unique_ptr<LockedNode> locked_follower_, locked_truth_sweep_;
};

class MobileWorld : public EmulatorWorld {
 public:
  MobileWorld(const SimSetup& setup, const EmulatorWorldOptions& options, int64_t start_utime)
      : rig_(std::get<MobileLidarConfig>(setup.rig.config)),
        scene_(setup.scene, PlateConfig{}),
        rng_(options.seed * 8 + 3),
        lead_rng_(options.seed * 8 + 7) {
    MobileLidarConfig timed = rig_;
    timed.sim.scan_rate_hz *= 1.0 + options.clock_drift_ppm * 1e-6;
    timed.sim.sample_rate_hz *= 1.0 + options.clock_drift_ppm * 1e-6;
    car_ = makeSimCar(timed, scene_, options.seed, start_utime);
    imu_ = std::make_unique<SimImu>(car_.get());
    wheels_ = std::make_unique<SimWheels>(car_.get());
    if (options.publish_truth) {
      truth_ = std::make_unique<SimCarTruthNode>(rig_, setup.scene, car_.get());
      locked_truth_ = std::make_unique<LockedNode>(truth_.get(), &mutex_);
    }
  }

  ImuSource imuSource() override {
    return [this](int64_t now_us) {
      std::lock_guard<std::mutex> lock(mutex_);
      return imu_->poll(now_us);
    };
  }
  TicksSource ticksSource() override {
    return [this](int64_t now_us) {
      std::lock_guard<std::mutex> lock(mutex_);
      return wheels_->poll(now_us);
    };
  }
  std::vector<Node*> nodes() override {
    if (!locked_truth_) return {};
    return {locked_truth_.get()};
  }

  ScanSource source(const BeamOffset& beam) override {
    return [this, beam](int64_t now_us) {
      std::lock_guard<std::mutex> lock(mutex_);
      std::vector<Scan2D> out;
      if (!started_) {
        // A powered X4 streams from the moment it is opened: before the car starts, the scans
        // of the car at rest (negative indices, their noise from their own generator so that
        // the run's scans are those of the same seed elsewhere).
        started_ = true;
        next_ = std::min<int64_t>(0, car_->scanIndexAt(now_us));
      }
      for (;;) {
        if (!pending_) {
          pending_ = car_->makeScan(next_, next_ < 0 ? &lead_rng_ : &rng_, beam);
          ++next_;
        }
        // As the scan begins: a sample-streaming device sends each ray at its own time.
        if (pending_->utime > now_us) break;
        out.push_back(std::move(*pending_));
        pending_.reset();
      }
      return out;
    };
  }

 private:
  std::string lidarModel() const override { return rig_.lidar.model; }
  MobileLidarConfig rig_;
  Scene scene_;
  std::mutex mutex_;
  std::unique_ptr<SimMobile> car_;
  std::unique_ptr<SimImu> imu_;
  std::unique_ptr<SimWheels> wheels_;
  std::unique_ptr<SimCarTruthNode> truth_;
  std::unique_ptr<LockedNode> locked_truth_;
  std::mt19937_64 rng_;
  std::mt19937_64 lead_rng_;
  bool started_ = false;
  int64_t next_ = 0;
  std::optional<Scan2D> pending_;
};

}  // namespace

ImuSource EmulatorWorld::imuSource() {
  throw std::runtime_error("an IMU needs a mobile_lidar rig (the simulated car)");
}
TicksSource EmulatorWorld::ticksSource() {
  throw std::runtime_error("a wheel board needs a mobile_lidar rig (the simulated car)");
}

std::unique_ptr<EmulatorWorld> makeEmulatorWorld(const EmulatorWorldOptions& options,
                                                 int64_t start_utime) {
  const SimSetup setup = loadSimSetup(options.rig, options.scene, options.overrides);
  if (setup.rig.kind() == RigKind::kRotatingLidar) {
    return std::make_unique<RotatingWorld>(setup, options, start_utime);
  }
  if (options.follow_lcm) {
    throw std::runtime_error("--follow-lcm needs a rotating_lidar rig (the shaft's truth)");
  }
  return std::make_unique<MobileWorld>(setup, options, start_utime);
}

}  // namespace sweepmap
