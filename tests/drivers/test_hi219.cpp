// The HI219 decoder against the two example frames of HiPNUC's user manual (section 6.3.4:
// a frame of single data items and a 0x91 record, with the values the manual decodes), the
// CRC, the same bytes split at every position, garbage between frames, a bad CRC.
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <string>

#include "core/angles.hpp"
#include "drivers/protocols/hi219.hpp"

namespace sweepmap {
namespace {

std::string hex(const std::string& text) {
  std::istringstream in(text);
  std::string out, byte;
  while (in >> byte) out.push_back(static_cast<char>(std::stoi(byte, nullptr, 16)));
  return out;
}

// Manual 6.3.4.1: 90 (ID), A0, B0, C0, D0, F0 items; CRC 0x61FD.
const std::string kItems =
    hex("5A A5 23 00 FD 61 90 00 A0 55 02 3D 01 E2 02 B0 FE FF 17 00 44 00 C0 80 FF 60 FF 32 FF "
        "D0 64 F2 6C 0E BB 01 F0 00 00 00 00");
// Manual 6.3.4.2: one 0x91 record; CRC 0x516C.
const std::string kImusol =
    hex("5A A5 4C 00 6C 51 91 00 A0 3B 01 A8 02 97 BD BB 04 00 9C A0 65 3E A2 26 45 3F 5C E7 30 3F "
        "E2 D4 5A C2 E5 9D A0 C1 EB 23 EE C2 78 77 99 41 AB AA D1 C1 AB 2A 0A C2 8D E1 42 42 8F 1D "
        "A8 C1 1E 0C 36 C2 E6 E5 5A 3F C1 94 9E 3E B8 C0 9E BE BE DF 8D BE");

std::vector<hi219::Frame> frames(const std::string& s, hi219::Decoder* d = nullptr) {
  hi219::Decoder local;
  if (!d) d = &local;
  std::vector<hi219::Event> out;
  d->feed(reinterpret_cast<const uint8_t*>(s.data()), s.size(), &out);
  std::vector<hi219::Frame> f;
  for (const auto& e : out) {
    if (const auto* x = std::get_if<hi219::Frame>(&e)) f.push_back(*x);
  }
  return f;
}

TEST(Hi219, ManualFrameOfSingleItems) {
  // The manual's CRC of this frame, 0x61FD, over its first four bytes and the payload.
  const auto* b = reinterpret_cast<const uint8_t*>(kItems.data());
  EXPECT_EQ(hi219::crc16(b + 6, kItems.size() - 6, hi219::crc16(b, 4)), 0x61FD);
  const auto f = frames(kItems);
  ASSERT_EQ(f.size(), 1u);
  EXPECT_EQ(f[0].id, 0);
  // acc(G) 0.597 0.317 0.738; gyr(deg/s) -0.2 2.3 6.8; mag(uT) -12.8 -16.0 -20.6;
  // eul(R/P/Y) 36.92 -34.84 44.3.
  EXPECT_NEAR(f[0].accel_m_s2[0], 0.597 * hi219::kGravity, 1e-9);
  EXPECT_NEAR(f[0].accel_m_s2[2], 0.738 * hi219::kGravity, 1e-9);
  EXPECT_NEAR(f[0].gyro_rad_s[0], -0.2 * kDegToRad, 1e-12);
  EXPECT_NEAR(f[0].gyro_rad_s[2], 6.8 * kDegToRad, 1e-12);
  EXPECT_NEAR(f[0].mag_ut[2], -20.6, 1e-9);
  EXPECT_NEAR(f[0].rpy_rad[0], 36.92 * kDegToRad, 1e-12);
  EXPECT_NEAR(f[0].rpy_rad[1], -34.84 * kDegToRad, 1e-12);
  EXPECT_NEAR(f[0].rpy_rad[2], 44.3 * kDegToRad, 1e-12);
  EXPECT_TRUE(f[0].has_pressure);
  EXPECT_FALSE(f[0].has_time);
}

TEST(Hi219, ManualImusolRecord) {
  const auto f = frames(kImusol);
  ASSERT_EQ(f.size(), 1u);
  // timestamp 310205; acc 0.224 0.770 0.691; gyr -54.708 -20.077 -119.070;
  // mag 19.183 -26.208 -34.542; eul 48.720 -21.014 -45.512; quat 0.855 0.310 -0.310 -0.277.
  EXPECT_EQ(f[0].time_ms, 310205u);
  EXPECT_NEAR(f[0].accel_m_s2[1] / hi219::kGravity, 0.770, 5e-4);
  EXPECT_NEAR(f[0].gyro_rad_s[2] / kDegToRad, -119.070, 5e-4);
  EXPECT_NEAR(f[0].mag_ut[0], 19.183, 5e-4);
  EXPECT_NEAR(f[0].rpy_rad[0] / kDegToRad, 48.720, 5e-4);
  EXPECT_NEAR(f[0].rpy_rad[2] / kDegToRad, -45.512, 5e-4);
  EXPECT_NEAR(f[0].quat_wxyz[0], 0.855, 5e-4);
  EXPECT_NEAR(f[0].quat_wxyz[3], -0.277, 5e-4);
  // Our encoder makes the same bytes from the decoded values (the record's reserved bytes
  // aside), with a CRC the decoder accepts.
  const auto again = frames(hi219::encodeFrame(hi219::encodeImusol(f[0])));
  ASSERT_EQ(again.size(), 1u);
  EXPECT_EQ(again[0].time_ms, 310205u);
  EXPECT_NEAR(again[0].quat_wxyz[1], f[0].quat_wxyz[1], 1e-7);
}

TEST(Hi219, SplitAtEveryPositionGarbageAndBadCrc) {
  const std::string s = kItems + kImusol + kItems;
  for (size_t cut = 0; cut <= s.size(); ++cut) {
    hi219::Decoder d;
    std::vector<hi219::Event> out;
    d.feed(reinterpret_cast<const uint8_t*>(s.data()), cut, &out);
    d.feed(reinterpret_cast<const uint8_t*>(s.data()) + cut, s.size() - cut, &out);
    ASSERT_EQ(out.size(), 3u) << "cut at " << cut;
  }
  std::string bad = kImusol;
  bad[40] ^= 0x08;
  hi219::Decoder d;
  const auto f = frames("\x5A\x01junk\x5A\xA5\xFF\xFF" + bad + kItems + "\x13" + kImusol, &d);
  ASSERT_EQ(f.size(), 2u);  // the bad frame dropped, both good ones kept
  EXPECT_EQ(f[1].time_ms, 310205u);
  EXPECT_EQ(d.counters().checksum_errors, 1);
  EXPECT_GE(d.counters().resyncs, 2);
}

// A false 5A A5 whose length field runs past the end of the input (issue 22): once the input
// ends, the bytes held for it are searched again, so the good frames after it are decoded, and
// the false start is counted; the same false start before good frames that complete it fails
// its CRC and is searched again at once. Nothing is lost either way.
TEST(Hi219, FalseHeaderLosesNoGoodFrameAfterIt) {
  const std::string false_header = hex("5A A5 F0 01 12 34");  // 496 bytes of payload announced
  for (const std::string& tail : {std::string(), std::string(600, '\x00')}) {
    const std::string s = kItems + false_header + kImusol + kItems + tail;
    hi219::Decoder d;
    std::vector<hi219::Event> out;
    d.feed(reinterpret_cast<const uint8_t*>(s.data()), s.size(), &out);
    d.finish(&out);
    std::vector<hi219::Frame> f;
    std::vector<DecodeError> errors;
    for (const auto& e : out) {
      if (const auto* x = std::get_if<hi219::Frame>(&e)) f.push_back(*x);
      if (const auto* x = std::get_if<DecodeError>(&e)) errors.push_back(*x);
    }
    ASSERT_EQ(f.size(), 3u) << "tail " << tail.size();
    EXPECT_EQ(f[1].time_ms, 310205u);
    EXPECT_EQ(f[1].offset, static_cast<int64_t>(kItems.size() + false_header.size()));
    EXPECT_GE(d.counters().resyncs, 1);
    ASSERT_FALSE(errors.empty());
    EXPECT_EQ(errors.front().offset, static_cast<int64_t>(kItems.size()));  // the false start
    if (tail.empty()) {
      EXPECT_EQ(d.counters().checksum_errors, 0);  // never completed: skipped
      EXPECT_EQ(d.counters().discarded_bytes, static_cast<int64_t>(false_header.size()));
    } else {
      EXPECT_EQ(d.counters().checksum_errors, 1);  // completed by what followed: a bad CRC
    }
  }
  // A false header at the very end, after good frames: they are out before it, it is reported.
  const std::string s = kImusol + kItems + false_header;
  hi219::Decoder d;
  std::vector<hi219::Event> out;
  d.feed(reinterpret_cast<const uint8_t*>(s.data()), s.size(), &out);
  EXPECT_EQ(out.size(), 2u);
  d.finish(&out);
  ASSERT_EQ(out.size(), 3u);
  ASSERT_TRUE(std::holds_alternative<DecodeError>(out[2]));
  EXPECT_EQ(std::get<DecodeError>(out[2]).offset, static_cast<int64_t>(s.size() - 6));
  EXPECT_EQ(d.counters().discarded_bytes, 6);
  EXPECT_EQ(d.counters().resyncs, 1);
}

}  // namespace
}  // namespace sweepmap
