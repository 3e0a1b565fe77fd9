// UdpmReceiver on a real multicast socket, inside a private network namespace of this test
// process (loopback only): it reads what liblcm publishes, refuses the datagrams that crash
// liblcm 1.3.1's receivers, and keeps receiving good traffic after them.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sched.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstdlib>
#include <lcm/lcm-cpp.hpp>
#include <string>
#include <vector>

#include "net/udpm_receiver.hpp"

namespace sweepmap::net {
namespace {

constexpr const char* kUrl = "udpm://239.255.76.67:7671?ttl=0";

// This test process, for its whole life, in a network namespace of its own with `lo` up and
// multicast routed to it. Skips when namespaces are not available (not root).
bool privateNetwork(std::string* why) {
  static int state = -1;
  if (state < 0) {
    state = unshare(CLONE_NEWNET) == 0 &&
                    std::system("ip link set lo up && ip route add 224.0.0.0/4 dev lo") == 0
                ? 1
                : 0;
  }
  if (!state) *why = "no private network namespace (needs root and iproute2)";
  return state == 1;
}

// Sends raw bytes to the group (or to `address`), as an attacker on the LAN would.
void sendRaw(const std::vector<uint8_t>& bytes, const char* address = "239.255.76.67") {
  const int fd = socket(AF_INET, SOCK_DGRAM, 0);
  ASSERT_GE(fd, 0);
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(7671);
  inet_pton(AF_INET, address, &to.sin_addr);
  ASSERT_EQ(sendto(fd, bytes.data(), bytes.size(), 0, reinterpret_cast<sockaddr*>(&to), sizeof to),
            static_cast<ssize_t>(bytes.size()));
  close(fd);
}

struct Received {
  std::vector<std::pair<std::string, std::vector<uint8_t>>> messages;
  void attach(UdpmReceiver& r, const std::string& pattern) {
    r.subscribe(pattern, [this](const std::string& c, const uint8_t* d, size_t n) {
      messages.emplace_back(c, std::vector<uint8_t>(d, d + n));
    });
  }
};

// Handles until `count` messages arrived or nothing came for a second.
void pump(UdpmReceiver& r, const Received& got, size_t count) {
  while (got.messages.size() < count && r.handleTimeout(1000) > 0) {
  }
  while (r.handleTimeout(50) > 0) {
  }
}

TEST(UdpmUrl, ParsesLiblcmsSyntaxAndNamesWhatIsWrong) {
  const UdpmUrl u = parseUdpmUrl("udpm://239.255.76.67:7667?ttl=1&recv_buf_size=2097152");
  EXPECT_EQ(u.group, "239.255.76.67");
  EXPECT_EQ(u.port, 7667);
  EXPECT_EQ(u.ttl, 1);
  EXPECT_EQ(u.recv_buf_size, 2097152);
  EXPECT_EQ(parseUdpmUrl("udpm://").port, 7667);
  EXPECT_THROW(parseUdpmUrl("udpm://10.0.0.1:7667"), std::invalid_argument);
  EXPECT_THROW(parseUdpmUrl("udpm://239.255.76.67:99999"), std::invalid_argument);
  EXPECT_THROW(parseUdpmUrl("udpm://239.255.76.67:7667?ttl=x"), std::invalid_argument);
  EXPECT_THROW(parseUdpmUrl("udpm://239.255.76.67:7667?bogus=1"), std::invalid_argument);
  EXPECT_TRUE(isUdpmUrl("udpm://239.255.76.67:7667"));
  EXPECT_FALSE(isUdpmUrl("memq://"));
}

TEST(UdpmReceiver, ReadsWhatLiblcmPublishesShortAndFragmented) {
  std::string why;
  if (!privateNetwork(&why)) GTEST_SKIP() << why;
  UdpmReceiver receiver(kUrl);
  Received got;
  got.attach(receiver, "SMALL|LARGE");
  lcm::LCM lcm(kUrl);
  ASSERT_TRUE(lcm.good());
  std::vector<uint8_t> small(100, 7), large(200000);
  for (size_t i = 0; i < large.size(); ++i) large[i] = static_cast<uint8_t>(i * 13);
  lcm.publish("SMALL", small.data(), static_cast<unsigned>(small.size()));
  lcm.publish("LARGE", large.data(), static_cast<unsigned>(large.size()));
  lcm.publish("OTHER", small.data(), static_cast<unsigned>(small.size()));
  pump(receiver, got, 2);
  ASSERT_EQ(got.messages.size(), 2u);
  EXPECT_EQ(got.messages[0].first, "SMALL");
  EXPECT_EQ(got.messages[0].second, small);
  EXPECT_EQ(got.messages[1].first, "LARGE");
  EXPECT_EQ(got.messages[1].second, large);
  EXPECT_EQ(receiver.counters().unsubscribed, 1u);
}

TEST(UdpmReceiver, SurvivesTheDatagramsThatCrashLiblcmAndReceivesAfterThem) {
  std::string why;
  if (!privateNetwork(&why)) GTEST_SKIP() << why;
  UdpmReceiver receiver(kUrl);
  Received got;
  got.attach(receiver, ".*");
  // Issue 21: fragment 0 of an LC03 message on a subscribed channel, its offset 0xFFFFFFFF:
  // liblcm 1.3.1 allocates the message, then its 32-bit check wraps and memcpy writes 4 GiB
  // before the buffer (131 bytes in all) ...
  std::vector<uint8_t> wrap = {'L',  'C',  '0',  '3',  0,    0,    0, 1, 0, 1,
                               0x86, 0xa0, 0xff, 0xff, 0xff, 0xff, 0, 0, 0, 2};
  for (char c : std::string("MAP_SAVE")) wrap.push_back(static_cast<uint8_t>(c));
  wrap.push_back(0);
  wrap.resize(131, 0x41);
  sendRaw(wrap);
  // ... and an LC02 whose channel has no NUL.
  std::vector<uint8_t> unterminated = {'L', 'C', '0', '2', 0, 0, 0, 2};
  for (char c : std::string("MAP_SAVE")) unterminated.push_back(static_cast<uint8_t>(c));
  sendRaw(unterminated);
  lcm::LCM lcm(kUrl);
  const std::vector<uint8_t> good(10, 1);
  lcm.publish("GOOD", good.data(), static_cast<unsigned>(good.size()));
  pump(receiver, got, 1);
  ASSERT_EQ(got.messages.size(), 1u);
  EXPECT_EQ(got.messages[0].first, "GOOD");
  const auto& c = receiver.counters().reassembly;
  EXPECT_EQ(c.refused[static_cast<size_t>(Refusal::kFragmentOutOfRange)], 1u);
  EXPECT_EQ(c.refused[static_cast<size_t>(Refusal::kChannelUnterminated)], 1u);
}

TEST(UdpmReceiver, AnAllowListDropsEveryOtherSender) {
  std::string why;
  if (!privateNetwork(&why)) GTEST_SKIP() << why;
  in_addr other{};
  inet_pton(AF_INET, "10.77.0.2", &other);
  ReceiverOptions options;
  options.allowed_senders = {ntohl(other.s_addr)};
  UdpmReceiver receiver(kUrl, options);
  Received got;
  got.attach(receiver, ".*");
  lcm::LCM lcm(kUrl);
  const std::vector<uint8_t> data(10, 1);
  for (int i = 0; i < 3; ++i) lcm.publish("FROM_LO", data.data(), 10);
  pump(receiver, got, 1);
  EXPECT_TRUE(got.messages.empty());
  EXPECT_EQ(receiver.counters().not_allowed, 3u);
}

// The socket is bound to the group, not to every address: a datagram sent straight to the
// host's address and the port (unicast, which any host that routes to it can send) is not read.
TEST(UdpmReceiver, HearsTheGroupOnlyNotUnicastToThePort) {
  std::string why;
  if (!privateNetwork(&why)) GTEST_SKIP() << why;
  UdpmReceiver receiver(kUrl);
  Received got;
  got.attach(receiver, ".*");
  sendRaw({'L', 'C', '0', '2', 0, 0, 0, 1, 'U', 'N', 'I', 0, 7}, "127.0.0.1");  // unicast
  sendRaw({'L', 'C', '0', '2', 0, 0, 0, 2, 'G', 'R', 'P', 0, 7});
  pump(receiver, got, 1);
  ASSERT_EQ(got.messages.size(), 1u);
  EXPECT_EQ(got.messages[0].first, "GRP");
  EXPECT_EQ(receiver.counters().datagrams, 1u);
}

TEST(UdpmReceiver, WithAKeyOnlySignedMessagesPassAndLoseTheirSignature) {
  std::string why;
  if (!privateNetwork(&why)) GTEST_SKIP() << why;
  std::array<uint8_t, kAuthKeyBytes> key{};
  key.fill(5);
  ReceiverOptions options;
  options.auth = MessageAuth(key);
  UdpmReceiver receiver(kUrl, options);
  Received got;
  got.attach(receiver, ".*");
  lcm::LCM lcm(kUrl);
  const std::vector<uint8_t> data(10, 1);
  lcm.publish("UNSIGNED", data.data(), 10);
  const std::vector<uint8_t> forged =
      MessageAuth(std::array<uint8_t, kAuthKeyBytes>{}).sign("FORGED", data.data(), data.size());
  lcm.publish("FORGED", forged.data(), static_cast<unsigned>(forged.size()));
  const std::vector<uint8_t> good = MessageAuth(key).sign("SIGNED", data.data(), data.size());
  lcm.publish("SIGNED", good.data(), static_cast<unsigned>(good.size()));
  pump(receiver, got, 1);
  ASSERT_EQ(got.messages.size(), 1u);
  EXPECT_EQ(got.messages[0].first, "SIGNED");
  EXPECT_EQ(got.messages[0].second, data);
  EXPECT_EQ(receiver.counters().not_signed, 2u);
}

}  // namespace
}  // namespace sweepmap::net
