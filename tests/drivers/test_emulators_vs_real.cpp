// The emulated devices against bytes of the real ones (tests/data/real/README.md), decoded by
// the same code: an emulator is checked against the device, not the other way round. X4: the
// statistics of a stream (samples per packet, where the zero packets fall, samples per turn)
// must be compatible with a real X4's (not equal: another room, another motor). HI219: the old
// item set, frame for frame like the manual's sample of a real module.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <optional>
#include <sstream>

#include "drivers/protocols/hi219.hpp"
#include "drivers/protocols/ydlidar.hpp"
#include "sim/beam.hpp"
#include "tools/emulate/odometry_emulators.hpp"
#include "tools/emulate/serial_devices.hpp"

namespace sweepmap {
namespace {

// What a stream of X4 bytes holds, by our decoder.
struct X4Stats {
  size_t packets = 0, full = 0, shortest = 255, longest = 0;  // sample packets (not zero)
  std::vector<double> ring_deg;                               // the zero packets' angles
  std::vector<size_t> turn_samples;  // samples between two zero packets after the first
  double fullShare() const { return packets ? double(full) / double(packets) : 0.0; }
  double laterRingSpreadDeg() const {
    if (ring_deg.size() < 3) return 0.0;
    const auto [lo, hi] = std::minmax_element(ring_deg.begin() + 1, ring_deg.end());
    return *hi - *lo;
  }
  // (p90 - p10) / median of the turns after the first complete one.
  double turnSpread() const {
    if (turn_samples.size() < 4) return 1.0;
    std::vector<size_t> t(turn_samples.begin() + 1, turn_samples.end());
    std::sort(t.begin(), t.end());
    const auto at = [&](double q) { return double(t[static_cast<size_t>(q * (t.size() - 1))]); };
    return (at(0.9) - at(0.1)) / at(0.5);
  }
};

X4Stats x4Stats(const std::string& bytes) {
  ydlidar::Decoder decoder;
  std::vector<ydlidar::Event> events;
  decoder.feed(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size(), &events);
  X4Stats s;
  size_t in_turn = 0;
  for (const auto& e : events) {
    const auto* p = std::get_if<ydlidar::Packet>(&e);
    if (!p) continue;
    if (p->ring_start) {
      if (!s.ring_deg.empty()) s.turn_samples.push_back(in_turn);
      s.ring_deg.push_back(p->samples.at(0).raw_angle_deg);
      in_turn = 0;
    } else {
      ++s.packets;
      s.full += p->samples.size() == 40;
      s.shortest = std::min(s.shortest, p->samples.size());
      s.longest = std::max(s.longest, p->samples.size());
    }
    in_turn += p->samples.size();
  }
  return s;
}

// The range a ray along `bearing` meets in a room of 4 x 3 m seen from (0.7, -0.4) m, with a
// pillar of 0.3 x 0.3 m at (1.35, -1.05) .. (1.65, -0.75) when `pillar` (two depth edges of
// about 0.6 m against 1.3 m and more).
double roomRange(double bearing, bool pillar) {
  const double c = std::cos(bearing), d = std::sin(bearing);
  const double rx = c > 0 ? (2.0 - 0.7) / c : (-2.0 - 0.7) / c;
  const double ry = d > 0 ? (1.5 + 0.4) / d : (-1.5 + 0.4) / d;
  double r = std::min(rx, ry);
  if (pillar) {
    // Slabs: the ray's entry into the pillar's x and y ranges.
    const double lo[2] = {1.35 - 0.7, -1.05 + 0.4}, hi[2] = {1.65 - 0.7, -0.75 + 0.4};
    const double dir[2] = {c, d};
    double t_in = 0.0, t_out = 1e9;
    for (int k = 0; k < 2; ++k) {
      if (std::fabs(dir[k]) < 1e-12) {
        if (lo[k] > 0.0 || hi[k] < 0.0) t_in = 1e9;
        continue;
      }
      const double a = lo[k] / dir[k], b = hi[k] / dir[k];
      t_in = std::max(t_in, std::min(a, b));
      t_out = std::min(t_out, std::max(a, b));
    }
    if (t_in <= t_out && t_in > 0.0) r = std::min(r, t_in);
  }
  return r;
}

// That room seen by a 360° lidar turning at 8.2 Hz, 5000 samples per second (the real X4
// streams: about 608 samples per turn); scans handed out as they begin, their rays on the
// motor's grid, each cast along the beam `beam` (empty: along the motor angle, no
// Scan2D::angles_rad). Every scan handed out is appended to *given when not null.
ScanSource roomSource(bool pillar = false, const BeamOffset& beam = nullptr,
                      std::vector<Scan2D>* given = nullptr) {
  auto next = std::make_shared<int64_t>(0);
  return [next, pillar, beam, given](int64_t now_us) {
    std::vector<Scan2D> out;
    constexpr double kRate = 8.2, kSamples = 5000.0 / kRate;
    for (;; ++*next) {
      const auto start = static_cast<int64_t>(std::llround(double(*next) / kRate * 1e6));
      if (start > now_us) break;
      Scan2D s;
      s.utime = start;
      s.seq = *next;
      const int n = static_cast<int>(kSamples);
      s.angle_min_rad = -M_PI;
      s.angle_increment_rad = 2.0 * M_PI / n;
      s.time_increment_ns = 200000;
      s.range_min_m = 0.12;
      s.range_max_m = 10.0;
      for (int i = 0; i < n; ++i) {
        const double motor = s.angle_min_rad + s.angle_increment_rad * i;
        const auto range_at = [&](double b) { return roomRange(b, pillar); };
        const BeamHit hit =
            beam ? castBeam(motor, beam, range_at) : BeamHit{motor, range_at(motor)};
        s.ranges_m.push_back(static_cast<float>(hit.range_m));
        if (beam) s.angles_rad.push_back(static_cast<float>(hit.bearing_rad));
      }
      if (given) given->push_back(s);
      out.push_back(std::move(s));
    }
    return out;
  };
}

// 20 s of an emulated X4 after A5 60 at t = 0.25 s.
std::string emulatedX4Stream(ScanSource source = roomSource()) {
  X4Device x4(std::move(source));
  std::string out;
  const std::string start("\xA5\x60", 2);
  x4.receive(reinterpret_cast<const uint8_t*>(start.data()), start.size(), 250000, &out);
  for (int64_t t = 250000; t <= 20250000; t += 5000) x4.advance(t, &out);
  return out;
}

std::optional<std::string> externalCapture(const std::string& file) {
  const char* dir = std::getenv("SWEEPMAP_EXTERNAL_CAPTURES");
  if (!dir) return std::nullopt;
  std::ifstream in(std::string(dir) + "/" + file, std::ios::binary);
  if (!in) return std::nullopt;
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void expectCompatible(const X4Stats& emu, const X4Stats& real, const std::string& name) {
  EXPECT_GE(emu.shortest, 1u);
  EXPECT_EQ(emu.longest, 40u);
  EXPECT_NEAR(emu.fullShare(), real.fullShare(), 0.15) << name;
  EXPECT_LT(emu.laterRingSpreadDeg(), 2.0 * std::max(real.laterRingSpreadDeg(), 0.5)) << name;
  EXPECT_LT(emu.turnSpread(), std::max(3.0 * real.turnSpread(), 0.02)) << name;
}

// The emulated X4 against the figures of three real streams (tests/data/real/README.md:
// about 91 % of the sample packets hold 40 samples, the rest 1 .. 39; the first zero packet
// where scanning starts, then every one within 348.0 .. 348.6 deg; turns of 593 .. 609
// samples), and against the streams themselves when SWEEPMAP_EXTERNAL_CAPTURES holds them.
TEST(EmulatorsVsReal, X4StreamStatisticsAreCompatible) {
  const X4Stats emu = x4Stats(emulatedX4Stream());
  ASSERT_GT(emu.ring_deg.size(), 100u);
  std::cout << "emulated X4: " << emu.packets << " packets, " << 100 * emu.fullShare()
            << " % of 40 samples, shortest " << emu.shortest << "; zero packets at "
            << emu.ring_deg[0] << " deg, then within " << emu.laterRingSpreadDeg()
            << " deg; turn spread " << emu.turnSpread() << "\n";
  X4Stats documented;
  documented.packets = 100;
  documented.full = 91;
  documented.ring_deg = {203.98, 348.0, 348.6};
  documented.turn_samples = {593, 598, 600, 607, 608, 608, 609};
  expectCompatible(emu, documented, "the README's figures");
  EXPECT_LT(emu.fullShare(), 0.99);  // short packets too
  // The first zero packet is the first sample after A5 60 (0.25 s after the first scan began, 8.2
  // Hz), not at the index mark; the later ones are.
  EXPECT_GT(std::abs(emu.ring_deg[0] - X4Device::kIndexMarkDeg), 5.0);
  EXPECT_NEAR(emu.ring_deg[1], X4Device::kIndexMarkDeg, 1.0);
  // The first turn ends where the motor first passes the mark, part of a turn, as on a real X4
  // (scan3: its first zero packet at 227.5°, the next at 348.0° 236 samples later).
  EXPECT_NEAR(double(emu.turn_samples.at(0)),
              5000.0 / 8.2 * (X4Device::kIndexMarkDeg - emu.ring_deg[0]) / 360.0, 3.0);
  for (const char* file : {"scan1.data", "scan2.data", "scan3.data"}) {
    const auto real = externalCapture(file);
    if (!real) continue;
    const X4Stats r = x4Stats(*real);
    std::cout << file << ": " << r.packets << " packets, " << 100 * r.fullShare()
              << " % of 40 samples; zero packets within " << r.laterRingSpreadDeg()
              << " deg after the first; turn spread " << r.turnSpread() << "\n";
    expectCompatible(emu, r, file);
  }
}

// FSA and LSA of a sample packet at stream offset `at` [1/64 deg].
std::pair<int, int> fsaLsa(const std::string& bytes, int64_t at) {
  const auto u16 = [&](int64_t k) {
    return int(uint8_t(bytes[size_t(k)])) | int(uint8_t(bytes[size_t(k + 1)])) << 8;
  };
  return {u16(at + 4) >> 1, u16(at + 6) >> 1};
}

// A real X4's motor turns evenly and it reports the motor's angles, so within a turn FSA and
// LSA never run backwards, whatever the ranges do: LSA >= FSA in every packet but across the
// 360 -> 0 wrap and the deliberate anomalies (LSA 75/64 deg below FSA, after a full packet),
// and each packet's FSA one step past the previous packet's last sample. A pillar puts depth
// edges in view, where AngCorrect jumps by about 0.9 deg.
TEST(EmulatorsVsReal, X4MotorAnglesRunEvenlyPastDepthEdges) {
  const std::string bytes = emulatedX4Stream(roomSource(true));
  ydlidar::Decoder decoder;
  std::vector<ydlidar::Event> events;
  decoder.feed(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size(), &events);
  const double step = 360.0 * 64.0 / int(5000.0 / 8.2);  // the motor's step [1/64 deg]
  int anomalies = 0, checked = 0, prev_last = -1;
  size_t prev_size = 0;
  for (const auto& e : events) {
    const auto* p = std::get_if<ydlidar::Packet>(&e);
    if (!p) continue;
    const auto [fsa, lsa] = fsaLsa(bytes, p->offset);
    const size_t n = p->samples.size();
    if (prev_last >= 0) {
      // One motor step after the previous packet's last sample (mod 360 deg; 1/64 deg steps).
      const int gap = ((fsa - prev_last) % (360 * 64) + 360 * 64) % (360 * 64);
      EXPECT_NEAR(gap, step, 2) << "packet at byte " << p->offset;
      ++checked;
    }
    const bool wrap = fsa > 270 * 64 && lsa < 90 * 64;
    if (n > 1 && lsa < fsa && !wrap) {
      EXPECT_EQ(fsa - lsa, 75) << "packet at byte " << p->offset;  // a deliberate anomaly
      EXPECT_EQ(prev_size, 40u) << "packet at byte " << p->offset;
      ++anomalies;
      prev_last = static_cast<int>(std::lround(fsa + step * double(n - 1))) % (360 * 64);
    } else {
      const int span = ((lsa - fsa) % (360 * 64) + 360 * 64) % (360 * 64);  // across 0 too
      EXPECT_NEAR(span, step * double(n - 1), 2) << "packet at byte " << p->offset;
      prev_last = lsa;
    }
    prev_size = n;
  }
  EXPECT_GT(checked, 2000);
  EXPECT_EQ(anomalies, decoder.counters().anomalies);
  EXPECT_LE(anomalies, 10);
}

// The whole chain: each ray cast where the X4's beam looks (motor + AngCorrect of the range it
// meets, sim/beam.hpp), the device reporting its motor angles, the host's decoder correcting
// them: every sample where its ray looked, past the pillar's depth edges too, and with the
// range it met.
TEST(EmulatorsVsReal, X4SamplesLandWhereTheirRaysLooked) {
  std::vector<Scan2D> given;
  const std::string bytes = emulatedX4Stream(roomSource(true, X4Device::beamOffsetRad, &given));
  struct Truth {
    double bearing_deg, range_mm;
  };
  std::vector<Truth> truth;  // the rays measured after A5 60 (0.25 s), in order
  size_t shadowed = 0;
  for (const Scan2D& s : given) {
    for (size_t i = 0; i < s.ranges_m.size(); ++i) {
      if (s.rayUtime(i) < 250000) continue;
      truth.push_back({s.rayAngle(i) * 180.0 / M_PI, s.ranges_m[i] * 1000.0});
      shadowed += s.ranges_m[i] == 0.0f;
    }
  }
  ydlidar::Decoder decoder;
  std::vector<ydlidar::Event> events;
  decoder.feed(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size(), &events);
  size_t k = 0, edges = 0;
  double worst_deg = 0.0;
  for (const auto& e : events) {
    const auto* p = std::get_if<ydlidar::Packet>(&e);
    if (!p) continue;
    for (const ydlidar::Sample& s : p->samples) {
      ASSERT_LT(k, truth.size());
      const Truth& t = truth[k++];
      EXPECT_NEAR(s.distance_mm, t.range_mm, 0.13) << "sample " << k;
      const double err = std::fabs(std::remainder(s.angle_deg - t.bearing_deg, 360.0));
      worst_deg = std::max(worst_deg, err);
      // A sample whose neighbour met a surface 0.3 m nearer or farther: a depth edge.
      if (k >= 2 && std::fabs(truth[k - 1].range_mm - truth[k - 2].range_mm) > 300.0) ++edges;
    }
  }
  std::cout << "emulated X4: " << k << " samples, worst angle error " << worst_deg << " deg, "
            << edges << " at depth edges, " << shadowed << " rays without a return\n";
  EXPECT_GT(k, 90000u);
  EXPECT_GT(edges, 100u);      // the pillar's edges were seen, every turn
  EXPECT_LT(worst_deg, 0.05);  // FSA/LSA in 1/64 deg, ranges in 1/4 mm
}

// The emulated HI219 set to the old item set: the items, sizes and units of the manual's frame
// (hi219/manual_items_90_a0_b0_c0_d0_f0.hex, sampled from a module), decoded by the same code.
TEST(EmulatorsVsReal, Hi219OldItemFramesLikeTheManualsSample) {
  std::ifstream in(std::string(SWEEPMAP_SOURCE_DIR) +
                   "/tests/data/real/hi219/manual_items_90_a0_b0_c0_d0_f0.hex");
  ASSERT_TRUE(in);
  std::string manual, line;
  while (std::getline(in, line)) {
    std::istringstream tokens(line.substr(0, line.find('#')));
    std::string t;
    while (tokens >> t) manual.push_back(static_cast<char>(std::stoi(t, nullptr, 16)));
  }
  ImuSample sample{};
  sample.utime = 1000000;
  const double gyro[3] = {0.01, -0.02, 0.3}, accel[3] = {0.5, -0.2, 9.81},
               rpy[3] = {0.1, -0.05, 1.2};
  for (int k = 0; k < 3; ++k) {
    sample.gyro[k] = gyro[k];
    sample.accel[k] = accel[k];
    sample.rpy[k] = rpy[k];
  }
  bool sent = false;
  Hi219Device imu(
      [&](int64_t) {
        std::vector<ImuSample> v;
        if (!sent) v.push_back(sample);
        sent = true;
        return v;
      },
      DeviceClockModel{}, 0, Hi219Frames::kOldItems);
  std::string emulated;
  imu.advance(2000000, &emulated);
  const auto decode = [](const std::string& bytes) {
    hi219::Decoder d;
    std::vector<hi219::Event> out;
    d.feed(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size(), &out);
    EXPECT_EQ(out.size(), 1u);
    return std::get<hi219::Frame>(out.at(0));
  };
  const hi219::Frame m = decode(manual), e = decode(emulated);
  EXPECT_EQ(e.size, m.size);  // 41 bytes: 90 A0 B0 C0 D0 F0
  EXPECT_EQ(emulated.substr(0, 4), manual.substr(0, 4));
  EXPECT_EQ(e.id, m.id);
  EXPECT_EQ(e.has_accel && e.has_gyro && e.has_mag && e.has_euler && e.has_pressure, true);
  EXPECT_FALSE(e.has_quat);
  EXPECT_FALSE(e.has_time);  // the old items carry no time stamp
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(e.accel_m_s2[k], sample.accel[k], 1e-3 * hi219::kGravity) << k;  // 1 mG
    EXPECT_NEAR(e.gyro_rad_s[k], sample.gyro[k], 0.1 * M_PI / 180.0) << k;       // 0.1°/s
  }
  EXPECT_NEAR(e.rpy_rad[0], sample.rpy[0], 0.01 * M_PI / 180.0);
  EXPECT_NEAR(e.rpy_rad[1], sample.rpy[1], 0.01 * M_PI / 180.0);
  EXPECT_NEAR(e.rpy_rad[2], sample.rpy[2], 0.1 * M_PI / 180.0);
}

}  // namespace
}  // namespace sweepmap
