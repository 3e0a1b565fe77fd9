// The wheel board protocol (drivers/protocols/wheelboard.hpp, our own): the CRC's check
// value, a frame laid out by hand from the specification, speed commands, sequence gaps,
// the same bytes split at every position, garbage and a bad CRC.
#include <gtest/gtest.h>

#include <string>

#include "drivers/protocols/wheelboard.hpp"

namespace sweepmap {
namespace {

std::vector<wheelboard::Event> decode(const std::string& s, wheelboard::Decoder* d) {
  std::vector<wheelboard::Event> out;
  d->feed(reinterpret_cast<const uint8_t*>(s.data()), s.size(), &out);
  return out;
}

TEST(Wheelboard, CrcCheckValue) {
  const std::string nine = "123456789";
  EXPECT_EQ(wheelboard::crc16(reinterpret_cast<const uint8_t*>(nine.data()), 9), 0x29B1);
}

TEST(Wheelboard, TicksFrameAsTheSpecificationLaysItOut) {
  // seq 7, time 0x00012345 us, left -1, right 1000, flags: watchdog stop.
  std::string f("\xA5\x5B\x01\x0E\x07\x00\x45\x23\x01\x00\xFF\xFF\xFF\xFF\xE8\x03\x00\x00\x01\x00",
                20);
  const uint16_t crc = wheelboard::crc16(reinterpret_cast<const uint8_t*>(f.data()) + 2, 18);
  f.push_back(static_cast<char>(crc & 0xff));
  f.push_back(static_cast<char>(crc >> 8));
  wheelboard::Ticks t;
  t.seq = 7;
  t.time_us = 0x12345;
  t.left = -1;
  t.right = 1000;
  t.flags = wheelboard::kFlagWatchdog;
  EXPECT_EQ(wheelboard::encodeTicks(t), f);
  wheelboard::Decoder d;
  const auto events = decode(f, &d);
  ASSERT_EQ(events.size(), 1u);
  const auto& got = std::get<wheelboard::Ticks>(events[0]);
  EXPECT_EQ(got.time_us, 0x12345u);
  EXPECT_EQ(got.left, -1);
  EXPECT_EQ(got.right, 1000);
  EXPECT_EQ(got.flags, wheelboard::kFlagWatchdog);
}

TEST(Wheelboard, SpeedCommandsRoundAndClamp) {
  wheelboard::Decoder d;
  const auto events =
      decode(wheelboard::encodeSpeed(3, 0.2004, -1.5) + wheelboard::encodeSpeed(4, 100.0, 0.0), &d);
  ASSERT_EQ(events.size(), 2u);
  EXPECT_DOUBLE_EQ(std::get<wheelboard::Speed>(events[0]).v_m_s, 0.2);
  EXPECT_DOUBLE_EQ(std::get<wheelboard::Speed>(events[0]).w_rad_s, -1.5);
  EXPECT_DOUBLE_EQ(std::get<wheelboard::Speed>(events[1]).v_m_s, 32.767);
}

std::string ticksStream(int first, int n) {
  std::string s;
  for (int k = first; k < first + n; ++k) {
    wheelboard::Ticks t;
    t.seq = static_cast<uint16_t>(k);
    t.time_us = 20000u * static_cast<uint32_t>(k);
    t.left = 13 * k;
    t.right = -11 * k;
    s += wheelboard::encodeTicks(t);
  }
  return s;
}

TEST(Wheelboard, SequenceGapsAcrossTheWrap) {
  wheelboard::Decoder d;
  decode(ticksStream(65530, 4) + ticksStream(65536 + 2, 3), &d);  // 65534, 65535, 0, 1 lost
  EXPECT_EQ(d.sequenceGaps(), 4);
  EXPECT_EQ(d.counters().packets, 7);
}

TEST(Wheelboard, SplitAtEveryPositionGarbageAndBadCrc) {
  const std::string s = ticksStream(0, 3) + wheelboard::encodeSpeed(9, 0.1, 0.2);
  for (size_t cut = 0; cut <= s.size(); ++cut) {
    wheelboard::Decoder d;
    std::vector<wheelboard::Event> out;
    d.feed(reinterpret_cast<const uint8_t*>(s.data()), cut, &out);
    d.feed(reinterpret_cast<const uint8_t*>(s.data()) + cut, s.size() - cut, &out);
    ASSERT_EQ(out.size(), 4u) << "cut at " << cut;
  }
  std::string bad = ticksStream(3, 1);
  bad[10] ^= 0x40;
  wheelboard::Decoder d;
  const auto events =
      decode("\xA5\x00junk\xA5\x5B\x77\xFF" + ticksStream(0, 3) + bad + ticksStream(4, 2), &d);
  int ticks = 0;
  for (const auto& e : events) ticks += std::holds_alternative<wheelboard::Ticks>(e);
  EXPECT_EQ(ticks, 5);
  EXPECT_EQ(d.counters().checksum_errors, 1);
  EXPECT_EQ(d.sequenceGaps(), 1);  // the dropped frame 3
  EXPECT_GE(d.counters().resyncs, 2);
}

}  // namespace
}  // namespace sweepmap
