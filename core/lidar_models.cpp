#include "core/lidar_models.hpp"

#include <cmath>
#include <sstream>

#include "core/angles.hpp"

namespace sweepmap {
namespace {

LidarModel scip(const std::string& name, ScipGeometry pp, uint32_t no_return, bool intensity,
                double min_m, double max_m, const std::string& source) {
  LidarModel m;
  m.name = name;
  m.protocol = DeviceProtocol::kScip;
  m.pp = pp;
  m.no_return_code = no_return;
  m.scip_intensity = intensity;
  m.range_min_m = min_m;
  m.range_max_m = max_m;
  m.scan_rate_hz = pp.scan_rpm / 60.0;
  m.scan_rate_min_hz = m.scan_rate_max_hz = m.scan_rate_hz;
  m.source = source;
  return m;
}

LidarModel serial(const std::string& name, DeviceProtocol protocol, int model_code, double min_m,
                  double max_m, double rate_hz, double rate_min_hz, double rate_max_hz,
                  double sample_hz, const std::string& source) {
  LidarModel m;
  m.name = name;
  m.protocol = protocol;
  m.model_code = model_code;
  m.range_min_m = min_m;
  m.range_max_m = max_m;
  m.scan_rate_hz = rate_hz;
  m.scan_rate_min_hz = rate_min_hz;
  m.scan_rate_max_hz = rate_max_hz;
  m.sample_rate_hz = sample_hz;
  m.source = source;
  return m;
}

std::vector<LidarModel> makeCatalogue() {
  // ME/GE (intensities): the UST and UTM families; the URG-04LX's SCIP 2.0 has MD/MS/GD/GS
  // only. Error codes (SCIP2.0 specification C-42-03320B, Tables 3 and 4): UTM-30LX family 1 "no
  // object in the range"; URG-04LX family 0 "detected object is possibly at 22 m", the code a
  // real URG-04LX-UG01 sends most (tests/data/real/scip, 53 of its 85 codes).
  const ScipGeometry ust10{20, 30000, 1440, 0, 1080, 540, 2400};
  const ScipGeometry ust20{20, 60000, 1440, 0, 1080, 540, 2400};
  const ScipGeometry utm30{23, 60000, 1440, 0, 1080, 540, 2400};
  const ScipGeometry urg04{20, 5600, 1024, 44, 725, 384, 600};
  return {
      scip("UST-10LX", ust10, 1, true, 0.06, 10.0,
           "PP of a real UST-10LX (firmware 4.0.2-A) as printed by a public Python driver; "
           "Hokuyo UST-10LX specification: 0.06-10 m, 270 deg, 0.25 deg, 25 ms/scan"),
      scip("UST-20LX", ust20, 1, true, 0.06, 20.0,
           "Hokuyo UST-20LX specification: 0.06-20 m, 270 deg, 0.25 deg, 25 ms/scan; steps as "
           "the UST-10LX; DMAX 60000 not seen in a real PP reply"),
      scip("UTM-30LX", utm30, 1, true, 0.1, 30.0,
           "PP of a real UTM-30LX-EW (its lines with their checksums, in Hokuyo sample code; "
           "the same DMIN/DMAX/steps/period in Hokuyo-aut/urg_node2's tests on the device); "
           "SCIP2.0 specification Table 2: steps 0/540/1080 of 1440; Hokuyo UTM-30LX "
           "specification: 0.1-30 m, 25 ms/scan"),
      scip("URG-04LX", urg04, 0, false, 0.06, 4.095,
           "PP example of the SCIP2.0 specification (C-42-03320B, 8.12) and of Hokuyo's "
           "urgnetwork wiki (a classic URG-04LX, checksums hold); Hokuyo URG-04LX "
           "specification: 0.06-4.095 m, 240 deg, 100 ms/scan"),
      scip("URG-04LX-UG01", urg04, 0, false, 0.02, 5.6,
           "PP of a real URG-04LX-UG01 (firmware 3.4.03, RecklessTedsFunland/rtf_urg); Hokuyo "
           "URG-04LX-UG01 specification: 0.02-5.6 m, 240 deg, 100 ms/scan"),
      serial("YDLIDAR-X4", DeviceProtocol::kYdlidarX4, 6, 0.12, 10.0, 7.0, 6.0, 12.0, 5000.0,
             "YDLIDAR X4 datasheet: 0.12-10 m, 5000 samples/s, 6-12 Hz (7 Hz typical); Miao "
             "2022; model code 6: X4 development manual, device information"),
      serial("RPLIDAR-A1", DeviceProtocol::kRplidar, 1, 0.15, 12.0, 5.5, 1.0, 10.0, 2000.0,
             "Slamtec RPLIDAR A1 datasheet: 0.15-12 m, 5.5 Hz typical (1-10 Hz), 2000 "
             "samples/s in the standard scan"),
      serial("RPLIDAR-A2", DeviceProtocol::kRplidar, 2, 0.15, 16.0, 10.0, 5.0, 15.0, 4000.0,
             "Slamtec RPLIDAR A2 datasheet: 0.15-16 m (A2M16; A2M8 12 m), 10 Hz typical "
             "(5-15 Hz), 4000 samples/s in the standard scan"),
  };
}

std::string num(double v) {
  std::ostringstream s;
  s.precision(9);
  s << v;
  return s.str();
}

void require(bool ok, const std::string& key, const std::string& why) {
  if (!ok) throw LidarFitError(key, why);
}

void checkScipFit(const LidarConfig& l, const LidarModel& m) {
  const ScipGeometry& pp = m.pp;
  const double step_deg = 360.0 / pp.ares;
  require(l.steps_per_revolution == pp.ares, "steps_per_revolution",
          "must be the " + m.name + "'s ARES " + std::to_string(pp.ares));
  const double c = l.angle_increment_deg / step_deg;
  require(std::fabs(c - std::lround(c)) < 1e-6 && std::lround(c) >= 1 && std::lround(c) <= 99,
          "angle_increment_deg",
          "must be 1 to 99 steps of the " + m.name + " (" + num(step_deg) + " deg each)");
  const ScipRequest r = scipRequestFor(l, m);
  require(r.start_step >= pp.amin && r.end_step <= pp.amax, "beam_count",
          "with angle_min_deg " + num(l.angle_min_deg) + " asks for steps " +
              std::to_string(r.start_step) + ".." + std::to_string(r.end_step) + ", outside the " +
              m.name + "'s " + std::to_string(pp.amin) + ".." + std::to_string(pp.amax) + " (" +
              num(pp.angleRad(pp.amin) / kDegToRad) + ".." + num(pp.angleRad(pp.amax) / kDegToRad) +
              " deg)");
  require(l.range_min_m >= pp.dmin_mm * 1e-3 - 1e-9 && l.range_max_m <= pp.dmax_mm * 1e-3 + 1e-9,
          "range_max_m",
          "and range_min_m must lie within the " + m.name + "'s DMIN..DMAX " +
              num(pp.dmin_mm * 1e-3) + ".." + num(pp.dmax_mm * 1e-3) + " m");
}

}  // namespace

double ScipGeometry::stepRad() const { return 2.0 * M_PI / ares; }
double ScipGeometry::angleRad(double step) const { return (step - afrt) * stepRad(); }

const std::vector<LidarModel>& lidarModels() {
  static const std::vector<LidarModel> models = makeCatalogue();
  return models;
}

const LidarModel* findLidarModel(const std::string& name) {
  for (const LidarModel& m : lidarModels()) {
    if (m.name == name) return &m;
  }
  return nullptr;
}

std::string lidarModelNames() {
  std::string out;
  for (const LidarModel& m : lidarModels()) out += (out.empty() ? "" : " | ") + m.name;
  return out;
}

ScipRequest scipRequestFor(const LidarConfig& l, const LidarModel& m) {
  const double step_deg = 360.0 / m.pp.ares;
  ScipRequest r;
  r.cluster = static_cast<int>(std::lround(l.angle_increment_deg / step_deg));
  if (r.cluster < 1) r.cluster = 1;
  // Ray 0 looks at the middle of its cluster: step start + (c - 1) / 2.
  const double start = m.pp.afrt + l.angle_min_deg / step_deg - 0.5 * (r.cluster - 1);
  require(std::fabs(start - std::lround(start)) < 1e-6, "angle_min_deg",
          "must be the middle of a cluster of the " + m.name + "'s steps: " + num(l.angle_min_deg) +
              " deg is step " + num(start + 0.5 * (r.cluster - 1)) + " (step s looks at (s - " +
              std::to_string(m.pp.afrt) + ") * " + num(step_deg) + " deg)");
  r.start_step = static_cast<int>(std::lround(start));
  r.end_step = r.start_step + l.beam_count * r.cluster - 1;
  return r;
}

void checkLidarFitsModel(const LidarConfig& l, const LidarModel& m) {
  if (m.protocol == DeviceProtocol::kScip) {
    checkScipFit(l, m);
  } else {
    require(l.range_min_m >= m.range_min_m - 1e-9 && l.range_max_m <= m.range_max_m + 1e-9,
            "range_max_m",
            "and range_min_m must lie within the " + m.name + "'s " + num(m.range_min_m) + ".." +
                num(m.range_max_m) + " m");
  }
  require(
      l.scan_rate_hz >= m.scan_rate_min_hz * 0.99 && l.scan_rate_hz <= m.scan_rate_max_hz * 1.01,
      "scan_rate_hz",
      "must be within the " + m.name + "'s " + num(m.scan_rate_min_hz) + ".." +
          num(m.scan_rate_max_hz) + " Hz");
}

LidarConfig fullFieldOf(const LidarModel& m) {
  LidarConfig l;
  l.model = m.name;
  l.device = "sim";
  l.scan_rate_hz = m.scan_rate_hz;
  if (m.protocol == DeviceProtocol::kScip) {
    l.beam_count = m.pp.amax - m.pp.amin + 1;
    l.steps_per_revolution = m.pp.ares;
    l.angle_increment_deg = 360.0 / m.pp.ares;
    l.angle_min_deg = m.pp.angleRad(m.pp.amin) / kDegToRad;
    l.range_min_m = m.pp.dmin_mm * 1e-3;
    l.range_max_m = m.pp.dmax_mm * 1e-3;
    return l;
  }
  l.beam_count = static_cast<int>(std::lround(m.sample_rate_hz / m.scan_rate_hz));
  l.steps_per_revolution = l.beam_count;
  l.angle_increment_deg = 360.0 / l.beam_count;
  l.angle_min_deg = -180.0;
  l.range_min_m = m.range_min_m;
  l.range_max_m = m.range_max_m;
  return l;
}

}  // namespace sweepmap
