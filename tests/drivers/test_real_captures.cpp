// The corpus of bytes captured from real devices by others (tests/data/real/, provenance and
// expected values in its README.md), decoded with our protocol decoders. The expected values
// come from the sources themselves or from an independent reading of the vendor documents,
// never from our decoder's output. A test named DISABLED_ documents where our decoder still
// disagrees with the device: its comment says what the device shows and what we do instead.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/angles.hpp"
#include "core/lidar_models.hpp"
#include "drivers/lidar_sessions.hpp"
#include "drivers/protocols/hi219.hpp"
#include "drivers/protocols/scip.hpp"
#include "drivers/protocols/ydlidar.hpp"

namespace sweepmap {
namespace {

std::string corpusPath(const std::string& name) {
  return std::string(SWEEPMAP_SOURCE_DIR) + "/tests/data/real/" + name;
}

// A file's bytes as they are; nullopt if it cannot be read.
std::optional<std::string> readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// A .bin capture: its bytes as they are.
std::string readBinary(const std::string& name) {
  auto bytes = readFile(corpusPath(name));
  if (!bytes) throw std::runtime_error("cannot read " + corpusPath(name));
  return *bytes;
}

// A .hex capture: bytes as two-digit hex tokens separated by white space; '#' starts a
// comment that runs to the end of the line.
std::string readHex(const std::string& name) {
  std::ifstream in(corpusPath(name));
  if (!in) throw std::runtime_error("cannot read " + corpusPath(name));
  std::string bytes, line;
  for (int line_no = 1; std::getline(in, line); ++line_no) {
    std::istringstream tokens(line.substr(0, line.find('#')));
    std::string token;
    while (tokens >> token) {
      if (token.size() != 2 || !std::isxdigit(static_cast<unsigned char>(token[0])) ||
          !std::isxdigit(static_cast<unsigned char>(token[1]))) {
        throw std::runtime_error(corpusPath(name) + ":" + std::to_string(line_no) + ": '" + token +
                                 "' is not a hex byte");
      }
      bytes.push_back(static_cast<char>(std::stoi(token, nullptr, 16)));
    }
  }
  return bytes;
}

// Every event of `bytes` fed to a fresh decoder, whole or one byte at a time.
template <class Decoder, class Event>
std::vector<Event> decodeAll(const std::string& bytes, bool byte_by_byte = false) {
  Decoder decoder;
  std::vector<Event> out;
  const auto* p = reinterpret_cast<const uint8_t*>(bytes.data());
  if (!byte_by_byte) {
    decoder.feed(p, bytes.size(), &out);
    return out;
  }
  for (size_t i = 0; i < bytes.size(); ++i) decoder.feed(p + i, 1, &out);
  return out;
}

template <class T, class Event>
std::vector<T> only(const std::vector<Event>& events) {
  std::vector<T> out;
  for (const auto& e : events) {
    if (const auto* x = std::get_if<T>(&e)) out.push_back(*x);
  }
  return out;
}

// --- Hokuyo SCIP 2.0 ------------------------------------------------------------------------

// scip/urg04lx_ug01_gd0044072501.bin: a URG-04LX-UG01 (firmware 3.4.03, serial H1620274)
// answering GD0044072501, captured by RecklessTedsFunland/rtf_urg (src/urg.hpp).
const char* const kUrgGd = "scip/urg04lx_ug01_gd0044072501.bin";

TEST(RealCapturesScip, Urg04lxGdReplyDecodesToItsSteps) {
  const std::string bytes = readBinary(kUrgGd);
  ASSERT_EQ(bytes.size(), 2134u);  // the source: "Total bytes in message: 2134"
  for (bool byte_by_byte : {false, true}) {
    const auto events = decodeAll<scip::Decoder, scip::Event>(bytes, byte_by_byte);
    EXPECT_TRUE(only<DecodeError>(events).empty());
    const auto scans = only<scip::ScanData>(events);
    ASSERT_EQ(scans.size(), 1u);
    const auto& s = scans[0];
    EXPECT_EQ(s.command, "GD");
    EXPECT_EQ(s.start_step, 44);
    EXPECT_EQ(s.end_step, 725);
    EXPECT_EQ(s.cluster, 1);
    EXPECT_EQ(s.time_ms, 11149560u);      // "ZR3h": 42<<18 | 34<<12 | 3<<6 | 56
    ASSERT_EQ(s.ranges_mm.size(), 682u);  // the source: "number points: 682"
    EXPECT_TRUE(s.intensities.empty());
    // Values read by hand from the data blocks ("006" "006" "006" "11N" ...).
    EXPECT_EQ(s.ranges_mm[0], 6u);
    EXPECT_EQ(s.ranges_mm[3], 4190u);
    EXPECT_EQ(s.ranges_mm[340], 293u);  // step 384, the front
    EXPECT_EQ(s.ranges_mm[640], 5461u);
    const auto codes =
        std::count_if(s.ranges_mm.begin(), s.ranges_mm.end(), [](uint32_t r) { return r < 20; });
    EXPECT_EQ(codes, 85);  // URG-04LX error codes (< DMIN 20): 53 x 0, 24 x 6, 8 x 7
    EXPECT_EQ(*std::max_element(s.ranges_mm.begin(), s.ranges_mm.end()), 5461u);
  }
}

TEST(RealCapturesScip, Urg04lxGdReplyAtTheModelsAngles) {
  // The device's PP, as the same source printed it.
  const scip::Params pp = scip::parseParams({{"MODL", "URG-04LX-UG01(Simple-URG)"},
                                             {"DMIN", "20"},
                                             {"DMAX", "5600"},
                                             {"ARES", "1024"},
                                             {"AMIN", "44"},
                                             {"AMAX", "725"},
                                             {"AFRT", "384"},
                                             {"SCAN", "600"}});
  const auto scans =
      only<scip::ScanData>(decodeAll<scip::Decoder, scip::Event>(readBinary(kUrgGd)));
  ASSERT_EQ(scans.size(), 1u);
  const Scan2D scan = scip::toScan2D(scans[0], pp);
  // hokuyoaist's report of a URG-04LX-UG01 (gbiggs/hokuyoaist#1): "Resolution: 0.00613592
  // radians/step, Minimum angle: -2.08621 radians, Maximum angle: 2.09235 radians".
  EXPECT_NEAR(scan.angle_min_rad, -2.08621, 1e-5);
  EXPECT_NEAR(scan.angle_increment_rad, 0.00613592, 1e-8);
  EXPECT_NEAR(scan.rayAngle(681), 2.09235, 1e-5);
  EXPECT_NEAR(scan.rayAngle(340), 0.0, 1e-12);
  ASSERT_EQ(scan.ranges_m.size(), 682u);
  EXPECT_EQ(scan.ranges_m[0], 0.0f);  // error code 6: no return
  EXPECT_FLOAT_EQ(scan.ranges_m[3], 4.190f);
  EXPECT_EQ(
      std::count_if(scan.ranges_m.begin(), scan.ranges_m.end(), [](float r) { return r > 0.0f; }),
      597);
  EXPECT_EQ(scan.device_stamp, 11149560);
}

// Raw bytes through the driver's own session, as `sweepmap decode scip FILE --lidar-model M`
// decodes them (tools/devices/capture.cpp: the model's whole field of view, device times).
std::vector<Scan2D> decodeAsModel(const std::string& bytes, const std::string& model,
                                  std::vector<std::string>* errors) {
  const LidarModel* m = findLidarModel(model);
  if (m == nullptr) throw std::runtime_error("no model " + model);
  SessionOptions options;
  options.time = ScanTime::kStream;
  auto session = makeLidarSession(DeviceProtocol::kScip, fullFieldOf(*m), options);
  std::vector<Scan2D> scans;
  session->onBytes(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size(), -1, &scans,
                   errors);
  return scans;
}

// Issue 22: "A URG-04LX GD/MD reply of steps 44-725, decoded with --lidar-model URG-04LX-UG01,
// gives one scan of 682 rays at the model's angles, with the error codes invalid."
TEST(RealCapturesScip, Urg04lxGdReplyDecodedAsItsModel) {
  std::vector<std::string> errors;
  const auto scans = decodeAsModel(readBinary(kUrgGd), "URG-04LX-UG01", &errors);
  EXPECT_TRUE(errors.empty()) << errors.front();
  ASSERT_EQ(scans.size(), 1u);
  const Scan2D& scan = scans[0];
  ASSERT_EQ(scan.ranges_m.size(), 682u);
  // The model's angles by the SCIP2.0 specification: step s at (s - AFRT) * 360 / ARES deg,
  // AFRT 384, ARES 1024 (the device's PP); ray i is step 44 + i.
  for (size_t i : {size_t(0), size_t(1), size_t(340), size_t(681)}) {
    EXPECT_NEAR(scan.rayAngle(i), (44.0 + double(i) - 384.0) * 2.0 * M_PI / 1024.0, 1e-9) << i;
  }
  EXPECT_NEAR(scan.rayAngle(0) / kDegToRad, -119.53125, 1e-4);  // 0.01 deg and better
  // Values below DMIN 20 are the URG-04LX's error codes (Table 3), never ranges: 85 of them.
  EXPECT_EQ(scan.ranges_m[0], 0.0f);  // code 6
  EXPECT_FLOAT_EQ(scan.ranges_m[3], 4.190f);
  EXPECT_FLOAT_EQ(scan.ranges_m[340], 0.293f);
  EXPECT_EQ(
      std::count_if(scan.ranges_m.begin(), scan.ranges_m.end(), [](float r) { return r > 0.0f; }),
      682 - 85);
  // The stamp is the scan's step 0; ray 0 (step 44) was measured 44 steps of
  // 100 ms / 1024 later: 11149560 ms + 4296.875 us.
  EXPECT_EQ(scan.utime, 11149560LL * 1000 + 4297);
}

// A UST-10LX GD reply for steps 0-10, hand-encoded by the SCIP2.0 specification (3-character
// values, 64-character blocks, each line with its checksum: the low 6 bits of the sum + 0x30).
// Values: 1234 ("CB"'s worked value, here in 3 characters "0CB"), 5432 ("1Dh", the
// specification's example), 1 (error code "no object in the range"), 65533 (beyond DMAX: what
// real USTs send with no echo), 20 (DMIN), 30000 (DMAX), 1000..1004; stamp 0x123456 ("4SAF").
const std::string kUstGd0To10 = "GD0000001000\n00P\n4SAF>\n0CB1Dh001?om00D7D`0?X0?Y0?Z0?[0?\\Z\n\n";

// Issue 22: "A UST-10LX GD reply for steps 0-10 gives one scan of 11 rays starting at the
// model's first angle."
TEST(SpecBytesScip, Ust10lxGdOfSteps0To10) {
  std::vector<std::string> errors;
  const auto scans = decodeAsModel(kUstGd0To10, "UST-10LX", &errors);
  EXPECT_TRUE(errors.empty()) << errors.front();
  ASSERT_EQ(scans.size(), 1u);
  const Scan2D& scan = scans[0];
  ASSERT_EQ(scan.ranges_m.size(), 11u);
  // Step 0 of a UST-10LX (PP: AMIN 0, AFRT 540, ARES 1440): (0 - 540) * 360 / 1440 = -135 deg.
  EXPECT_NEAR(scan.rayAngle(0), -0.75 * M_PI, 1e-12);
  EXPECT_NEAR(scan.rayAngle(10), (10.0 - 540.0) * 2.0 * M_PI / 1440.0, 1e-12);
  const std::vector<float> want = {1.234f, 5.432f, 0.0f,   0.0f,   0.020f, 30.0f,
                                   1.000f, 1.001f, 1.002f, 1.003f, 1.004f};
  for (size_t i = 0; i < want.size(); ++i) EXPECT_FLOAT_EQ(scan.ranges_m[i], want[i]) << i;
  EXPECT_EQ(scan.device_stamp, 0x123456);
  EXPECT_EQ(scan.utime, 0x123456LL * 1000);  // step 0 is ray 0
}

// The same steps decoded at a cluster of 2 (GD0000001002: 6 values, the last cluster one
// step): each ray at its cluster's middle step.
TEST(SpecBytesScip, ClusterRaysAtTheirMiddleStep) {
  scip::ScanData d;
  d.command = "GD";
  d.start_step = 0;
  d.end_step = 10;
  d.cluster = 2;
  d.ranges_mm = {1000, 1000, 1000, 1000, 1000, 1000};
  const scip::Params pp = scip::parseParams({{"DMIN", "20"},
                                             {"DMAX", "30000"},
                                             {"ARES", "1440"},
                                             {"AMIN", "0"},
                                             {"AMAX", "1080"},
                                             {"AFRT", "540"},
                                             {"SCAN", "2400"}});
  const Scan2D scan = scip::toScan2D(d, pp);
  const double step = 2.0 * M_PI / 1440.0;
  ASSERT_EQ(scan.ranges_m.size(), 6u);
  for (size_t i = 0; i < 5; ++i) {
    EXPECT_NEAR(scan.rayAngle(i), (2.0 * double(i) + 0.5 - 540.0) * step, 1e-6) << i;
  }
  EXPECT_NEAR(scan.rayAngle(5), (10.0 - 540.0) * step, 1e-6);  // step 10 alone
}

// --- Figures a real UTM-30LX-EW gave (no bytes published) -----------------------------------
//
// Hokuyo's ROS 2 driver Hokuyo-aut/urg_node2 (Apache-2.0), test/urg_node2_test.cpp at commit
// 815a1107c6e06cff3974998af9a471c30f701909: tests named UTM_30_LX_EW that run the driver
// against the sensor at 192.168.0.10 (the repository holds no emulator). The driver takes
// range_min/max, the angles and the scan period from the device's PP, and the number of rays
// from the values the device sent (urg_library's urg_get_distance returns the count decoded).

TEST(RealDeviceFiguresScip, Utm30lxEwParametersAsUrgNode2Reads) {
  const LidarModel& m = *findLidarModel("UTM-30LX");
  const double step = 2.0 * M_PI / 1440.0;
  // "range_min 0.023", "range_max 60.0": PP DMIN 23, DMAX 60000.
  EXPECT_EQ(m.pp.dmin_mm, 23);
  EXPECT_EQ(m.pp.dmax_mm, 60000);
  // "angle_min (2 pi * -540) / 1440", "angle_max (2 pi * 540) / 1440", "angle_increment
  // 2 pi / 1440", 1081 ranges: ARES 1440, AMIN 0, AMAX 1080, AFRT 540.
  EXPECT_EQ(m.pp.ares, 1440);
  EXPECT_NEAR(m.pp.angleRad(m.pp.amin), -540 * step, 1e-12);
  EXPECT_NEAR(m.pp.angleRad(m.pp.amax), 540 * step, 1e-12);
  EXPECT_EQ(m.pp.amax - m.pp.amin + 1, 1081);
  // "scan_time 0.025", "time_increment (270 / 360) * 0.025 / 1080": SCAN 2400 rpm.
  EXPECT_NEAR(60.0 / m.pp.scan_rpm, 0.025, 1e-12);
  EXPECT_NEAR(m.pp.stepPeriodS(), (270.0 / 360.0) * 0.025 / 1080.0, 1e-12);
  EXPECT_TRUE(m.scip_intensity);  // its intensity tests get intensities (ME)
}

// A GD reply with `values` (3 characters each) as the SCIP2.0 specification lays it out:
// echo, status 00, the time stamp, 64-character blocks, each line with its checksum, LF LF.
std::string gdReplyOf(const std::string& echo, uint32_t stamp_ms,
                      const std::vector<uint32_t>& values) {
  std::string data;
  for (uint32_t v : values) data += scip::encodeValue(v, 3);
  std::string reply = echo + "\n" + scip::withChecksum("00") + "\n" +
                      scip::withChecksum(scip::encodeValue(stamp_ms, 4)) + "\n";
  for (size_t i = 0; i < data.size(); i += 64) {
    reply += scip::withChecksum(data.substr(i, 64)) + "\n";
  }
  return reply + "\n";
}

// urg_node2's intensity test asks the UTM-30LX-EW for steps 180..900 in clusters of 2 (721
// steps) and gets 361 rays; its multi-echo test asks for steps 0..1080 in clusters of 99 and
// gets 11: the device sends ceil(steps / cluster) values, the last cluster cut short by the
// end step (here step 900 alone; steps 990..1080). Our decoder expects the same counts and
// takes no other.
TEST(RealDeviceFiguresScip, Utm30lxEwClusterCountsAsTheDeviceSendsThem) {
  struct Case {
    const char* echo;
    size_t values;
  };
  for (const Case& c : {Case{"GD0180090002", 361}, Case{"GD0000108099", 11}}) {
    const std::vector<uint32_t> ok(c.values, 1500);
    const auto events = decodeAll<scip::Decoder, scip::Event>(gdReplyOf(c.echo, 1000, ok));
    EXPECT_TRUE(only<DecodeError>(events).empty()) << c.echo;
    const auto scans = only<scip::ScanData>(events);
    ASSERT_EQ(scans.size(), 1u) << c.echo;
    EXPECT_EQ(scans[0].ranges_mm.size(), c.values) << c.echo;
    // One value short: not this reply.
    const std::vector<uint32_t> short_by_one(c.values - 1, 1500);
    const auto bad = decodeAll<scip::Decoder, scip::Event>(gdReplyOf(c.echo, 1000, short_by_one));
    EXPECT_TRUE(only<scip::ScanData>(bad).empty()) << c.echo;
    EXPECT_FALSE(only<DecodeError>(bad).empty()) << c.echo;
  }
  // The 361 rays at the PP's angles: ray 360 is step 900 alone, where urg_node2's
  // angle_max "(2 pi * 360) / 1440" puts it too (ray 0 is at its cluster's middle, 180.5;
  // urg_node2 gives the cluster's first step, 180: lidar_models.hpp).
  const scip::Params pp = scip::parseParams({{"DMIN", "23"},
                                             {"DMAX", "60000"},
                                             {"ARES", "1440"},
                                             {"AMIN", "0"},
                                             {"AMAX", "1080"},
                                             {"AFRT", "540"},
                                             {"SCAN", "2400"}});
  const auto scans = only<scip::ScanData>(decodeAll<scip::Decoder, scip::Event>(
      gdReplyOf("GD0180090002", 1000, std::vector<uint32_t>(361, 1500))));
  ASSERT_EQ(scans.size(), 1u);
  const Scan2D scan = scip::toScan2D(scans[0], pp);
  const double step = 2.0 * M_PI / 1440.0;
  EXPECT_NEAR(scan.rayAngle(360), 360 * step, 1e-6);  // angles are floats
  EXPECT_NEAR(scan.rayAngle(0), -359.5 * step, 1e-6);
}

// scip/urg04lx_pp_urgnetwork.txt and urg04lx_vv_urgnetwork.txt: a classic URG-04LX's PP and VV
// replies as Hokuyo's urgnetwork wiki prints them (every checksum holds).
TEST(RealCapturesScip, Urg04lxPpAndVvReplies) {
  const auto replies = only<scip::Reply>(decodeAll<scip::Decoder, scip::Event>(
      readBinary("scip/urg04lx_pp_urgnetwork.txt") + readBinary("scip/urg04lx_vv_urgnetwork.txt")));
  ASSERT_EQ(replies.size(), 2u);
  const auto& pp = replies[0].params;
  EXPECT_EQ(pp.at("MODL"), "URG-04LX(Hokuyo Automatic Co.,Ltd.)");
  const scip::Params p = scip::parseParams(pp);
  const LidarModel& m = *findLidarModel("URG-04LX");
  EXPECT_EQ(p.dmin_mm, 20);
  EXPECT_EQ(p.dmax_mm, 5600);
  EXPECT_EQ(p.ares, 1024);
  EXPECT_EQ(p.amin, 44);
  EXPECT_EQ(p.amax, 725);
  EXPECT_EQ(p.afrt, 384);
  EXPECT_EQ(p.scan_rpm, 600);
  // The catalogue holds what the device says.
  EXPECT_EQ(m.pp.dmin_mm, p.dmin_mm);
  EXPECT_EQ(m.pp.dmax_mm, p.dmax_mm);
  EXPECT_EQ(m.pp.ares, p.ares);
  EXPECT_EQ(m.pp.amin, p.amin);
  EXPECT_EQ(m.pp.amax, p.amax);
  EXPECT_EQ(m.pp.afrt, p.afrt);
  EXPECT_EQ(m.pp.scan_rpm, p.scan_rpm);
  const auto& vv = replies[1].params;
  EXPECT_EQ(vv.at("PROD"), "SOKUIKI Sensor URG-04LX");
  EXPECT_EQ(vv.at("FIRM"), "3.1.00(18/Jan./2007)");
  EXPECT_EQ(vv.at("SERI"), "H0614967");
}

// --- HiPNUC HI219 / HI2xx -------------------------------------------------------------------

hi219::Frame onlyFrame(const std::string& name) {
  const auto events = decodeAll<hi219::Decoder, hi219::Event>(readHex(name));
  EXPECT_TRUE(only<DecodeError>(events).empty());
  const auto frames = only<hi219::Frame>(events);
  if (frames.size() != 1) throw std::runtime_error(name + ": expected one frame");
  return frames[0];
}

TEST(RealCapturesHi219, ManualFrameOfOldItems) {
  const hi219::Frame f = onlyFrame("hi219/manual_items_90_a0_b0_c0_d0_f0.hex");
  EXPECT_EQ(f.size, 41);
  EXPECT_EQ(f.id, 0);
  // The manual: acc(G) 0.597 0.317 0.738; gyr(deg/s) -0.200 2.300 6.800;
  // mag(uT) -12.800 -16.000 -20.600; eul(R/P/Y) 36.920 -34.840 44.300; pressure 0.
  const double acc_g[3] = {0.597, 0.317, 0.738}, gyr_dps[3] = {-0.2, 2.3, 6.8},
               mag_ut[3] = {-12.8, -16.0, -20.6}, rpy_deg[3] = {36.92, -34.84, 44.3};
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(f.accel_m_s2[k] / hi219::kGravity, acc_g[k], 1e-9) << k;
    EXPECT_NEAR(f.gyro_rad_s[k] / kDegToRad, gyr_dps[k], 1e-9) << k;
    EXPECT_NEAR(f.mag_ut[k], mag_ut[k], 1e-9) << k;
    EXPECT_NEAR(f.rpy_rad[k] / kDegToRad, rpy_deg[k], 1e-9) << k;
  }
  EXPECT_TRUE(f.has_pressure);
  EXPECT_EQ(f.pressure_pa, 0.0);
  EXPECT_FALSE(f.has_time);
  EXPECT_FALSE(f.has_quat);
}

TEST(RealCapturesHi219, ManualImusolRecord) {
  const hi219::Frame f = onlyFrame("hi219/manual_imusol_91.hex");
  EXPECT_EQ(f.size, 82);
  EXPECT_EQ(f.id, 0);
  EXPECT_EQ(f.time_ms, 310205u);
  // The manual, to three decimals: acc 0.224 0.770 0.691; gyr -54.708 -20.077 -119.070;
  // mag 19.183 -26.208 -34.542; eul(R/P/Y) 48.720 -21.014 -45.512; quat 0.855 0.310 -0.310
  // -0.277.
  const double acc_g[3] = {0.224, 0.770, 0.691}, gyr_dps[3] = {-54.708, -20.077, -119.070},
               mag_ut[3] = {19.183, -26.208, -34.542}, rpy_deg[3] = {48.720, -21.014, -45.512},
               quat[4] = {0.855, 0.310, -0.310, -0.277};
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(f.accel_m_s2[k] / hi219::kGravity, acc_g[k], 5e-4) << k;
    EXPECT_NEAR(f.gyro_rad_s[k] / kDegToRad, gyr_dps[k], 5e-4) << k;
    EXPECT_NEAR(f.mag_ut[k], mag_ut[k], 5e-4) << k;
    EXPECT_NEAR(f.rpy_rad[k] / kDegToRad, rpy_deg[k], 5e-4) << k;
  }
  for (int k = 0; k < 4; ++k) EXPECT_NEAR(f.quat_wxyz[k], quat[k], 5e-4) << k;
}

// --- YDLIDAR X4, captures we may not copy ----------------------------------------------------

// deepakkamesh/ydlidar's X4 streams have no licence, so they are not in the repository (see
// README.md). Fetch the repository at commit 3beb50e458de65b252580b817800b8b962f103ee and
// point SWEEPMAP_EXTERNAL_CAPTURES at a directory holding its scan1.data, scan2.data and
// scan3.data to run these tests; without it they are skipped.
std::optional<std::string> externalCapture(const std::string& file) {
  const char* dir = std::getenv("SWEEPMAP_EXTERNAL_CAPTURES");
  if (!dir) return std::nullopt;
  return readFile(std::string(dir) + "/" + file);
}

struct X4Stream {
  const char* file;
  size_t packets, samples, ring_starts;
  int64_t first_ring_offset;
  double first_ring_deg;  // the first zero packet's FSA
};
// Counted by an independent reading of the X4 development manual (a throw-away script over
// the bytes: A5 5A descriptor, then AA 55 packets, XOR check of the 16-bit words). Each file
// ends with a packet cut short (75, 74, 74 bytes of 90), which yields nothing.
const X4Stream kX4Streams[] = {
    {"scan1.data", 455, 16721, 28, 405, 348.515625},
    {"scan2.data", 1243, 43129, 71, 7, 203.984375},
    {"scan3.data", 1949, 68319, 114, 7, 227.546875},
};

TEST(RealCapturesX4External, DeepakkameshStreamsDecodeToTheirPackets) {
  for (const X4Stream& x : kX4Streams) {
    const auto bytes = externalCapture(x.file);
    if (!bytes) GTEST_SKIP() << "SWEEPMAP_EXTERNAL_CAPTURES/" << x.file << " not found";
    const auto events = decodeAll<ydlidar::Decoder, ydlidar::Event>(*bytes);
    EXPECT_TRUE(only<DecodeError>(events).empty()) << x.file;
    const auto starts = only<ydlidar::ScanStart>(events);
    ASSERT_EQ(starts.size(), 1u) << x.file;
    EXPECT_EQ(starts[0].offset, 0) << x.file;
    const auto packets = only<ydlidar::Packet>(events);
    EXPECT_EQ(packets.size(), x.packets) << x.file;
    size_t samples = 0, rings = 0;
    const ydlidar::Packet* first_ring = nullptr;
    for (const auto& p : packets) {
      samples += p.samples.size();
      if (!p.ring_start) continue;
      ++rings;
      if (!first_ring) first_ring = &p;
    }
    EXPECT_EQ(samples, x.samples) << x.file;
    EXPECT_EQ(rings, x.ring_starts) << x.file;
    ASSERT_NE(first_ring, nullptr) << x.file;
    EXPECT_EQ(first_ring->offset, x.first_ring_offset) << x.file;
    EXPECT_DOUBLE_EQ(first_ring->samples.at(0).raw_angle_deg, x.first_ring_deg) << x.file;
  }
}

// scan3.data, the packet at byte 1635: FSA 223.34375 deg, LSA 222.171875 deg, 40 samples;
// the packet before it (byte 1545) runs 204.0 .. 222.84375 deg over 40 samples, the one
// after it (byte 1725) 222.640625 .. 224.109375 deg. The vendor SDK (YDLIDAR/YDLidar-SDK
// src/YDlidarDriver.cpp at d37ace902f73, waitPackage, case 7: "if (LastSampleAngle <
// FirstSampleAngle) { if ((FirstSampleAngle > 270 * 64) && (LastSampleAngle < 90 * 64))
// wrap, else IntervalSampleAngle = IntervalSampleAngle_LastPackage") keeps the previous
// packet's step, (222.84375 - 204.0) / 39 deg, from FSA; so do we (once: counted as an anomaly).
TEST(RealCapturesX4External, AnomalousPacketKeepsThePreviousInterval) {
  const auto bytes = externalCapture("scan3.data");
  if (!bytes) GTEST_SKIP() << "SWEEPMAP_EXTERNAL_CAPTURES/scan3.data not found";
  ydlidar::Decoder decoder;
  std::vector<ydlidar::Event> events;
  decoder.feed(reinterpret_cast<const uint8_t*>(bytes->data()), bytes->size(), &events);
  EXPECT_EQ(decoder.counters().anomalies, 1);
  const auto packets = only<ydlidar::Packet>(events);
  const auto it = std::find_if(packets.begin(), packets.end(),
                               [](const ydlidar::Packet& p) { return p.offset == 1635; });
  ASSERT_NE(it, packets.end());
  ASSERT_EQ(it->samples.size(), 40u);
  const double interval = (222.84375 - 204.0) / 39.0;
  double worst = 0.0;
  for (size_t k = 0; k < 40; ++k) {
    worst = std::max(worst, std::abs(it->samples[k].raw_angle_deg - (223.34375 + interval * k)));
  }
  EXPECT_LT(worst, 1e-6) << "last sample at " << it->samples[39].raw_angle_deg
                         << " deg, the SDK puts it at " << 223.34375 + interval * 39;
}

// The X4 stream read again, apart from our decoder, by the development manual and the SDK's
// rules: AA 55 packets whose XOR of 16-bit words holds; sample i at FSA + i * step (the step
// from FSA..LSA across 0 when FSA > 270 and LSA < 90 deg, else the last packet's) plus
// atan(21.8 (155.3 - d) / (155.3 d)); turns from one zero packet (CT bit 0) to the next.
struct RawX4Sample {
  double angle_deg, distance_mm;
};
std::vector<std::vector<RawX4Sample>> rawX4Turns(const std::string& b) {
  const auto u16 = [&](size_t i) {
    return static_cast<int>(static_cast<uint8_t>(b[i]) | (static_cast<uint8_t>(b[i + 1]) << 8));
  };
  std::vector<std::vector<RawX4Sample>> turns;  // turns[0]: before the first zero packet
  turns.emplace_back();
  double last_step = 0.0;
  for (size_t i = 0; i + 10 <= b.size();) {
    const size_t lsn = static_cast<uint8_t>(b[i + 3]);
    if (u16(i) != 0x55AA || lsn == 0 || i + 10 + 2 * lsn > b.size()) {
      ++i;
      continue;
    }
    int x = 0;
    for (size_t w = 0; w < 5 + lsn; ++w) x ^= w == 4 ? 0 : u16(i + 2 * w);
    if (x != u16(i + 8)) {
      ++i;
      continue;
    }
    const int fsa = u16(i + 4) >> 1, lsa = u16(i + 6) >> 1;
    if (lsn > 1 && (lsa >= fsa || (fsa > 270 * 64 && lsa < 90 * 64))) {
      last_step = ((lsa - fsa + 360 * 64) % (360 * 64)) / 64.0 / double(lsn - 1);
    }
    if (b[i + 2] & 1) turns.emplace_back();
    for (size_t k = 0; k < lsn; ++k) {
      const double d = u16(i + 10 + 2 * k) / 4.0;
      double a = fsa / 64.0 + (lsn > 1 ? last_step : 0.0) * double(k);
      if (d > 0) a += std::atan(21.8 * (155.3 - d) / (155.3 * d)) * 180.0 / M_PI;
      turns.back().push_back({std::fmod(a + 360.0, 360.0), d});
    }
    i += 10 + 2 * lsn;
  }
  return turns;
}

// The X4 of rig B as the rig file describes it (config/rig_b.yaml).
LidarConfig x4Rig() {
  LidarConfig c;
  c.model = "YDLIDAR-X4";
  c.beam_count = 714;
  c.angle_min_deg = -180.0;
  c.angle_increment_deg = 360.0 / 714;
  c.scan_rate_hz = 7.0;
  c.steps_per_revolution = 714;
  c.range_min_m = 0.12;
  c.range_max_m = 10.0;
  return c;
}

// One LIDAR_SCAN per revolution between zero packets, none for the turn the stream starts in
// or the one it ends in, and every valid sample (0.12..10 m) of each complete turn in it, in
// order, at its own angle (0.01 deg).
TEST(RealCapturesX4External, OneScanPerRevolutionWithEverySample) {
  for (const X4Stream& x : kX4Streams) {
    const auto bytes = externalCapture(x.file);
    if (!bytes) GTEST_SKIP() << "SWEEPMAP_EXTERNAL_CAPTURES/" << x.file << " not found";
    const auto turns = rawX4Turns(*bytes);
    ASSERT_EQ(turns.size(), x.ring_starts + 1) << x.file;
    auto session = makeLidarSession(DeviceProtocol::kYdlidarX4, x4Rig(), {ScanTime::kStream, 0});
    std::vector<Scan2D> scans;
    std::vector<std::string> errors;
    session->onBytes(reinterpret_cast<const uint8_t*>(bytes->data()), bytes->size(), -1, &scans,
                     &errors);
    session->finish(&scans, &errors);
    EXPECT_EQ(errors.size(), 1u) << x.file;  // the packet cut short at the end
    std::string counts;
    for (const auto& [name, value] : session->sessionCounters()) {
      counts += " " + name + " " + std::to_string(value);
    }
    ASSERT_EQ(scans.size(), x.ring_starts - 1) << x.file << counts;
    size_t valid = 0, present = 0;
    for (size_t k = 0; k < scans.size(); ++k) {
      const Scan2D& s = scans[k];
      const auto& turn = turns[k + 1];
      EXPECT_TRUE(validateScan(s, 714).empty()) << validateScan(s, 714);
      ASSERT_EQ(s.angles_rad.size(), s.ranges_m.size());
      EXPECT_EQ(s.ranges_m.size(), turn.size()) << x.file << " turn " << k;
      for (size_t i = 0; i < turn.size(); ++i) {
        if (turn[i].distance_mm < 120.0 || turn[i].distance_mm > 10000.0) continue;
        ++valid;
        if (i >= s.ranges_m.size()) continue;
        const double da = std::remainder(s.angles_rad[i] / kDegToRad - turn[i].angle_deg, 360.0);
        if (std::abs(s.ranges_m[i] * 1e3 - turn[i].distance_mm) < 1e-3 && std::abs(da) < 0.01) {
          ++present;
        }
      }
      for (size_t i = 1; i < s.ranges_m.size(); ++i) ASSERT_GT(s.rayUtime(i), s.rayUtime(i - 1));
      if (k > 0) {
        EXPECT_GT(s.utime, scans[k - 1].rayUtime(scans[k - 1].ranges_m.size() - 1));
      }
    }
    std::cout << x.file << ": " << scans.size() << " turns, " << valid << " valid samples in them, "
              << present << " present (" << 100.0 * double(present) / double(valid) << " %)\n";
    EXPECT_GE(double(present), 0.999 * double(valid)) << x.file;
  }
}

// --- RPLIDAR standard scan, captures we may not copy -----------------------------------------

// CodreanuDan/RPLidar_RoomScanner (no licence; README.md): an RPLIDAR's health reply, then the
// SCAN descriptor and 5-byte samples, dumped as hex text ("0xa5" per line, or "A5 5A ..."),
// in FrameGrabber/scripts/Measurements/. Read again here apart from our decoder, by the
// protocol document: after A5 5A 05 00 00 40 81, 5-byte samples whose S and !S differ and whose
// C bit is 1 (else one byte on); turns from one S = 1 to the next.
std::string hexText(const std::string& text) {
  std::string bytes;
  for (size_t i = 0; i + 1 < text.size();) {
    if (text[i] == '0' && (text[i + 1] == 'x' || text[i + 1] == 'X')) i += 2;
    if (i + 1 < text.size() && std::isxdigit(static_cast<unsigned char>(text[i])) &&
        std::isxdigit(static_cast<unsigned char>(text[i + 1]))) {
      bytes.push_back(static_cast<char>(std::stoi(text.substr(i, 2), nullptr, 16)));
      i += 2;
    } else {
      ++i;
    }
  }
  return bytes;
}

struct RawRpSample {
  double angle_deg, distance_mm;
};
std::vector<std::vector<RawRpSample>> rawRplidarTurns(const std::string& b) {
  std::vector<std::vector<RawRpSample>> turns(1);  // turns[0]: before the first S = 1
  size_t i = b.find(std::string("\xA5\x5A\x05\x00\x00\x40\x81", 7));
  if (i == std::string::npos) return {};
  const auto u = [&](size_t k) { return static_cast<unsigned>(static_cast<uint8_t>(b[k])); };
  for (i += 7; i + 5 <= b.size();) {
    const unsigned q6 = (u(i + 1) >> 1) | (u(i + 2) << 7);
    if ((u(i) & 1) == ((u(i) >> 1) & 1) || (u(i + 1) & 1) != 1 || q6 >= 360 * 64) {
      ++i;
      continue;
    }
    if (u(i) & 1) turns.emplace_back();
    turns.back().push_back({q6 / 64.0, (u(i + 3) | (u(i + 4) << 8)) / 4.0});
    i += 5;
  }
  return turns;
}

// Every complete turn of each dump one LIDAR_SCAN, with every valid sample (0.15 .. 12 m) in
// it at its own angle.
TEST(RealCapturesRplidarExternal, OneScanPerTurnWithEverySample) {
  LidarConfig a1;
  a1.model = "RPLIDAR-A1";
  a1.steps_per_revolution = 360;
  a1.range_min_m = 0.15;
  a1.range_max_m = 12.0;
  a1.scan_rate_hz = 5.5;
  for (const char* file :
       {"sample_data_2.txt", "sample_data_pyserial_1.txt", "sample_data_pyserial_3.txt"}) {
    const auto text = externalCapture(file);
    if (!text) GTEST_SKIP() << "SWEEPMAP_EXTERNAL_CAPTURES/" << file << " not found";
    const std::string bytes = hexText(*text);
    const auto turns = rawRplidarTurns(bytes);
    ASSERT_GE(turns.size(), 3u) << file;
    auto session = makeLidarSession(DeviceProtocol::kRplidar, a1, {ScanTime::kStream, 0});
    std::vector<Scan2D> scans;
    std::vector<std::string> errors;
    session->onBytes(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size(), -1, &scans,
                     &errors);
    session->finish(&scans, &errors);
    ASSERT_EQ(scans.size(), turns.size() - 2) << file;  // neither the first nor the open last
    size_t valid = 0, present = 0;
    for (size_t k = 0; k < scans.size(); ++k) {
      const auto& turn = turns[k + 1];
      EXPECT_EQ(scans[k].ranges_m.size(), turn.size()) << file << " turn " << k;
      for (size_t i = 0; i < turn.size(); ++i) {
        if (turn[i].distance_mm < 150.0 || turn[i].distance_mm > 12000.0) continue;
        ++valid;
        if (i >= scans[k].ranges_m.size()) continue;
        const double da =
            std::remainder(scans[k].angles_rad[i] / kDegToRad - turn[i].angle_deg, 360.0);
        present += std::abs(scans[k].ranges_m[i] * 1e3 - turn[i].distance_mm) < 1e-3 &&
                   std::abs(da) < 0.01;
      }
    }
    std::cout << file << ": " << scans.size() << " turns, " << valid << " valid samples, "
              << present << " present (" << 100.0 * double(present) / double(valid) << " %)\n";
    EXPECT_GE(double(present), 0.999 * double(valid)) << file;
  }
}

}  // namespace
}  // namespace sweepmap
