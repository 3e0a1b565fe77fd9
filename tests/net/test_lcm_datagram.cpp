// LcmReassembler against well-formed traffic (as liblcm sends it) and against every malformed
// datagram we know of: the findings of issue 21 and the limits of the wire format.
#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <random>

#include "net/lcm_datagram.hpp"

namespace sweepmap::net {
namespace {

using Bytes = std::vector<uint8_t>;

Bytes payload(size_t n, uint8_t seed = 1) {
  Bytes b(n);
  for (size_t i = 0; i < n; ++i) b[i] = static_cast<uint8_t>(seed + i * 31);
  return b;
}

void putU32(Bytes& b, size_t at, uint32_t v) {
  for (int i = 0; i < 4; ++i) b[at + i] = static_cast<uint8_t>(v >> (24 - 8 * i));
}

// An LC03 datagram with the given header fields, followed by `tail`.
Bytes fragment(uint32_t seqno, uint32_t size, uint32_t offset, uint16_t number, uint16_t count,
               const Bytes& tail) {
  Bytes b(20);
  putU32(b, 0, kLcmMagicLong);
  putU32(b, 4, seqno);
  putU32(b, 8, size);
  putU32(b, 12, offset);
  b[16] = static_cast<uint8_t>(number >> 8);
  b[17] = static_cast<uint8_t>(number);
  b[18] = static_cast<uint8_t>(count >> 8);
  b[19] = static_cast<uint8_t>(count);
  b.insert(b.end(), tail.begin(), tail.end());
  return b;
}

Bytes channelThen(const std::string& channel, const Bytes& data) {
  Bytes b(channel.begin(), channel.end());
  b.push_back(0);
  b.insert(b.end(), data.begin(), data.end());
  return b;
}

constexpr SenderId kAlice{0x7f000001, 40000};
constexpr SenderId kMallory{0x7f000002, 40001};

uint64_t refused(const LcmReassembler& r, Refusal why) {
  return r.counters().refused[static_cast<size_t>(why)];
}

std::optional<LcmMessage> feed(LcmReassembler& r, const Bytes& d, SenderId s = kAlice,
                               int64_t now = 0) {
  return r.feed(d.data(), d.size(), s, now);
}

TEST(LcmDatagram, ShortMessageHasLcmsLayoutAndRoundTrips) {
  const Bytes data = payload(100);
  const auto datagrams = encodeLcmDatagrams("LIDAR_SCAN", data.data(), data.size(), 7);
  ASSERT_EQ(datagrams.size(), 1u);
  const Bytes& d = datagrams[0];
  ASSERT_EQ(d.size(), 8u + 11u + 100u);
  EXPECT_EQ(std::string(d.begin(), d.begin() + 4), "LC02");
  EXPECT_EQ(d[7], 7);
  EXPECT_EQ(d[8 + 10], 0);  // the channel's NUL
  LcmReassembler r;
  const auto m = feed(r, d);
  ASSERT_TRUE(m);
  EXPECT_EQ(m->channel, "LIDAR_SCAN");
  EXPECT_EQ(m->data, data);
  EXPECT_EQ(m->seqno, 7u);
}

TEST(LcmDatagram, FragmentsAsLiblcmCutsThemAndReassemblesInAnyOrder) {
  const Bytes data = payload(200000, 3);
  auto datagrams = encodeLcmDatagrams("SWEEP_CLOUD", data.data(), data.size(), 9);
  // liblcm 1.3.1: 65487 bytes after each header, the channel inside fragment 0.
  ASSERT_EQ(datagrams.size(), 4u);
  EXPECT_EQ(datagrams[0].size(), 20u + 65487u);
  EXPECT_EQ(datagrams[1].size(), 20u + 65487u);
  EXPECT_EQ(datagrams[3].size(), 20u + (200000u + 12u) - 3u * 65487u);
  std::mt19937 rng(5);
  for (int trial = 0; trial < 5; ++trial) {
    LcmReassembler r;
    std::shuffle(datagrams.begin(), datagrams.end(), rng);
    std::optional<LcmMessage> m;
    for (size_t i = 0; i < datagrams.size(); ++i) {
      m = feed(r, datagrams[i]);
      EXPECT_EQ(m.has_value(), i + 1 == datagrams.size());
    }
    ASSERT_TRUE(m);
    EXPECT_EQ(m->channel, "SWEEP_CLOUD");
    EXPECT_EQ(m->data, data);
    EXPECT_EQ(r.pendingBytes(), 0u);
    EXPECT_EQ(r.counters().refusedTotal(), 0u);
  }
}

TEST(LcmDatagram, TwoSendersInterleavedStayApart) {
  const Bytes a = payload(150000, 1), b = payload(150000, 2);
  const auto da = encodeLcmDatagrams("A", a.data(), a.size(), 1);
  const auto db = encodeLcmDatagrams("B", b.data(), b.size(), 1);  // same seqno, other sender
  LcmReassembler r;
  std::vector<LcmMessage> got;
  for (size_t i = 0; i < da.size(); ++i) {
    if (auto m = feed(r, da[i], kAlice)) got.push_back(*m);
    if (auto m = feed(r, db[i], kMallory)) got.push_back(*m);
  }
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].data, a);
  EXPECT_EQ(got[1].data, b);
}

// Issue 21: the 131-byte datagram that crashes every liblcm 1.3.1 receiver (fragment 0 on a
// subscribed channel, offset 0xFFFFFFFF), and the same offset on a later fragment.
TEST(LcmDatagram, FragmentOffsetThatWrapsIn32BitsIsRefused) {
  const Bytes d = fragment(1, 100000, 0xFFFFFFFFu, 0, 2, channelThen("MAP_SAVE", payload(102)));
  ASSERT_EQ(d.size(), 131u);
  LcmReassembler r;
  EXPECT_FALSE(feed(r, d));
  EXPECT_FALSE(feed(r, fragment(1, 100000, 0xFFFFFFFFu, 1, 2, payload(111))));
  EXPECT_EQ(refused(r, Refusal::kFragmentOutOfRange), 2u);
  EXPECT_EQ(r.pendingBytes(), 0u);
  // Also after a good fragment 0 of the same message.
  const Bytes first = fragment(2, 100000, 0, 0, 2, channelThen("MAP_SAVE", payload(1000)));
  EXPECT_FALSE(feed(r, first));
  EXPECT_FALSE(feed(r, fragment(2, 100000, 0xFFFFFF00u, 1, 2, payload(300))));
  EXPECT_EQ(refused(r, Refusal::kFragmentOutOfRange), 3u);
}

TEST(LcmDatagram, ChannelWithoutNulOrTooLongOrNotPrintableIsRefused) {
  LcmReassembler r;
  Bytes d(8);
  putU32(d, 0, kLcmMagicShort);
  for (char c : std::string("LIDAR_SCAN")) d.push_back(static_cast<uint8_t>(c));
  EXPECT_FALSE(feed(r, d));
  EXPECT_EQ(refused(r, Refusal::kChannelUnterminated), 1u);

  Bytes longer(8);
  putU32(longer, 0, kLcmMagicShort);
  const Bytes name = channelThen(std::string(64, 'X'), payload(4));
  longer.insert(longer.end(), name.begin(), name.end());
  EXPECT_FALSE(feed(r, longer));
  EXPECT_EQ(refused(r, Refusal::kChannelTooLong), 1u);

  Bytes odd(8);
  putU32(odd, 0, kLcmMagicShort);
  const Bytes bad = channelThen("EVIL\nNAME", payload(4));
  odd.insert(odd.end(), bad.begin(), bad.end());
  EXPECT_FALSE(feed(r, odd));
  EXPECT_EQ(refused(r, Refusal::kChannelInvalid), 1u);
  // The longest legal name passes.
  const Bytes data = payload(10);
  const auto ok = encodeLcmDatagrams(std::string(63, 'C'), data.data(), data.size(), 0);
  EXPECT_TRUE(feed(r, ok[0]));
}

TEST(LcmDatagram, HeadersShorterThanTheyClaimAreRefused) {
  LcmReassembler r;
  for (size_t n = 0; n < 20; ++n) {
    Bytes d = fragment(1, 10, 0, 0, 1, channelThen("C", payload(10)));
    d.resize(n);
    EXPECT_FALSE(feed(r, d)) << n;
  }
  EXPECT_EQ(r.counters().refusedTotal(), 20u);
  EXPECT_EQ(r.counters().messages, 0u);
  EXPECT_FALSE(feed(r, Bytes{'X', 'X', 'X', 'X', 0, 0, 0, 0}));
  EXPECT_EQ(refused(r, Refusal::kBadMagic), 1u);
}

TEST(LcmDatagram, DeclaredSizesAndCountsAreBounded) {
  ReassemblyLimits limits;
  limits.max_message_bytes = 1 << 20;
  LcmReassembler r(limits);
  EXPECT_FALSE(feed(r, fragment(1, (1 << 20) + 1, 0, 0, 17, channelThen("C", payload(10)))));
  EXPECT_EQ(refused(r, Refusal::kMessageTooLarge), 1u);
  EXPECT_FALSE(feed(r, fragment(1, 1000, 0, 0, 0, channelThen("C", payload(10)))));
  EXPECT_FALSE(feed(r, fragment(1, 1000, 10, 5, 5, payload(10))));
  EXPECT_FALSE(feed(r, fragment(1, 10, 0, 0, 12, channelThen("C", payload(10)))));
  EXPECT_EQ(refused(r, Refusal::kBadFragmentCount), 3u);
  EXPECT_EQ(r.pendingBytes(), 0u);
}

TEST(LcmDatagram, DuplicateMismatchedAndIncompleteFragmentsNeverCompleteAMessage) {
  LcmReassembler r;
  const Bytes f0 = fragment(4, 20, 0, 0, 2, channelThen("C", payload(10)));
  EXPECT_FALSE(feed(r, f0));
  EXPECT_FALSE(feed(r, f0));
  EXPECT_EQ(refused(r, Refusal::kDuplicateFragment), 1u);
  EXPECT_FALSE(feed(r, fragment(4, 30, 10, 1, 2, payload(10))));  // another size
  EXPECT_EQ(refused(r, Refusal::kFragmentMismatch), 1u);
  EXPECT_EQ(r.pendingBytes(), 0u);
  // Both fragments arrive but leave bytes uncovered.
  EXPECT_FALSE(feed(r, fragment(5, 20, 0, 0, 2, channelThen("C", payload(5)))));
  EXPECT_FALSE(feed(r, fragment(5, 20, 15, 1, 2, payload(5))));
  EXPECT_EQ(refused(r, Refusal::kIncomplete), 1u);
  // Fragment 0 (the channel) never came.
  EXPECT_FALSE(feed(r, fragment(6, 20, 0, 1, 2, payload(20))));
  EXPECT_EQ(r.pendingMessages(), 1u);
}

TEST(LcmDatagram, UnfinishedMessagesExpire) {
  ReassemblyLimits limits;
  limits.fragment_timeout_us = 1000;
  LcmReassembler r(limits);
  EXPECT_FALSE(feed(r, fragment(1, 100000, 0, 0, 2, channelThen("C", payload(65000))), kAlice, 0));
  EXPECT_GE(r.pendingBytes(), 65000u);
  const Bytes data = payload(10);
  EXPECT_TRUE(feed(r, encodeLcmDatagrams("D", data.data(), data.size(), 2)[0], kAlice, 5000));
  EXPECT_EQ(r.pendingBytes(), 0u);
  EXPECT_EQ(refused(r, Refusal::kTimedOut), 1u);
}

// Spoofed senders each opening a large message: memory stays within the bounds, and a sender
// with a legitimate message still gets it through.
TEST(LcmDatagram, MemoryIsBoundedPerSenderAndInAll) {
  ReassemblyLimits limits;
  limits.max_pending_bytes = 1u << 20;
  limits.max_pending_bytes_per_sender = 300000;
  limits.max_senders = 16;
  LcmReassembler r(limits);
  for (uint32_t i = 0; i < 1000; ++i) {
    const SenderId s{0x0a000000u + i % 40, static_cast<uint16_t>(1000 + i)};
    feed(r, fragment(i, 3u << 20, 0, 0, 100, channelThen("C", payload(60000))), s, i);
    ASSERT_LE(r.pendingBytes(), limits.max_pending_bytes);
    ASSERT_LE(r.pendingMessages(), limits.max_senders * limits.max_pending_per_sender);
  }
  for (uint32_t seqno = 0; seqno < 100; ++seqno) {
    feed(r, fragment(seqno, 1u << 20, 0, 0, 20, channelThen("C", payload(60000))), kMallory, 2000);
    ASSERT_LE(r.pendingBytes(), limits.max_pending_bytes);
  }
  const Bytes data = payload(150000);
  std::optional<LcmMessage> m;
  for (const Bytes& d : encodeLcmDatagrams("GOOD", data.data(), data.size(), 1)) {
    m = feed(r, d, kAlice, 3000);
  }
  ASSERT_TRUE(m);
  EXPECT_EQ(m->data, data);
}

// Random mutations of valid traffic: nothing crashes (the fuzz target goes much further), and
// whatever completes is exactly what some sender sent or is refused.
TEST(LcmDatagram, MutatedTrafficNeverCrashesOrGrows) {
  std::mt19937 rng(11);
  LcmReassembler r;
  const Bytes data = payload(140000);
  const auto good = encodeLcmDatagrams("SWEEP_CLOUD", data.data(), data.size(), 3);
  for (int i = 0; i < 5000; ++i) {
    Bytes d = good[rng() % good.size()];
    const int edits = 1 + static_cast<int>(rng() % 4);
    for (int e = 0; e < edits; ++e) {
      const size_t at = rng() % std::min<size_t>(d.size(), 40);
      d[at] = static_cast<uint8_t>(rng());
    }
    if (rng() % 8 == 0) d.resize(rng() % d.size());
    feed(r, d, SenderId{static_cast<uint32_t>(rng() % 4), 1}, i);
    ASSERT_LE(r.pendingBytes(), ReassemblyLimits{}.max_pending_bytes);
  }
  EXPECT_GT(r.counters().refusedTotal(), 0u);
}

}  // namespace
}  // namespace sweepmap::net
