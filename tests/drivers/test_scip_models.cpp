// The SCIP driver (drivers/lidar_sessions.cpp) against the SCIP emulator
// (tools/emulate/scip_device.hpp) of each catalogue model (core/lidar_models.hpp), over an
// in-memory link on a virtual clock: the field of view a rig file asks for is what the driver
// requests and what its scans hold, at the model's angles; the URG-04LX's steps and error
// codes; a device that is not the rig's model is refused naming both. The serial lidars' sessions
// take their model from the catalogue too (range and rate limits, the identity the device
// reports).
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "core/lidar_models.hpp"
#include "drivers/lidar_sessions.hpp"
#include "drivers/protocols/scip.hpp"
#include "drivers/protocols/ydlidar.hpp"
#include "tools/emulate/scip_device.hpp"
#include "tools/emulate/serial_devices.hpp"

namespace sweepmap {
namespace {

// The emulator behind a ByteStream: what the host writes reaches it at the virtual time; a
// read with nothing to hand waits its timeout on the virtual clock.
class EmulatorLink : public ByteStream {
 public:
  EmulatorLink(EmulatedLidar* device, int64_t* now_us) : device_(device), now_us_(now_us) {}
  size_t read(uint8_t* buffer, size_t capacity, int timeout_ms) override {
    device_->advance(*now_us_, &pending_);
    if (pending_.empty()) {
      *now_us_ += int64_t{timeout_ms} * 1000;
      device_->advance(*now_us_, &pending_);
    }
    const size_t n = std::min(capacity, pending_.size());
    std::copy(pending_.begin(), pending_.begin() + static_cast<std::ptrdiff_t>(n), buffer);
    pending_.erase(0, n);
    sent_ += n;
    return n;
  }
  void write(const void* data, size_t size, int) override {
    const auto* p = static_cast<const uint8_t*>(data);
    written_.append(reinterpret_cast<const char*>(p), size);
    device_->receive(p, size, *now_us_, &pending_);
  }
  int fd() const override { return -1; }
  std::string describe() const override { return "emulator"; }
  const std::string& written() const { return written_; }

 private:
  EmulatedLidar* device_;
  int64_t* now_us_;
  std::string pending_, written_;
  size_t sent_ = 0;
};

// A world seen by a lidar of `model`: every 1/rate s a scan over the model's whole field,
// ray i (step AMIN + i) at range 1 m + i mm, but every 7th ray without a return.
ScanSource fullFieldSource(const LidarModel& m) {
  auto next = std::make_shared<int64_t>(0);
  return [m, next](int64_t now_us) {
    const auto period_us = static_cast<int64_t>(std::llround(1e6 / m.scan_rate_hz));
    std::vector<Scan2D> out;
    while ((*next + 1) * period_us <= now_us) {
      Scan2D s;
      s.utime = *next * period_us;
      s.time_increment_ns = static_cast<int64_t>(std::llround(m.pp.stepPeriodS() * 1e9));
      s.angle_min_rad = m.pp.angleRad(m.pp.amin);
      s.angle_increment_rad = m.pp.stepRad();
      for (int i = 0; i <= m.pp.amax - m.pp.amin; ++i) {
        s.ranges_m.push_back(i % 7 == 3 ? 0.0f : 1.0f + 0.001f * float(i));
      }
      ++*next;
      out.push_back(s);
    }
    return out;
  };
}

struct DriveResult {
  std::vector<Scan2D> scans;
  std::vector<std::string> errors;
  std::string written;  // what the driver sent
};

// Starts the driver for `rig` against an emulated `device_model`, then reads `seconds`.
DriveResult drive(const LidarConfig& rig, const std::string& device_model, double seconds) {
  const LidarModel& m = *findLidarModel(device_model);
  ScipDevice device(fullFieldSource(m), EmulatedClock{}, 0, device_model);
  int64_t now_us = 0;
  EmulatorLink link(&device, &now_us);
  SessionOptions options;
  options.time = ScanTime::kStream;
  auto session = makeLidarSession(DeviceProtocol::kScip, rig, options);
  session->start(link, [&] { return now_us; });
  DriveResult run;
  session->onBytes(nullptr, 0, -1, &run.scans, &run.errors);
  const int64_t end = now_us + static_cast<int64_t>(seconds * 1e6);
  uint8_t buffer[8192];
  while (now_us < end) {
    const size_t n = link.read(buffer, sizeof buffer, 5);
    session->onBytes(buffer, n, -1, &run.scans, &run.errors);
  }
  run.written = link.written();
  return run;
}

TEST(ScipModels, CatalogueHoldsEveryModelOfIssue22) {
  for (const char* name : {"UST-10LX", "UST-20LX", "UTM-30LX", "URG-04LX", "URG-04LX-UG01",
                           "YDLIDAR-X4", "RPLIDAR-A1", "RPLIDAR-A2"}) {
    const LidarModel* m = findLidarModel(name);
    ASSERT_NE(m, nullptr) << name;
    EXPECT_FALSE(m->source.empty()) << name;
    EXPECT_GT(m->range_max_m, m->range_min_m) << name;
    EXPECT_GT(m->scan_rate_hz, 0.0) << name;
    // A model's whole field fits the model.
    EXPECT_NO_THROW(checkLidarFitsModel(fullFieldOf(*m), *m)) << name;
  }
  EXPECT_EQ(findLidarModel("UST-10"), nullptr);
  // The UST-10LX's steps 0..1080: -135..+135 deg.
  const LidarConfig ust = fullFieldOf(*findLidarModel("UST-10LX"));
  EXPECT_EQ(ust.beam_count, 1081);
  EXPECT_DOUBLE_EQ(ust.angle_min_deg, -135.0);
}

TEST(ScipModels, ARigsFieldOfViewMustBeStepsOfItsModel) {
  const LidarModel& ust = *findLidarModel("UST-10LX");
  LidarConfig l = fullFieldOf(ust);
  l.beam_count = 721;
  l.angle_min_deg = -90.0;  // steps 180..900
  const ScipRequest r = scipRequestFor(l, ust);
  EXPECT_EQ(r.start_step, 180);
  EXPECT_EQ(r.end_step, 900);
  EXPECT_EQ(r.cluster, 1);
  const auto key = [&](const LidarConfig& c) {
    try {
      checkLidarFitsModel(c, ust);
    } catch (const LidarFitError& e) {
      return e.key;
    }
    return std::string();
  };
  EXPECT_EQ(key(l), "");
  LidarConfig off = l;
  off.angle_min_deg = -90.1;  // between two steps
  EXPECT_EQ(key(off), "angle_min_deg");
  off = l;
  off.beam_count = 1000;  // past step 1080
  EXPECT_EQ(key(off), "beam_count");
  off = l;
  off.range_max_m = 31.0;  // beyond DMAX
  EXPECT_EQ(key(off), "range_max_m");
  // A cluster of 2: ray 0 at the middle of steps 180 and 181.
  LidarConfig two = l;
  two.angle_increment_deg = 0.5;
  two.angle_min_deg = -90.0 + 0.125;
  two.beam_count = 360;
  EXPECT_EQ(key(two), "");
  EXPECT_EQ(scipRequestFor(two, ust).start_step, 180);
  EXPECT_EQ(scipRequestFor(two, ust).end_step, 899);
  EXPECT_EQ(scipRequestFor(two, ust).cluster, 2);
}

// A rig that crops the UST-10LX to -90..+90 deg: the driver asks for steps 180..900 only, and
// its scans hold those rays at their own angles, with the world's ranges.
TEST(ScipModels, DriverRequestsAndDecodesASubRange) {
  LidarConfig rig = fullFieldOf(*findLidarModel("UST-10LX"));
  rig.beam_count = 721;
  rig.angle_min_deg = -90.0;
  rig.range_min_m = 0.06;
  rig.range_max_m = 10.0;
  const DriveResult run = drive(rig, "UST-10LX", 0.2);
  EXPECT_NE(run.written.find("ME0180090001000\n"), std::string::npos) << run.written;
  EXPECT_TRUE(run.errors.empty()) << run.errors.front();
  ASSERT_GE(run.scans.size(), 5u);
  for (const Scan2D& s : run.scans) {
    ASSERT_EQ(s.ranges_m.size(), 721u);
    EXPECT_NEAR(s.angle_min_rad, -0.5 * M_PI, 1e-12);
    EXPECT_NEAR(s.rayAngle(720), 0.5 * M_PI, 1e-9);
    // Ray i is step 180 + i: the source's ray 180 + i.
    for (size_t i : {size_t(0), size_t(1), size_t(360), size_t(720)}) {
      const size_t src = 180 + i;
      const float want = src % 7 == 3 ? 0.0f : 1.0f + 0.001f * float(src);
      EXPECT_NEAR(s.ranges_m[i], want, 1e-4) << i;
    }
  }
  // The scan's stamp is its step 0; ray 0 (step 180) came 180 steps of 25 ms / 1440 later:
  // 3125 us (device times: the stamp in ms, unwrapped).
  for (const Scan2D& s : run.scans) EXPECT_EQ(s.utime - s.device_stamp * 1000, 3125);
  EXPECT_NEAR(double(run.scans[2].utime - run.scans[1].utime), 25000.0, 1000.0);
}

// A rig at a cluster of 4: the device sends the nearest range of each 4 steps; each ray sits
// at its cluster's middle.
TEST(ScipModels, DriverRequestsClusters) {
  LidarConfig rig = fullFieldOf(*findLidarModel("UST-10LX"));
  rig.angle_increment_deg = 1.0;
  rig.angle_min_deg = -135.0 + 0.375;  // middle of steps 0..3
  rig.beam_count = 270;                // steps 0..1079
  rig.range_min_m = 0.06;
  rig.range_max_m = 10.0;
  const DriveResult run = drive(rig, "UST-10LX", 0.1);
  EXPECT_NE(run.written.find("ME0000107904000\n"), std::string::npos) << run.written;
  ASSERT_GE(run.scans.size(), 2u);
  const Scan2D& s = run.scans.back();
  ASSERT_EQ(s.ranges_m.size(), 270u);
  EXPECT_NEAR(s.rayAngle(0), (1.5 - 540.0) * 2.0 * M_PI / 1440.0, 1e-12);
  EXPECT_NEAR(s.angle_increment_rad, 4.0 * 2.0 * M_PI / 1440.0, 1e-12);
  // Cluster 0 holds steps 0..3: step 3 has no return, the nearest valid is step 0's 1.000 m.
  EXPECT_NEAR(s.ranges_m[0], 1.000f, 1e-4);
  EXPECT_NEAR(s.ranges_m[1], 1.004f, 1e-4);  // steps 4..7
}

// The URG-04LX-UG01: its steps 44..725 at its own angles, its error code 0 for no return
// never a range.
TEST(ScipModels, DriverOnAnEmulatedUrg04lx) {
  LidarConfig rig = fullFieldOf(*findLidarModel("URG-04LX-UG01"));
  const DriveResult run = drive(rig, "URG-04LX-UG01", 0.5);
  EXPECT_NE(run.written.find("ME0044072501000\n"), std::string::npos);
  EXPECT_NE(run.written.find("MD0044072501000\n"), std::string::npos);  // no ME: 0E
  EXPECT_TRUE(run.errors.empty()) << run.errors.front();
  ASSERT_GE(run.scans.size(), 3u);
  const Scan2D& s = run.scans.back();
  ASSERT_EQ(s.ranges_m.size(), 682u);
  EXPECT_NEAR(s.rayAngle(0), (44.0 - 384.0) * 2.0 * M_PI / 1024.0, 1e-12);
  EXPECT_NEAR(s.rayAngle(681), (725.0 - 384.0) * 2.0 * M_PI / 1024.0, 1e-9);
  EXPECT_EQ(s.ranges_m[3], 0.0f);  // no return: the device sent error code 0
  EXPECT_NEAR(s.ranges_m[4], 1.004f, 1e-4);
  EXPECT_NEAR(double(run.scans[2].utime - run.scans[1].utime), 100000.0, 1000.0);
}

// A URG-04LX attached where the rig file says UST-10LX: refused, naming both.
TEST(ScipModels, ADeviceThatIsNotTheRigsModelIsRefused) {
  const LidarConfig rig = fullFieldOf(*findLidarModel("UST-10LX"));
  try {
    drive(rig, "URG-04LX-UG01", 0.1);
    FAIL() << "no identity mismatch";
  } catch (const IdentityMismatch& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("UST-10LX"), std::string::npos) << what;
    EXPECT_NE(what.find("URG-04LX-UG01"), std::string::npos) << what;
  }
  // Same name, other steps (a UTM-30LX where a UST-20LX is expected): MODL differs first.
  const LidarConfig utm = fullFieldOf(*findLidarModel("UTM-30LX"));
  EXPECT_THROW(drive(utm, "UST-20LX", 0.1), IdentityMismatch);
}

// ---- Serial lidars -------------------------------------------------------------------------

// A 360° lidar's turns at `rate_hz` with `samples` rays each, all at 1 m.
ScanSource turnSource(double rate_hz, int samples) {
  auto next = std::make_shared<int64_t>(0);
  return [=](int64_t now_us) {
    std::vector<Scan2D> out;
    for (;; ++*next) {
      const auto start = static_cast<int64_t>(std::llround(double(*next) / rate_hz * 1e6));
      if (start > now_us) break;
      Scan2D s;
      s.utime = start;
      s.angle_min_rad = -M_PI;
      s.angle_increment_rad = 2.0 * M_PI / samples;
      s.time_increment_ns = static_cast<int64_t>(std::llround(1e9 / rate_hz / samples));
      s.ranges_m.assign(static_cast<size_t>(samples), 1.0f);
      out.push_back(std::move(s));
    }
    return out;
  };
}

// Starts `protocol`'s session for `rig` against `device`, then reads `seconds`: its scans.
std::vector<Scan2D> driveSerial(EmulatedLidar* device, DeviceProtocol protocol,
                                const LidarConfig& rig, double seconds) {
  int64_t now_us = 0;
  EmulatorLink link(device, &now_us);
  auto session = makeLidarSession(protocol, rig, SessionOptions{ScanTime::kStream, 0});
  session->start(link, [&] { return now_us; });
  std::vector<Scan2D> scans;
  std::vector<std::string> errors;
  const int64_t end = now_us + static_cast<int64_t>(seconds * 1e6);
  uint8_t buffer[4096];
  while (now_us < end) {
    const size_t n = link.read(buffer, sizeof buffer, 5);
    session->onBytes(buffer, n, -1, &scans, &errors);
  }
  return scans;
}

// The X4 and RPLIDAR sessions take the rig's lidar.model from the catalogue: a model of another
// protocol, range limits beyond the model's (the X4's 0.12-10 m, the A1's 0.15-12 m, the A2's
// 0.15-16 m) or a rate outside its motor's are refused when the session is made.
TEST(SerialModels, SessionsTakeTheirLimitsFromTheCatalogue) {
  const SessionOptions o{ScanTime::kStream, 0};
  const LidarConfig x4 = fullFieldOf(*findLidarModel("YDLIDAR-X4"));
  EXPECT_NO_THROW(makeLidarSession(DeviceProtocol::kYdlidarX4, x4, o));
  EXPECT_THROW(makeLidarSession(DeviceProtocol::kRplidar, x4, o), std::invalid_argument);
  EXPECT_THROW(makeLidarSession(DeviceProtocol::kYdlidarX4, LidarConfig{}, o),
               std::invalid_argument);  // the default UST-10LX
  LidarConfig far = x4;
  far.range_max_m = 12.0;
  try {
    makeLidarSession(DeviceProtocol::kYdlidarX4, far, o);
    FAIL() << "an X4 asked for 12 m";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("YDLIDAR-X4's 0.12..10 m"), std::string::npos) << e.what();
  }
  LidarConfig near = x4;
  near.range_min_m = 0.1;
  EXPECT_THROW(makeLidarSession(DeviceProtocol::kYdlidarX4, near, o), std::invalid_argument);
  LidarConfig fast = x4;
  fast.scan_rate_hz = 13.0;  // the X4's motor: 6-12 Hz
  EXPECT_THROW(makeLidarSession(DeviceProtocol::kYdlidarX4, fast, o), std::invalid_argument);
  LidarConfig a1 = fullFieldOf(*findLidarModel("RPLIDAR-A1"));
  a1.range_max_m = 16.0;
  EXPECT_THROW(makeLidarSession(DeviceProtocol::kRplidar, a1, o), std::invalid_argument);
  LidarConfig a2 = fullFieldOf(*findLidarModel("RPLIDAR-A2"));
  EXPECT_DOUBLE_EQ(a2.range_max_m, 16.0);
  EXPECT_NO_THROW(makeLidarSession(DeviceProtocol::kRplidar, a2, o));
}

// The catalogue's identities are what the protocol documents say the devices report.
TEST(SerialModels, CatalogueIdentitiesAreTheProtocols) {
  EXPECT_EQ(findLidarModel("YDLIDAR-X4")->model_code, ydlidar::kModelX4);
  EXPECT_EQ(findLidarModel("RPLIDAR-A1")->model_code, 0x18 >> 4);  // A1M8 reports 0x18
  EXPECT_EQ(findLidarModel("RPLIDAR-A2")->model_code, 2);
}

// The emulated A1 (model 0x18) streams for a rig file that says RPLIDAR-A1 and is refused,
// naming both, for one that says RPLIDAR-A2; the emulated X4 streams for YDLIDAR-X4.
TEST(SerialModels, ADeviceThatIsNotTheRigsModelIsRefused) {
  LidarConfig a1 = fullFieldOf(*findLidarModel("RPLIDAR-A1"));
  a1.scan_rate_hz = 5.5;
  RplidarDevice device(turnSource(5.5, 360));
  EXPECT_GE(driveSerial(&device, DeviceProtocol::kRplidar, a1, 1.0).size(), 3u);
  const LidarConfig a2 = fullFieldOf(*findLidarModel("RPLIDAR-A2"));
  RplidarDevice other(turnSource(5.5, 360));
  try {
    driveSerial(&other, DeviceProtocol::kRplidar, a2, 0.1);
    FAIL() << "no identity mismatch";
  } catch (const IdentityMismatch& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("RPLIDAR-A2"), std::string::npos) << what;
    EXPECT_NE(what.find("model 24, family 1"), std::string::npos) << what;
  }
  X4Device x4(turnSource(7.0, 714));
  EXPECT_GE(
      driveSerial(&x4, DeviceProtocol::kYdlidarX4, fullFieldOf(*findLidarModel("YDLIDAR-X4")), 1.0)
          .size(),
      3u);
}

// A Hokuyo on a serial or USB port (the URG-04LX's): scip:///dev/PORT, 19200 baud unless given.
TEST(ScipModels, SerialScipUri) {
  const DeviceUri u = parseDeviceUri("scip:///dev/ttyACM0");
  EXPECT_EQ(u.protocol, DeviceProtocol::kScip);
  EXPECT_EQ(u.path, "/dev/ttyACM0");
  EXPECT_EQ(u.baud, 19200);
  EXPECT_TRUE(u.host.empty());
  EXPECT_EQ(parseDeviceUri("scip:///dev/ttyUSB0?baud=115200").baud, 115200);
  EXPECT_THROW(parseDeviceUri("scip:///dev/ttyACM0?speed=1"), std::invalid_argument);
  EXPECT_EQ(parseDeviceUri("scip://192.168.0.10").path, "");
}

}  // namespace
}  // namespace sweepmap
