// The lidar protocol decoders against the protocol documents' own examples (SCIP 2.0
// encodings and checksums, a VV reply captured from a real URG-04LX-UG01, the X4's packet
// layout, check code and angle correction, RPLIDAR descriptors and sample bits), the same
// bytes split at every position, garbage and false sync bytes between packets, bad
// checksums, and the emulated devices' conversations.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <string>

#include "drivers/lidar_sessions.hpp"
#include "drivers/protocols/rplidar.hpp"
#include "drivers/protocols/scip.hpp"
#include "drivers/protocols/ydlidar.hpp"
#include "tools/emulate/devices.hpp"
#include "tools/emulate/scip_device.hpp"
#include "tools/emulate/serial_devices.hpp"

namespace sweepmap {
namespace {

template <class Decoder, class Event>
std::vector<Event> decodeAll(const std::string& s, Decoder* d = nullptr) {
  Decoder local;
  if (!d) d = &local;
  std::vector<Event> out;
  d->feed(reinterpret_cast<const uint8_t*>(s.data()), s.size(), &out);
  return out;
}

template <class T, class Event>
std::vector<T> only(const std::vector<Event>& events) {
  std::vector<T> out;
  for (const auto& e : events) {
    if (const T* t = std::get_if<T>(&e)) out.push_back(*t);
  }
  return out;
}

// ---- SCIP 2.0 ----------------------------------------------------------------------------

TEST(Scip, EncodingExamplesOfTheSpecification) {
  EXPECT_EQ(scip::encodeValue(1234, 2), "CB");
  EXPECT_EQ(scip::encodeValue(5432, 3), "1Dh");
  EXPECT_EQ(*scip::decodeValue("CB"), 1234u);
  EXPECT_EQ(*scip::decodeValue("1Dh"), 5432u);
  EXPECT_EQ(*scip::decodeValue(scip::encodeValue(16777215, 4)), 16777215u);
  EXPECT_FALSE(scip::decodeValue("C "));
  EXPECT_FALSE(scip::decodeValue("CBCBC"));
}

TEST(Scip, ChecksumExamples) {
  EXPECT_EQ(scip::withChecksum("00"), "00P");
  EXPECT_EQ(scip::withChecksum("99"), "99b");
  EXPECT_EQ(scip::withChecksum("02"), "02R");       // BM on a laser already on
  EXPECT_EQ(scip::checksum("PROT:SCIP 2.0"), 'N');  // the specification's example
  EXPECT_EQ(scip::checksum("VEND:Hokuyo Automatic Co.,Ltd."), '[');
  EXPECT_EQ(scip::checksum("FIRM:3.4.03(17/Dec./2012)"), 'T');
}

// A VV reply as a URG-04LX-UG01 sent it.
const std::string kRealVv =
    "VV\n00P\nVEND:Hokuyo Automatic Co.,Ltd.;[\n"
    "PROD:SOKUIKI Sensor URG-04LX-UG01(Simple-URG);[\nFIRM:3.4.03(17/Dec./2012);T\n"
    "PROT:SCIP 2.0;N\nSERI:H1510998;V\n\n";

TEST(Scip, DecodesARealVvReply) {
  const auto events = decodeAll<scip::Decoder, scip::Event>(kRealVv);
  const auto replies = only<scip::Reply>(events);
  ASSERT_EQ(replies.size(), 1u);
  EXPECT_TRUE(replies[0].ok);
  EXPECT_EQ(replies[0].params.at("SERI"), "H1510998");
  EXPECT_EQ(replies[0].params.at("PROD"), "SOKUIKI Sensor URG-04LX-UG01(Simple-URG)");
  EXPECT_EQ(replies[0].params.at("PROT"), "SCIP 2.0");
}

// An MD reply by hand: steps 44..65, cluster 1, 22 values of 3 characters (66 characters:
// the last value straddles the first 64-character block and the second).
std::string handMdReply(uint32_t stamp, std::vector<uint32_t>* values) {
  std::string data;
  for (uint32_t i = 0; i < 22; ++i) {
    values->push_back(1000 + 37 * i);
    data += scip::encodeValue(values->back(), 3);
  }
  const std::string b1 = data.substr(0, 64), b2 = data.substr(64);
  return "MD0044006501000\n99b\n" + scip::withChecksum(scip::encodeValue(stamp, 4)) + "\n" +
         scip::withChecksum(b1) + "\n" + scip::withChecksum(b2) + "\n\n";
}

TEST(Scip, ValuesStraddleBlocks) {
  std::vector<uint32_t> values;
  const auto scans =
      only<scip::ScanData>(decodeAll<scip::Decoder, scip::Event>(handMdReply(4321, &values)));
  ASSERT_EQ(scans.size(), 1u);
  EXPECT_EQ(scans[0].ranges_mm, values);
  EXPECT_EQ(scans[0].time_ms, 4321u);
  EXPECT_EQ(scans[0].start_step, 44);
  EXPECT_EQ(scans[0].end_step, 65);
}

TEST(Scip, EveryStatusCodeIsNamed) {
  EXPECT_EQ(scip::statusText("MD", "04"), "end step is out of range");
  EXPECT_EQ(scip::statusText("GD", "10"), "laser is off");
  EXPECT_EQ(scip::statusText("BM", "02"), "laser is already on");
  EXPECT_EQ(scip::statusText("TM", "03"), "adjust mode is off (send TM0 first)");
  EXPECT_EQ(scip::statusText("QT", "0E"), "undefined command (2)");
  EXPECT_EQ(scip::statusText("MD", "55"), "hardware trouble (laser, motor or other malfunction)");
  EXPECT_EQ(scip::statusText("MD", "ZZ"), "unknown status");
  const auto replies = only<scip::Reply>(decodeAll<scip::Decoder, scip::Event>(
      "MD0000999901000\n04" + std::string(1, scip::checksum("04")) + "\n\n"));
  ASSERT_EQ(replies.size(), 1u);
  EXPECT_FALSE(replies[0].ok);
  EXPECT_EQ(replies[0].status, "04");
}

// A stream of replies: the same events whatever the split.
std::string scipStream() {
  std::vector<uint32_t> v;
  return kRealVv + "BM\n02R\n\n" + handMdReply(1, &v) + handMdReply(26, &v) + "QT\n00P\n\n";
}

TEST(Scip, SameEventsSplitAtEveryPosition) {
  const std::string s = scipStream();
  const auto whole = decodeAll<scip::Decoder, scip::Event>(s);
  ASSERT_EQ(whole.size(), 5u);
  for (size_t cut = 0; cut <= s.size(); ++cut) {
    scip::Decoder d;
    std::vector<scip::Event> out;
    d.feed(reinterpret_cast<const uint8_t*>(s.data()), cut, &out);
    d.feed(reinterpret_cast<const uint8_t*>(s.data()) + cut, s.size() - cut, &out);
    ASSERT_EQ(out.size(), whole.size()) << "cut at " << cut;
    EXPECT_EQ(only<scip::ScanData>(out).back().time_ms, 26u);
  }
}

TEST(Scip, GarbageAndFalseStartsAreSkippedAndCounted) {
  std::vector<uint32_t> v;
  const std::string s =
      "\x01\x02junk\n\nMDxx\n" + handMdReply(7, &v) + "\x7f\x7f" + handMdReply(8, &v);
  scip::Decoder d;
  const auto events = decodeAll<scip::Decoder, scip::Event>(s, &d);
  const auto scans = only<scip::ScanData>(events);
  ASSERT_EQ(scans.size(), 2u);  // both good replies kept
  EXPECT_EQ(scans[1].time_ms, 8u);
  EXPECT_GE(d.counters().resyncs, 2);
  EXPECT_GT(d.counters().discarded_bytes, 8);
  EXPECT_EQ(d.counters().scans, 2);
}

TEST(Scip, BadBlockChecksumDropsThatScanOnly) {
  std::vector<uint32_t> v;
  std::string bad = handMdReply(7, &v);
  bad[30] = bad[30] == 'A' ? 'B' : 'A';  // a data character
  scip::Decoder d;
  const auto events = decodeAll<scip::Decoder, scip::Event>(bad + handMdReply(8, &v), &d);
  const auto scans = only<scip::ScanData>(events);
  ASSERT_EQ(scans.size(), 1u);
  EXPECT_EQ(scans[0].time_ms, 8u);
  EXPECT_EQ(d.counters().checksum_errors, 1);
  const auto errors = only<DecodeError>(events);
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].what.find("checksum"), std::string::npos);
  EXPECT_GT(errors[0].offset, 20);
}

TEST(Scip, ALostReplyEndDoesNotLoseTheNextReply) {
  std::vector<uint32_t> v;
  std::string first = handMdReply(7, &v);
  first.pop_back();  // the empty line that ends it
  const auto scans =
      only<scip::ScanData>(decodeAll<scip::Decoder, scip::Event>(first + handMdReply(8, &v)));
  ASSERT_EQ(scans.size(), 1u);
  EXPECT_EQ(scans[0].time_ms, 8u);
}

TEST(Scip, EndlessGarbageStaysBounded) {
  scip::Decoder d;
  std::vector<scip::Event> out;
  const std::string junk(1 << 20, 'x');
  d.feed(reinterpret_cast<const uint8_t*>(junk.data()), junk.size(), &out);
  std::vector<uint32_t> v;
  const std::string good = "\n" + handMdReply(9, &v);
  d.feed(reinterpret_cast<const uint8_t*>(good.data()), good.size(), &out);
  EXPECT_EQ(only<scip::ScanData>(out).size(), 1u);
  EXPECT_GE(d.counters().discarded_bytes, 1 << 20);
}

// The emulated UST-10LX: a conversation as the specification describes it.
TEST(ScipDevice, Conversation) {
  int64_t next = 0;
  ScanSource source = [&](int64_t now_us) {
    std::vector<Scan2D> out;
    while (next * 25000 + 25000 <= now_us) {
      Scan2D s;
      s.utime = next * 25000;
      s.time_increment_ns = 17361;
      s.angle_min_rad = -0.75 * M_PI;  // the UST-10LX's steps 0..1080
      s.angle_increment_rad = 2.0 * M_PI / 1440.0;
      s.ranges_m.assign(1081, 1.5f);
      s.ranges_m[0] = 0.0f;  // no return
      ++next;
      out.push_back(s);
    }
    return out;
  };
  EmulatedClock clock;
  clock.start_ms = 16777215 - 10;  // wraps 10 ms in
  ScipDevice dev(source, clock, 0);
  std::string out;
  const auto say = [&](const std::string& cmd, int64_t t) {
    out.clear();
    dev.receive(reinterpret_cast<const uint8_t*>(cmd.data()), cmd.size(), t, &out);
    return only<scip::Reply>(decodeAll<scip::Decoder, scip::Event>(out));
  };
  EXPECT_EQ(say("PP\n", 0).at(0).params.at("AMAX"), "1080");
  EXPECT_EQ(say("BM\n", 0).at(0).status, "00");
  EXPECT_EQ(say("BM\n", 0).at(0).status, "02");
  EXPECT_EQ(say("TM1\n", 0).at(0).status, "03");
  EXPECT_EQ(say("TM0\n", 0).at(0).status, "00");
  EXPECT_EQ(*say("TM1\n", 5000).at(0).time_ms, 16777215u - 5);
  EXPECT_EQ(say("TM2\n", 0).at(0).status, "00");
  EXPECT_EQ(say("XX\n", 0).at(0).status, "0E");
  EXPECT_EQ(say("MD0000200001000\n", 0).at(0).status, "04");
  EXPECT_EQ(say("MD0100005001000\n", 0).at(0).status, "05");
  EXPECT_EQ(say("MD00001080010\n", 0).at(0).status, "0C");
  EXPECT_EQ(say("ME0000108000002;ab\n", 0).at(0).status, "00");
  out.clear();
  dev.advance(100000, &out);  // four scans done; the stream asked for two
  const auto scans = only<scip::ScanData>(decodeAll<scip::Decoder, scip::Event>(out));
  ASSERT_EQ(scans.size(), 2u);
  EXPECT_EQ(scans[0].remaining, 1);
  EXPECT_EQ(scans[1].remaining, 0);
  EXPECT_EQ(scans[0].ranges_mm[0], 1u);  // no return: an error code below DMIN
  EXPECT_EQ(scans[0].ranges_mm[1], 1500u);
  EXPECT_EQ(scans[0].intensities.size(), 1081u);
  EXPECT_EQ(scans[1].time_ms, 14u);  // across the wrap: 16777215 - 10 + 25 - 2^24
}

// ---- YDLIDAR X4 ----------------------------------------------------------------------------

// Two samples by hand after the manual's layout: FSA 10°, LSA 11°, S1 1000 mm, S2 none.
// CS = 55AA ^ 0501 ^ 0FA0 ^ 0000 ^ 0200 ^ 0581 = 588A.
const std::string kX4Packet("\xAA\x55\x00\x02\x01\x05\x81\x05\x8A\x58\xA0\x0F\x00\x00", 14);

TEST(Ydlidar, PacketLayoutCheckCodeAndAngleCorrection) {
  const auto packets =
      only<ydlidar::Packet>(decodeAll<ydlidar::Decoder, ydlidar::Event>(kX4Packet));
  ASSERT_EQ(packets.size(), 1u);
  ASSERT_EQ(packets[0].samples.size(), 2u);
  EXPECT_EQ(packets[0].samples[0].distance_mm, 1000.0);
  EXPECT_EQ(packets[0].samples[0].raw_angle_deg, 10.0);
  const double corr = std::atan(21.8 * (155.3 - 1000.0) / (155.3 * 1000.0)) * 180.0 / M_PI;
  EXPECT_NEAR(corr, -6.7622, 1e-4);
  EXPECT_NEAR(packets[0].samples[0].angle_deg, 10.0 + corr, 1e-9);
  EXPECT_EQ(packets[0].samples[1].angle_deg, 11.0);  // no return: no correction
  EXPECT_EQ(ydlidar::encodePacket(false, 10.0, 11.0, {1000.0, 0.0}), kX4Packet);
  EXPECT_EQ(ydlidar::angleCorrectionDeg(155.3), 0.0);
  EXPECT_NEAR(ydlidar::angleCorrectionDeg(100.0), 4.4387, 1e-4);
  EXPECT_EQ(ydlidar::angleCorrectionDeg(0.0), 0.0);
}

TEST(Ydlidar, Replies) {
  const std::string info = ydlidar::encodeInfo(6, 1, 5, 1, "ABCDEFGHIJKLMNOP");
  EXPECT_EQ(info.substr(0, 7), std::string("\xA5\x5A\x14\x00\x00\x00\x04", 7));
  const std::string scan = ydlidar::encodeDescriptor(5, 1, ydlidar::kTypeScan);
  EXPECT_EQ(scan, std::string("\xA5\x5A\x05\x00\x00\x40\x81", 7));  // the manual's
  const auto events = decodeAll<ydlidar::Decoder, ydlidar::Event>(
      info + ydlidar::encodeHealth(2, 0x0102) + scan + kX4Packet);
  ASSERT_EQ(events.size(), 4u);
  EXPECT_EQ(std::get<ydlidar::DeviceInfo>(events[0]).model, 6);
  EXPECT_EQ(std::get<ydlidar::Health>(events[1]).error_code, 0x0102);
  EXPECT_TRUE(std::holds_alternative<ydlidar::ScanStart>(events[2]));
}

std::string x4Stream() {
  std::string s = ydlidar::encodeDescriptor(5, 1, ydlidar::kTypeScan);
  s += ydlidar::encodePacket(true, 359.9, 359.9, {800.0});
  for (int k = 0; k < 6; ++k) {
    s += ydlidar::encodePacket(false, k * 10.0, k * 10.0 + 9.0, {500.0, 600.0, 0.0, 1200.25});
  }
  return s;
}

TEST(Ydlidar, SameEventsSplitAtEveryPositionAndGarbageBetween) {
  const std::string s = x4Stream();
  const size_t n = decodeAll<ydlidar::Decoder, ydlidar::Event>(s).size();
  ASSERT_EQ(n, 8u);
  for (size_t cut = 0; cut <= s.size(); ++cut) {
    ydlidar::Decoder d;
    std::vector<ydlidar::Event> out;
    d.feed(reinterpret_cast<const uint8_t*>(s.data()), cut, &out);
    d.feed(reinterpret_cast<const uint8_t*>(s.data()) + cut, s.size() - cut, &out);
    ASSERT_EQ(out.size(), n) << "cut at " << cut;
  }
  // False syncs (AA without 55, A5 without 5A, AA 55 with an impossible header) and junk.
  const std::string junk("\xAA\x01\xA5\x00\xAA\x55\x01\x05\x00\x00\x13", 11);
  ydlidar::Decoder d;
  const auto events = decodeAll<ydlidar::Decoder, ydlidar::Event>(junk + s + junk + s, &d);
  EXPECT_EQ(only<ydlidar::Packet>(events).size(), 14u);
  EXPECT_GE(d.counters().resyncs, 2);
}

TEST(Ydlidar, BadCheckCodeDropsThatPacketOnly) {
  std::string bad = kX4Packet;
  bad[11] ^= 0x01;  // a distance bit
  ydlidar::Decoder d;
  const auto events = decodeAll<ydlidar::Decoder, ydlidar::Event>(bad + kX4Packet, &d);
  EXPECT_EQ(only<ydlidar::Packet>(events).size(), 1u);
  EXPECT_EQ(d.counters().checksum_errors, 1);
}

// ---- RPLIDAR -------------------------------------------------------------------------------

// The X4's turns as the session sees them: 12 packets of 60 samples per turn at `rate_hz`;
// the packets of turns [burst_from, burst_to) all reach the host at the end of the last one (a
// stall, then the backlog, each packet read on its own: the harshest timing).
// Returns the error the session throws, or "" after `turns` turns.
std::string feedX4Turns(double rate_hz, int turns, int burst_from = -1, int burst_to = -1) {
  LidarConfig x4;
  x4.model = "YDLIDAR-X4";
  x4.beam_count = 714;
  x4.angle_min_deg = -180.0;
  x4.angle_increment_deg = 360.0 / 714;
  x4.scan_rate_hz = 7.0;
  x4.steps_per_revolution = 714;
  x4.range_min_m = 0.12;
  x4.range_max_m = 10.0;
  auto session = makeLidarSession(DeviceProtocol::kYdlidarX4, x4, SessionOptions{});
  std::vector<Scan2D> scans;
  std::vector<std::string> errors;
  const int64_t t0 = 1'000'000'000;
  const int64_t burst_at = t0 + static_cast<int64_t>(burst_to / rate_hz * 1e6);
  try {
    for (int t = 0; t < turns; ++t) {
      // As the device sends them: a one-sample packet at the zero position, then the turn.
      for (int p = -1; p < 12; ++p) {
        const std::string bytes =
            p < 0 ? ydlidar::encodePacket(true, 0.0, 0.0, {2000.0})
                  : ydlidar::encodePacket(false, p * 30.0 + 0.5, p * 30.0 + 30.0,
                                          std::vector<double>(60, 2000.0));
        int64_t arrival = t0 + static_cast<int64_t>((t + (p + 1) / 12.0) / rate_hz * 1e6);
        if (t >= burst_from && t < burst_to) arrival = burst_at;
        std::vector<Scan2D> got;
        session->onBytes(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size(), arrival,
                         &got, &errors);
        scans.insert(scans.end(), got.begin(), got.end());
      }
    }
  } catch (const std::exception& e) {
    return e.what();
  }
  EXPECT_GT(scans.size(), size_t(turns - 3));
  return "";
}

// Another device or motor setting stops the driver; a host stall that makes a turn or two
// look fast does not.
TEST(X4Session, ScanRateFarFromTheRigsStopsTheDriverAHostStallDoesNot) {
  EXPECT_EQ(feedX4Turns(7.0, 40), "");
  EXPECT_EQ(feedX4Turns(7.0, 40, 10, 13), "");
  const std::string e = feedX4Turns(12.0, 40);
  EXPECT_NE(e.find("scan rate: the rig file says 7 Hz, the YDLIDAR-X4 turns at 12"),
            std::string::npos)
      << e;
}

// Turns of an X4 as the session makes them: the stream starts inside a turn (dropped), each
// zero packet (at the index mark) opens a turn of every sample until the next, and a zero
// packet lost to a bad check code loses its two turns, never makes a scan of both.
TEST(X4Session, OneScanPerTurnFromZeroPacketToZeroPacket) {
  LidarConfig x4;
  x4.model = "YDLIDAR-X4";
  x4.beam_count = 714;
  x4.steps_per_revolution = 714;
  x4.range_min_m = 0.12;
  x4.range_max_m = 10.0;
  x4.scan_rate_hz = 7.0;
  std::string bytes = ydlidar::encodeDescriptor(5, 1, ydlidar::kTypeScan);
  // Part of a turn, then 6 turns from 348 deg: the zero packet, then 12 packets of 30 samples.
  bytes += ydlidar::encodePacket(false, 200.0, 347.5, std::vector<double>(40, 1500.0));
  for (int t = 0; t < 6; ++t) {
    std::string zero = ydlidar::encodePacket(true, 348.0, 348.0, {1000.0});
    if (t == 3) zero[8] ^= 0x01;  // a bad check code: the zero packet is dropped
    bytes += zero;
    for (int p = 0; p < 12; ++p) {
      const double a = 348.5 + p * 30.0;
      bytes += ydlidar::encodePacket(false, a, a + 29.0, std::vector<double>(30, 2000.0 + t));
    }
  }
  bytes += ydlidar::encodePacket(true, 348.0, 348.0, {1000.0});
  auto session = makeLidarSession(DeviceProtocol::kYdlidarX4, x4, {ScanTime::kStream, 0});
  std::vector<Scan2D> scans;
  std::vector<std::string> errors;
  session->onBytes(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size(), -1, &scans,
                   &errors);
  session->finish(&scans, &errors);
  ASSERT_EQ(scans.size(), 4u);  // turns 0, 1, 4, 5; turns 2 + 3 (no zero packet between) lost
  const float expected_range[4] = {2.0f, 2.001f, 2.004f, 2.005f};
  for (size_t k = 0; k < scans.size(); ++k) {
    const Scan2D& s = scans[k];
    ASSERT_EQ(s.ranges_m.size(), 1u + 12 * 30) << k;  // the zero packet's sample and the turn's
    ASSERT_EQ(s.angles_rad.size(), s.ranges_m.size());
    EXPECT_FLOAT_EQ(s.ranges_m[0], 1.0f);
    EXPECT_NEAR(s.ranges_m[1], expected_range[k], 1e-6);
    EXPECT_TRUE(validateScan(s, x4.beam_count).empty());
    for (size_t i = 1; i < s.ranges_m.size(); ++i) EXPECT_GT(s.rayUtime(i), s.rayUtime(i - 1));
  }
  std::map<std::string, int64_t> c;
  for (const auto& [name, value] : session->sessionCounters()) c[name] = value;
  EXPECT_EQ(c["turns"], 4);
  EXPECT_EQ(c["partial_turns"], 1);
  EXPECT_EQ(c["broken_turns"], 1);
  EXPECT_EQ(session->decoderCounters().checksum_errors, 1);
}

// RPLIDAR: a turn from one sample with S = 1 to the next, with the samples' qualities.
TEST(RplidarSession, OneScanPerTurnFromStartFlagToStartFlag) {
  LidarConfig a1;
  a1.model = "RPLIDAR-A1";
  a1.steps_per_revolution = 360;
  a1.range_min_m = 0.15;
  a1.range_max_m = 12.0;
  a1.scan_rate_hz = 5.5;
  std::string bytes = rplidar::encodeDescriptor(5, 1, rplidar::kTypeScan);
  for (int i = 100; i < 360; ++i) bytes += rplidar::encodeSample(false, 10, i, 1000.0);
  for (int t = 0; t < 3; ++t) {
    for (int i = 0; i < 360; ++i)
      bytes += rplidar::encodeSample(i == 0, i % 2 ? 47 : 0, i + 0.5, i % 2 ? 1000.0 + t : 0.0);
  }
  bytes += rplidar::encodeSample(true, 47, 0.25, 1000.0);
  auto session = makeLidarSession(DeviceProtocol::kRplidar, a1, {ScanTime::kStream, 0});
  std::vector<Scan2D> scans;
  std::vector<std::string> errors;
  session->onBytes(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size(), -1, &scans,
                   &errors);
  ASSERT_EQ(scans.size(), 3u);
  for (size_t k = 0; k < 3; ++k) {
    ASSERT_EQ(scans[k].ranges_m.size(), 360u);
    ASSERT_EQ(scans[k].intensities.size(), 360u);
    EXPECT_NEAR(scans[k].angles_rad[0], 0.5 * M_PI / 180.0, 1e-6);
    EXPECT_NEAR(scans[k].angles_rad[359], (359.5 - 360.0) * M_PI / 180.0, 1e-6);
    EXPECT_EQ(scans[k].ranges_m[0], 0.0f);
    EXPECT_NEAR(scans[k].ranges_m[1], 1.0 + 0.001 * k, 1e-6);
    EXPECT_EQ(scans[k].intensities[1], 47.0f);
  }
}

TEST(Rplidar, RequestsDescriptorsAndSampleBits) {
  EXPECT_EQ(rplidar::request(rplidar::kCmdScan), std::string("\xA5\x20", 2));
  // SET_MOTOR_PWM 660 with its checksum (A5 ^ F0 ^ 02 ^ 94 ^ 02 = C1).
  EXPECT_EQ(rplidar::request(rplidar::kCmdMotorPwm, std::string("\x94\x02", 2)),
            std::string("\xA5\xF0\x02\x94\x02\xC1", 6));
  EXPECT_EQ(rplidar::encodeDescriptor(5, 1, rplidar::kTypeScan),
            std::string("\xA5\x5A\x05\x00\x00\x40\x81", 7));
  // quality 15, S = 1, 90.0° (q6 5760), 1234.5 mm (q2 4938).
  const std::string sample("\x3D\x01\x2D\x4A\x13", 5);
  EXPECT_EQ(rplidar::encodeSample(true, 15, 90.0, 1234.5), sample);
  const auto events = decodeAll<rplidar::Decoder, rplidar::Event>(
      rplidar::encodeDescriptor(5, 1, rplidar::kTypeScan) + sample);
  const auto batches = only<rplidar::Samples>(events);
  ASSERT_EQ(batches.size(), 1u);
  const rplidar::Sample& s = batches[0].samples.at(0);
  EXPECT_TRUE(s.start);
  EXPECT_EQ(s.quality, 15);
  EXPECT_EQ(s.angle_deg, 90.0);
  EXPECT_EQ(s.distance_mm, 1234.5);
}

TEST(Rplidar, InfoAndHealth) {
  const auto events = decodeAll<rplidar::Decoder, rplidar::Event>(
      rplidar::encodeInfo(0x18, 1, 29, 7, "0123456789abcdef") + rplidar::encodeHealth(1, 0x8001));
  ASSERT_EQ(events.size(), 2u);
  const auto& info = std::get<rplidar::DeviceInfo>(events[0]);
  EXPECT_EQ(info.model, 0x18);
  EXPECT_EQ(info.firmware_major, 1);
  EXPECT_EQ(info.firmware_minor, 29);
  EXPECT_EQ(std::get<rplidar::Health>(events[1]).error_code, 0x8001);
}

std::string rplidarStream() {
  std::string s = rplidar::encodeDescriptor(5, 1, rplidar::kTypeScan);
  for (int k = 0; k < 40; ++k) s += rplidar::encodeSample(k % 20 == 0, 40, k * 9.0, 100.0 * k);
  return s;
}

size_t sampleCount(const std::vector<rplidar::Event>& events) {
  size_t n = 0;
  for (const auto& b : only<rplidar::Samples>(events)) n += b.samples.size();
  return n;
}

TEST(Rplidar, SameSamplesSplitAtEveryPositionAndResyncAfterJunk) {
  const std::string s = rplidarStream();
  for (size_t cut = 0; cut <= s.size(); ++cut) {
    rplidar::Decoder d;
    std::vector<rplidar::Event> out;
    d.feed(reinterpret_cast<const uint8_t*>(s.data()), cut, &out);
    d.feed(reinterpret_cast<const uint8_t*>(s.data()) + cut, s.size() - cut, &out);
    ASSERT_EQ(sampleCount(out), 40u) << "cut at " << cut;
  }
  // Bytes whose start or check bits are wrong between samples: skipped, counted.
  std::string mixed = s;
  mixed.insert(7 + 5 * 10, std::string("\x03\x00\x00", 3));  // S == !S, C = 0
  rplidar::Decoder d;
  const auto events = decodeAll<rplidar::Decoder, rplidar::Event>(mixed, &d);
  EXPECT_EQ(sampleCount(events), 40u);
  EXPECT_GE(d.counters().resyncs, 1);
  EXPECT_EQ(d.counters().discarded_bytes, 3);
}

}  // namespace
}  // namespace sweepmap
