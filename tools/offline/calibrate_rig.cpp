// `sweepmap calib rig`'s workflow in named steps: check the inputs, read the logs' sweeps
// (planes and plate rays), solve, write the file, report; and `calib plan`.
#include "tools/offline/calibrate_rig.hpp"

#include <algorithm>
#include <condition_variable>
#include <deque>
#include <exception>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <thread>

#include "calib/rig_a_calibration.hpp"
#include "core/angles.hpp"
#include "core/calibration_file.hpp"
#include "core/event_log.hpp"
#include "core/exit_codes.hpp"
#include "core/progress.hpp"
#include "tools/offline/calibrate_common.hpp"
#include "tools/offline/calibrate_logs.hpp"
#include "tools/offline/calibrate_rig_kinds.hpp"
#include "tools/offline/log_sweeps.hpp"

namespace sweepmap {
namespace {

using calib_workflow::kCalibRig;

namespace fs = std::filesystem;
using calib_workflow::Clock;
using calib_workflow::seconds;

struct RigAInputs {
  std::vector<RigASweep> sweeps;
  std::vector<std::string> rejected;
  std::vector<std::string> log_errors;
  RigATruth truth;
  double read_s = 0.0;
};

// A sweep read from a log, waiting for its planes and plate rays (takeSweep).
struct SweepJob {
  std::string source;
  AssembledSweep sweep;
  std::vector<Scan2D> scans;
  std::optional<RigASweep> taken;
  std::string rejected;  // why not, when not taken
  std::exception_ptr error;
};

// One sweep's planes and plate rays into job->taken, or why not into job->rejected.
void takeSweep(const RigCalibRequest& o, const RotatingLidarConfig& rig, SweepJob* job) try {
  const AssembledSweep& s = job->sweep;
  if (s.window.accel_overlap) {
    job->rejected = "motor ramp overlapped the lidar window";
    return;
  }
  std::vector<SweepRay> rays;
  rays.reserve(s.points_Op.size());
  forEachSweepRay(job->scans, s.window.omega_rad_s, [&](const SweepRay& r) { rays.push_back(r); });
  RigASweep sweep;
  sweep.source = job->source;
  sweep.planes = segmentSweepPlanes(s.points_Op, rays, o.segmentation, job->source);
  if (sweep.planes.empty()) {
    job->rejected = "no plane found";
    return;
  }
  takePlateCandidates(rays, rigAValuesOf(rig), PlateRegion::fromConfig(rig.plate), &sweep);
  job->taken = std::move(sweep);
} catch (...) {
  job->error = std::current_exception();
}

// The sweeps segmented on two workers while the logs are read (a sweep's planes depend on its
// rays alone: the same result whatever the threads): the segmentation is ~80 % of reading.
// At most one sweep waits while the workers segment theirs (and the reader holds the next),
// so a log's rays are never all in memory at once.
constexpr size_t kSweepWorkers = 2;

class SweepPool {
 public:
  SweepPool(const RigCalibRequest& o, const RotatingLidarConfig& rig) : o_(o), rig_(rig) {
    for (size_t k = 0; k < kSweepWorkers; ++k) workers_.emplace_back([this] { work(); });
  }
  ~SweepPool() { stop(); }

  // Stops without segmenting the sweeps still queued (a log could not be read: they are not
  // used).
  void cancel() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      cancelled_ = true;
    }
    stop();
  }

  // Queues a sweep; waits while one waits already.
  void push(SweepJob job) {
    std::unique_lock<std::mutex> lock(mutex_);
    room_.wait(lock, [&] { return next_ == jobs_.size(); });
    jobs_.push_back(std::move(job));
    ready_.notify_one();
  }

  // Every sweep into in->sweeps or in->rejected, in the logs' order; rethrows a worker's error.
  void finish(RigAInputs* in) {
    stop();
    for (SweepJob& job : jobs_) {
      if (job.error) std::rethrow_exception(job.error);
      if (job.taken) {
        in->sweeps.push_back(std::move(*job.taken));
        continue;
      }
      in->rejected.push_back(job.source + ": " + job.rejected);
      if (!o_.json) std::cerr << "  " << job.source << ": rejected: " << job.rejected << "\n";
    }
    jobs_.clear();
  }

 private:
  void work() {
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
      ready_.wait(lock, [&] { return done_ || cancelled_ || next_ < jobs_.size(); });
      if (cancelled_ || next_ == jobs_.size()) return;  // cancelled, or done_ and nothing left
      SweepJob* job = &jobs_[next_++];                  // a deque's elements stay where they are
      room_.notify_one();
      lock.unlock();
      takeSweep(o_, rig_, job);
      job->scans = {};  // the rays are in job->taken now
      job->sweep = {};
      lock.lock();
    }
  }

  void stop() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      done_ = true;
    }
    ready_.notify_all();
    for (auto& t : workers_) t.join();
    workers_.clear();
  }

  const RigCalibRequest& o_;
  const RotatingLidarConfig& rig_;
  std::mutex mutex_;
  std::condition_variable ready_, room_;
  std::deque<SweepJob> jobs_;
  size_t next_ = 0;  // the first job no worker has taken
  bool done_ = false;
  bool cancelled_ = false;
  std::vector<std::thread> workers_;
};

void takeTruth(const LogReadResult& r, RigATruth* t) {
  if (r.alpha_true_rad) t->alpha_deg = *r.alpha_true_rad * kRadToDeg;
  if (r.lidar_offset_x_true_m) t->offset_x_mm = *r.lidar_offset_x_true_m * 1e3;
  if (r.scan_plane_tilt_true_rad) t->tilt_deg = *r.scan_plane_tilt_true_rad * kRadToDeg;
  if (r.mirror_offset_true_rad) t->mirror_deg = *r.mirror_offset_true_rad * kRadToDeg;
}

// Every sweep of every log; false (after saying so) if a log cannot be opened.
bool readLogs(const RigCalibRequest& o, const RotatingLidarConfig& rig, Progress& progress,
              RigAInputs* in) {
  const auto t0 = Clock::now();
  LidarLogReading r;
  SweepPool pool(o, rig);
  r.take_sweep = [&](const std::string& log, const AssembledSweep& s,
                     const std::vector<Scan2D>& scans) {
    pool.push({log + " sweep " + std::to_string(s.window.sweep_id), s, scans, {}, {}, {}});
  };
  r.took_log = [&](const LogReadResult& l) { takeTruth(l, &in->truth); };
  r.progress = &progress;
  if (!readLidarLogs(o.logs, rig, kCalibRig, r, &in->log_errors)) {
    pool.cancel();
    return false;
  }
  pool.finish(in);
  in->read_s = seconds(Clock::now() - t0);
  return true;
}

// The rig file's key that applies the file `calib rig` writes for the kind.
std::string calibrationFileKey(RigKind kind) {
  if (kind == RigKind::kRotatingProfile) return "geometry.calibration_file";
  return "calibration_file";
}

// How the rig file points at `out`: its calibration_file, relative to the rig file's folder.
// `key` is the rig kind's calibration_file key.
std::string pointRigAt(const std::string& rig_path, const std::string& key,
                       const std::string& out) {
  const fs::path rig_dir = fs::absolute(rig_path).parent_path();
  const fs::path rel = fs::absolute(out).lexically_relative(rig_dir);
  const bool installed = fs::absolute(rig_path).lexically_normal().string().rfind(
                             fs::absolute(configDir()).lexically_normal().string(), 0) == 0;
  std::ostringstream s;
  if (installed) {
    const fs::path copy = fs::path(rig_path).filename();
    s << "to use it: copy the installed rig file here (sweepmap sim --rig " << rig_path
      << " --print-config > " << copy.string() << " is one way, or cp " << rig_path << " .), set "
      << key << ": " << fs::absolute(out).lexically_relative(fs::current_path()).string()
      << " in it, and pass --rig " << copy.string();
  } else {
    s << "to use it: set " << key << ": " << rel.string() << " in " << rig_path
      << " (relative to the rig file's folder)";
  }
  return s.str();
}

int calibrateRigA(const RigCalibRequest& o, const Rig& loaded) {
  const RotatingLidarConfig& rig = std::get<RotatingLidarConfig>(loaded.config);
  for (const auto& log : o.logs) {
    if (!calib_workflow::logFileExists(log, kCalibRig)) return kExitUsage;
  }
  if (!calib_workflow::outputDirExists(o.out, kCalibRig)) return kExitUsage;
  ProgressOptions po;
  po.enabled = !o.json;
  Progress progress(kCalibRig, po);
  RigAInputs in;
  if (!readLogs(o, rig, progress, &in)) return kExitBadInput;
  if (in.sweeps.empty()) {
    progress.finish();
    std::cerr << kCalibRig << ": no usable sweep in the logs (" << in.rejected.size()
              << " rejected): nothing calibrated\n";
    if (o.json)
      std::cout << nlohmann::json{{"sweeps_used", 0}, {"sweeps_rejected", in.rejected}}.dump(2)
                << "\n";
    return 1;
  }
  RigASolveOptions so = rigASolveOptions(rig);
  so.truth = in.truth;
  progress.stage("solving");
  RigCalibration c;
  {
    ProgressTicker ticker(progress);
    c = solveRigA(in.sweeps, so);
  }
  progress.finish();
  c.rejected = in.rejected;
  for (const auto& e : in.log_errors) c.warnings.push_back(e);
  return reportRigCalibration(o, loaded, in.read_s, c,
                              [&] { writeRigCalibrationOf(o, loaded, c); });
}

// Rig A's plan: the recording and why.
void printRigAPlan(const std::string& rig_name, const RotatingLidarConfig& rig_a) {
  const RigARecording r;
  const ScanMode mode = scanMode(r.mode);
  // Each sweep: the window, the ramps and homing (~3 s), the return at the move speed.
  const double minutes =
      r.sweeps * (mode.period_s + 3.0 + r.sweep_angle_deg / rig_a.motor.move_speed_deg_s) / 60.0;
  std::cout
      << "What to record for `sweepmap calib rig --rig " << rig_name << "` (rotating_lidar):\n"
      << "  scene:    a closed rectangular room, 4 to 10 m, its four walls in view over most of "
         "their height; the rig on its stand square to the walls (its front, X, facing one "
         "wall) and well inside the room (1 m or more from every wall); the plate clear.\n"
      << "            Why: the walls' planes fix each sweep's attitude and bend with the offset, "
         "the tilt and the mirror offset (the plane constraint); the plate angle alpha is "
         "defined against the walls (Yuan 2021 section 4.2). Clutter on the walls, people "
         "walking, a window are tolerated; a room with few plain walls is not.\n"
      << "  sweeps:   " << r.sweeps << ", mode " << r.mode << ", each a full turn (motor."
      << "sweep_angle_deg=" << r.sweep_angle_deg << ": " << mode.period_s << " s, gamma "
      << mode.gamma_deg * r.sweep_angle_deg / 180.0
      << " deg), rig standing still; the lidar's cable must allow one turn (the motor turns "
         "back after each sweep)\n"
      << "            Why: a full turn shows the plate and every wall from both sides of the "
         "scan plane. In a half turn each part of the plate is seen from one side, and 1 mm of "
         "lidar-to-axis offset turns it by ~0.73 deg (it sits 55-111 mm from the axis): alpha "
         "is then only as good as the offset the walls give (10 sweeps: sigma ~0.15 mm, so "
         "alpha ~0.11 deg). Seen from both sides, the offset turns the plate's two views "
         "opposite ways and doubles each wall: alpha's sigma falls to 0.002-0.007 deg (~0.0035 "
         "deg typical), the offset's to ~0.1 mm, from 10 sweeps (both fall as 1/sqrt(sweeps)). "
         "Half turns (the rig's "
         "sweep angle) still calibrate, with those larger sigmas.\n"
      << "  duration: about " << std::fixed << std::setprecision(1) << minutes
      << " min (sweeps, returns and homing)\n"
      << "  record:   sweepmap record --rig " << rig_name
      << " --out calib.lcmlog (live, the motor run from a rig file with motor.sweep_angle_deg: "
      << r.sweep_angle_deg << "), or lcm-logger\n"
      << "  simulate: sweepmap sim --rig " << rig_name << " "
      << calibrationRecordingSimLine(RigKind::kRotatingLidar) << " --out calib.lcmlog\n"
      << "  then:     sweepmap calib rig --rig " << rig_name
      << " --logs calib.lcmlog --out rig_calibration.yaml\n";
}

}  // namespace

int reportRigCalibration(const RigCalibRequest& o, const Rig& loaded, double read_s,
                         const RigCalibration& c, const std::function<void()>& write) {
  const bool any = std::any_of(c.parameters.begin(), c.parameters.end(),
                               [](const CalibParameter& p) { return p.observable; });
  bool written = false;
  if (any) {
    try {
      write();
      written = true;
    } catch (const std::exception& e) {
      std::cerr << kCalibRig << ": " << e.what() << "\n";
      return kExitDeviceIo;
    }
  }
  std::cerr << kCalibRig << " (" << loaded.kindName() << "): ";
  if (loaded.kind() == RigKind::kMobileLidar) {
    std::cerr << o.logs.size() << " drive(s); ";
  } else {
    std::cerr << c.sweeps_used << " sweeps (" << c.rejected.size() << " rejected); ";
  }
  std::cerr << "reading " << std::fixed << std::setprecision(1) << read_s << " s, solving "
            << c.seconds << " s\n"
            << rigCalibrationReport(c);
  std::cerr.unsetf(std::ios::floatfield);
  if (written) {
    std::cerr << "  wrote " << o.out << "\n  "
              << pointRigAt(loaded.path, calibrationFileKey(loaded.kind()), o.out) << "\n";
  } else {
    std::cerr << "  nothing written: no parameter is observable from these logs\n";
  }
  if (o.json) {
    nlohmann::json j = rigCalibrationJson(c);
    j["rig"] = loaded.path;
    j["out"] = written ? nlohmann::json(o.out) : nullptr;
    j["timing_s"] = {{"read", read_s}, {"solve", c.seconds}};
    std::cout << std::setprecision(12) << j.dump(2) << "\n";
  }
  return written ? 0 : 1;
}

int calibrateRigFromLogs(const RigCalibRequest& o) {
  Rig rig;
  try {
    rig = loadRig(o.rig, o.sets);
  } catch (const std::exception& e) {
    std::cerr << kCalibRig << ": config error: " << e.what() << "\n";
    return kExitUsage;
  }
  if (rig.kind() == RigKind::kRotatingProfile) return calibrateProfileRig(o, rig);
  if (rig.kind() == RigKind::kMobileLidar) return calibrateMobileLidarRig(o, rig);
  return calibrateRigA(o, rig);
}

int printCalibrationPlan(const std::string& rig_name, const std::vector<std::string>& sets) {
  Rig rig;
  try {
    rig = loadRig(rig_name, sets);
  } catch (const std::exception& e) {
    std::cerr << "calib plan: config error: " << e.what() << "\n";
    return kExitUsage;
  }
  if (rig.kind() == RigKind::kRotatingProfile) return printProfileRigPlan(rig_name, rig);
  if (rig.kind() == RigKind::kMobileLidar) return printMobileLidarRigPlan(rig_name, rig);
  printRigAPlan(rig_name, std::get<RotatingLidarConfig>(rig.config));
  return 0;
}

RigAValues rigAValuesOf(const RotatingLidarConfig& rig) {
  return {rig.plate.alpha_deg, rig.geometry.lidar_offset_x_mm, rig.geometry.scan_plane_tilt_deg,
          rig.geometry.mirror_offset_deg};
}

RigASolveOptions rigASolveOptions(const RotatingLidarConfig& rig) {
  RigASolveOptions so;
  so.nominal = rigAValuesOf(rig);
  so.plate = PlateModel::fromConfig(rig.plate);
  so.region = PlateRegion::fromConfig(rig.plate);
  so.min_plate_hits = rig.plate.min_points;
  return so;
}

}  // namespace sweepmap
