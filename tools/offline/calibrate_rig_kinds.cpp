// `calib rig` and `calib plan` for rigs B and C: see tools/offline/calibrate_rig_kinds.hpp.
#include "tools/offline/calibrate_rig_kinds.hpp"

#include <cmath>
#include <iomanip>
#include <iostream>
#include <limits>
#include <optional>
#include <sstream>

#include "calib/axis_offset.hpp"
#include "core/angles.hpp"
#include "core/calibration_file.hpp"
#include "core/config.hpp"
#include "core/event_log.hpp"
#include "core/exit_codes.hpp"
#include "core/progress.hpp"
#include "core/set_arguments.hpp"
#include "tools/offline/calibrate_axis_offset.hpp"
#include "tools/offline/calibrate_common.hpp"
#include "tools/offline/calibrate_logs.hpp"
#include "tools/offline/mobile_rig_calibration.hpp"
#include "tools/offline/profile_log.hpp"

namespace sweepmap {
namespace {

using calib_workflow::kCalibRig;

using calib_workflow::Clock;
using calib_workflow::seconds;

// The plan's recording of rig C and what the solver uses of it.
constexpr int kPlatePoses = 3;  // Zhao 2021's m = 3 non-parallel poses
constexpr int kMaxPointsPerSweep = 20000;
constexpr int kMinPointsPerSweep = 100;
std::string num(double v) {
  std::ostringstream s;
  s << std::setprecision(6) << v;
  return s.str();
}

bool checkPaths(const RigCalibRequest& o) {
  for (const auto& log : o.logs) {
    if (!calib_workflow::logFileExists(log, kCalibRig)) return false;
  }
  return calib_workflow::outputDirExists(o.out, kCalibRig);
}

// ---- rig C -------------------------------------------------------------------------------

using ProfileInputs = PlateSweeps;

// Where the encoder zero came from, or why it is left nominal.
struct ZeroSource {
  bool reference_used = false;  // exactly one sweep over the base's reference face
  std::string note;
};

// Why plate poses alone never give the zero (said in each note that holds it nominal).
constexpr const char* kPlatesCannotFixZero =
    "plate poses cannot fix the zero: a turn of the whole cloud about the axis leaves every "
    "plate a plane";

ZeroSource zeroSource(const RotatingProfileConfig& rig, const ProfileInputs& in,
                      const std::vector<size_t>& reference) {
  if (!rig.turntable.reference.declared) {
    return {false, std::string("the rig file declares no reference face on the base "
                               "(turntable.reference), and ") +
                       kPlatesCannotFixZero + "; it turns the map, never its shape"};
  }
  if (reference.empty()) {
    const double reach_deg =
        kReferenceToleranceDeg / std::sin(rig.turntable.reference.normal_tilt_deg * M_PI / 180.0);
    return {false, "no sweep over the base's reference face (no plane within " +
                       num(kReferenceToleranceDeg) +
                       " deg of turntable.reference's normal; one is recognised while the rig "
                       "file's encoder zero is within about " +
                       num(std::round(reach_deg)) + " deg of the truth), and " +
                       kPlatesCannotFixZero};
  }
  std::string sweeps;
  for (const size_t k : reference) sweeps += (sweeps.empty() ? "" : ", ") + in.planes[k].source;
  if (reference.size() > 1) {
    return {false, "sweeps " + sweeps +
                       " all look like the base's reference face (turntable.reference): a plate "
                       "pose laid like the face cannot be told from it, so none is used; record "
                       "one sweep over the face and lay the plate poses away from its direction "
                       "(calib plan)"};
  }
  return {true, "fixed by the base's reference face (turntable.reference), seen in " + sweeps};
}

// Why a parameter the solver did not determine is left nominal.
std::string profileNote(size_t i, const AxisOffsetResult& r, const ZeroSource& zero) {
  if (i < 2) return "the plate poses do not determine M and N (see the warnings)";
  if (i == 3 && !r.zero_estimated) {
    return zero.reference_used ? "the base's reference face was seen, but these sweeps did not "
                                 "determine the zero (see the warnings)"
                               : zero.note;
  }
  if (i == 3) return "sigma above the limit (see the warnings)";
  return "sigma above the limit, or not determined by these poses (see the warnings)";
}

RigCalibration profileResult(const RotatingProfileConfig& rig, const ProfileInputs& in,
                             const AxisOffsetResult& r, double max_sigma_deg,
                             const ZeroSource& zero) {
  const ProfileGeometryConfig& g = rig.geometry;
  const char* keys[] = {"geometry.offset_m_mm", "geometry.offset_n_mm", "geometry.laser_tilt_deg",
                        "geometry.encoder_zero_deg"};
  const double values[] = {r.geometry.m_mm, r.geometry.n_mm, r.geometry.laser_tilt_rad * kRadToDeg,
                           r.geometry.encoder_zero_rad * kRadToDeg};
  const double nominal[] = {g.offset_m_mm, g.offset_n_mm, g.laser_tilt_deg, g.encoder_zero_deg};
  const double sigma[] = {r.sigma_m_mm, r.sigma_n_mm, r.sigma_tilt_deg, r.sigma_zero_deg};
  const bool determined[] = {r.observable, r.observable,
                             r.tilt_estimated && sigma[2] <= max_sigma_deg,
                             r.zero_estimated && sigma[3] <= max_sigma_deg};
  RigCalibration c;
  for (size_t i = 0; i < 4; ++i) {
    CalibParameter p;
    p.key = keys[i];
    p.unit = i < 2 ? "mm" : "deg";
    p.nominal = nominal[i];
    p.observable = determined[i] && std::isfinite(sigma[i]);
    p.value = p.observable ? values[i] : nominal[i];
    p.sigma = p.observable ? sigma[i] : std::numeric_limits<double>::quiet_NaN();
    if (!p.observable) p.note = profileNote(i, r, zero);
    if (p.observable && i == 3) p.note = zero.note;
    if (in.truth) {
      const ProfileGeometry& t = in.truth->geometry;
      const double truth[] = {t.m_mm, t.n_mm, t.laser_tilt_rad * kRadToDeg,
                              t.encoder_zero_rad * kRadToDeg};
      p.truth = truth[i];
    }
    c.parameters.push_back(p);
  }
  c.correlation = correlationOf(r.covariance);
  c.rms_before = r.rms_before_mm;
  c.rms_after = r.rms_after_mm;
  c.warnings = r.warnings;
  if (!r.converged) c.warnings.push_back("the least squares did not converge");
  c.sweeps_used = static_cast<int>(in.planes.size());
  c.rejected = in.rejected;
  c.seconds = r.seconds;
  return c;
}

// The format of `calib axis-offset` (geometry.calibration_file applies all four values); no
// date, so the same logs give the same bytes.
void writeProfileFile(const RigCalibRequest& o, const RigCalibration& c) {
  AxisOffsetCalibration f;
  f.m_mm = c.parameters[0].value;
  f.n_mm = c.parameters[1].value;
  f.laser_tilt_deg = c.parameters[2].value;
  f.encoder_zero_deg = c.parameters[3].value;
  f.source["tool"] = "sweepmap calib rig";
  f.source["planes"] = std::to_string(c.sweeps_used);
  for (const CalibParameter& p : c.parameters) {
    const std::string name = p.key.substr(p.key.find('.') + 1);
    f.source["sigma_" + name] = p.observable ? num(p.sigma) : "not observable (nominal kept)";
  }
  f.source["rms_after_mm"] = num(c.rms_after);
  f.source["encoder_zero"] = c.parameters[3].note;
  f.logs = o.logs;
  writeAxisOffsetCalibration(o.out, f);
}

}  // namespace

void writeRigCalibrationOf(const RigCalibRequest& o, const Rig& loaded, const RigCalibration& c) {
  RigCalibrationFile f = rigCalibrationFile(c, "sweepmap calib rig", o.logs);
  f.source["rig"] = loaded.path;
  writeRigCalibration(o.out, f);
}

int calibrateProfileRig(const RigCalibRequest& o, const Rig& loaded) {
  const RotatingProfileConfig& rig = std::get<RotatingProfileConfig>(loaded.config);
  if (!checkPaths(o)) return kExitUsage;
  ProgressOptions po;
  po.enabled = !o.json;
  Progress progress(kCalibRig, po);
  progress.stage("reading the plate poses");
  ProfileInputs in;
  if (!readPlateSweeps(o.logs, {kMinPointsPerSweep, kMaxPointsPerSweep}, kCalibRig,
                       /*say_each=*/false, &in))
    return kExitBadInput;
  if (in.planes.empty()) {
    progress.finish();
    std::cerr << kCalibRig << ": no sweep with " << kMinPointsPerSweep
              << " or more points in the logs: nothing calibrated\n";
    return 1;
  }
  AxisOffsetOptions options;
  options.initial = rig.geometry.toGeometry();
  options.estimate_tilt = true;
  options.estimate_encoder_zero = true;  // reported unobservable when the poses cannot fix it
  const std::vector<size_t> reference =
      useReferenceFace(rig.turntable.reference, in.planes, &options);
  progress.stage("solving");
  AxisOffsetResult r;
  {
    ProgressTicker ticker(progress);
    r = solveAxisOffset(in.planes, options);
  }
  progress.finish();
  const RigCalibration c =
      profileResult(rig, in, r, options.max_sigma_deg, zeroSource(rig, in, reference));
  return reportRigCalibration(o, loaded, in.read_s, c, [&] { writeProfileFile(o, c); });
}

int calibrateMobileLidarRig(const RigCalibRequest& o, const Rig& loaded) {
  if (!checkPaths(o)) return kExitUsage;
  MobileRigCalibRequest request;
  request.logs = o.logs;
  request.rig = loaded.path;
  request.sets = o.sets;
  request.progress = !o.json;
  const auto t0 = Clock::now();
  RigCalibration c;
  try {
    c = runMobileRigCalibration(request);
  } catch (const ConfigError& e) {
    std::cerr << kCalibRig << ": config error: " << e.what() << "\n";
    return kExitUsage;
  } catch (const LogError& e) {  // names the log and the offset
    std::cerr << kCalibRig << ": cannot read log: " << e.what() << "\n";
    return kExitBadInput;
  } catch (const std::exception& e) {  // what the drive held could not be calibrated
    std::cerr << kCalibRig << ": " << o.logs.at(0) << ": " << e.what() << "\n";
    return kExitBadInput;
  }
  c.seconds = seconds(Clock::now() - t0);  // reading, odometry re-runs and the solve
  c.rms_before *= 1e3;                     // m -> mm
  c.rms_after *= 1e3;
  c.residual_unit = "mm";
  const std::string& angles_file =
      std::get<MobileLidarConfig>(loaded.config).mounting.calibration_file;
  if (!angles_file.empty()) {
    c.warnings.push_back("the rig file's mounting.calibration_file (" + angles_file +
                         ") replaces the mounting angles of its calibration_file: clear it to "
                         "use the angles calibrated here");
  }
  return reportRigCalibration(o, loaded, 0.0, c, [&] { writeRigCalibrationOf(o, loaded, c); });
}

int printProfileRigPlan(const std::string& rig_name, const Rig& loaded) {
  const RotatingProfileConfig& rig = std::get<RotatingProfileConfig>(loaded.config);
  const TurntableConfig& t = rig.turntable;
  const TurntableReference& ref = t.reference;
  const double sweep_s = std::fabs(t.sweep_end_deg - t.sweep_start_deg) / t.speed_deg_s;
  const int sweeps = kPlatePoses + 1;
  std::cout
      << "What to record for `sweepmap calib rig --rig " << rig_name << "` (rotating_profile):\n"
      << "  scene:    a flat plate (machined aluminium, 250 mm square or larger) under the "
         "sensor at its working distance, in "
      << kPlatePoses
      << " or more poses, each tilted about 30 deg from level towards a different direction "
         "(60, 180 and 300 deg of azimuth from the reference face's direction, below; never "
         "towards it: "
         "such a pose is taken for the face) and at a different height; one turntable sweep "
         "per pose.\n"
      << "            Why: the plate's points lie on one plane only with the right M, N and "
         "laser-plane tilt (Zhao 2021 section 3); parallel poses let the tilt and M trade off, "
         "so the poses must not be parallel.\n"
      << "  reference: then one sweep over the base's reference face (turntable.reference): "
         "the plate on its "
      << num(ref.normal_tilt_deg)
      << " deg wedge laid against the fence fixed to the turntable's base, so its normal leans "
         "towards azimuth "
      << num(ref.normal_azimuth_deg)
      << " deg from X_r (the rig file states it, and its squareness: +-"
      << num(ref.azimuth_sigma_deg) << " deg).\n"
      << "            Why: the encoder zero is the turntable's angle against X_r, and only "
         "something fixed to the base defines X_r: free plate poses cannot fix it (turning the "
         "whole cloud about the axis leaves every plate a plane). The face's known azimuth "
         "does; without that sweep the zero is reported unobservable and kept (it turns the "
         "map, not its shape)."
      << (ref.declared ? ""
                       : " This rig file declares no reference face (turntable.reference."
                         "declared: false): the zero will not be calibrated.")
      << "\n"
      << "  sweeps:   " << sweeps << " (one per pose, then the reference), " << t.sweep_start_deg
      << " to " << t.sweep_end_deg << " deg at " << t.speed_deg_s << " deg/s\n"
      << "  duration: about " << std::fixed << std::setprecision(0) << sweeps * (sweep_s + 30.0)
      << " s (sweeps and moving the plate between them)\n"
      << "  record:   lcm-logger calib.lcmlog while the rig sweeps each pose\n"
      << "  simulate: sweepmap sim --rig " << rig_name << " "
      << calibrationRecordingSimLine(RigKind::kRotatingProfile) << " --out calib.lcmlog\n"
      << "  then:     sweepmap calib rig --rig " << rig_name
      << " --logs calib.lcmlog --out rig_calibration.yaml\n"
      << "            and set geometry.calibration_file: rig_calibration.yaml in the rig file\n";
  return 0;
}

int printMobileLidarRigPlan(const std::string& rig_name, const Rig& rig) {
  // The drive's shape and pace: the rig file's sim.* values, which its simulate: line uses. The
  // floor it needs: the path with 0.25 m to spare at either end and 0.2 m at either side.
  const SimMobileConfig& drive = std::get<MobileLidarConfig>(rig.config).sim;
  const RigBRecording recording;
  std::cout << "What to record for `sweepmap calib rig --rig " << rig_name << "` (mobile_lidar):\n"
            << "  scene:    a room with plain walls within the lidar's range on every side (the "
               "lab), with "
            << drive.figure8_lobe_spacing_m + 2.0 * drive.figure8_radius_m + 0.5 << " x "
            << 2.0 * drive.figure8_radius_m + 0.4 << " m of free floor for the car.\n"
            << "  path:     a figure-eight: two lobes of " << drive.figure8_radius_m << " m radius "
            << drive.figure8_lobe_spacing_m
            << " m apart, joined by two straights that cross in the middle, at " << drive.speed_m_s
            << " m/s, stopping for " << drive.stop_duration_s << " s after every "
            << recording.stop_interval_s << " s of driving.\n"
            << "            Why: the gyro measures the turn rate whatever the wheels are; the "
               "straights fix the ratio of the two radii, the turns both ways fix each radius "
               "against the track, the stops fix the gyro's bias. The distance driven (the radii's "
               "and the track's common scale) no turn rate shows: the lidar measures it, seeing "
               "the same walls from near and far. The lobes turn the scan plane through every "
               "heading both ways, so the passes over the same walls separate the mounting's "
               "yaw alpha from the wheels; Miao 2022's circle cannot (it turns one way at one "
               "rate: alpha and the wheels trade off).\n"
            << "  duration: " << recording.duration_s
            << " s (about six laps; four left one of the mounting's angles outside 0.3 mrad on "
               "three drives in thirty, six on two)\n"
            << "  record:   sweepmap record --rig " << rig_name << " --out calib.lcmlog (live)\n"
            << "  simulate: sweepmap sim --rig " << rig_name << " "
            << calibrationRecordingSimLine(RigKind::kMobileLidar) << " --out calib.lcmlog\n"
            << "  then:     sweepmap calib rig --rig " << rig_name
            << " --logs calib.lcmlog --out rig_calibration.yaml\n"
            << "            and set calibration_file: rig_calibration.yaml in the rig file\n";
  return 0;
}

std::vector<std::string> rigBRecordingSets(const RigBRecording& recording) {
  return {"sim.path=figure8", "sim.stop_interval_s=" + std::to_string(recording.stop_interval_s),
          "sim.duration_s=" + std::to_string(recording.duration_s)};
}

std::vector<std::string> calibrationRecordingSimArgs(RigKind kind) {
  switch (kind) {
    case RigKind::kRotatingLidar: {
      const RigARecording r;
      return {"--set",    "motor.mode=" + std::to_string(r.mode),
              "--set",    "motor.sweep_angle_deg=" + std::to_string(r.sweep_angle_deg),
              "--sweeps", std::to_string(r.sweeps)};
    }
    case RigKind::kMobileLidar:
      return setArguments(rigBRecordingSets(RigBRecording()));
    case RigKind::kRotatingProfile:
      return {"--set", "sim.scene=plate",
              "--set", "sim.plate_count=" + std::to_string(kPlatePoses),
              "--set", "sim.reference_sweep=true"};
  }
  return {};
}

std::string calibrationRecordingSimLine(RigKind kind) {
  std::string line;
  for (const std::string& a : calibrationRecordingSimArgs(kind))
    line += (line.empty() ? "" : " ") + a;
  return line;
}

}  // namespace sweepmap
