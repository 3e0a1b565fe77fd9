// Device URIs, the host clock sync of a device counter, and the byte transports on
// loopback TCP and a pseudo-terminal.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <termios.h>
#include <unistd.h>

#include <cmath>
#include <random>
#include <stdexcept>

#include "core/device_uri.hpp"
#include "drivers/clock_sync.hpp"
#include "drivers/io/byte_stream.hpp"

namespace sweepmap {
namespace {

TEST(DeviceUri, ParsesEveryForm) {
  EXPECT_EQ(parseDeviceUri("sim").protocol, DeviceProtocol::kSim);
  DeviceUri u = parseDeviceUri("scip://192.168.0.10");
  EXPECT_EQ(u.protocol, DeviceProtocol::kScip);
  EXPECT_EQ(u.host, "192.168.0.10");
  EXPECT_EQ(u.port, 10940);
  u = parseDeviceUri("scip://localhost:20000");
  EXPECT_EQ(u.host, "localhost");
  EXPECT_EQ(u.port, 20000);
  u = parseDeviceUri("scip://[::1]:10941");
  EXPECT_EQ(u.host, "::1");
  EXPECT_EQ(u.port, 10941);
  u = parseDeviceUri("ydlidar:///dev/ttyUSB0");
  EXPECT_EQ(u.protocol, DeviceProtocol::kYdlidarX4);
  EXPECT_EQ(u.path, "/dev/ttyUSB0");
  EXPECT_EQ(u.baud, 128000);
  u = parseDeviceUri("rplidar:///dev/ttyUSB1?baud=256000");
  EXPECT_EQ(u.protocol, DeviceProtocol::kRplidar);
  EXPECT_EQ(u.path, "/dev/ttyUSB1");
  EXPECT_EQ(u.baud, 256000);
  EXPECT_EQ(parseDeviceUri("rplidar:///dev/ttyUSB1").baud, 115200);
}

TEST(DeviceUri, RejectsWithTheReason) {
  const auto message = [](const std::string& text) {
    try {
      parseDeviceUri(text);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(message("usb0").find("expected sim, scip://"), std::string::npos);
  EXPECT_NE(message("scip://host:0").find("bad port '0'"), std::string::npos);
  EXPECT_NE(message("scip://:10940").find("no host"), std::string::npos);
  EXPECT_NE(message("ydlidar://dev/ttyUSB0").find("absolute path"), std::string::npos);
  EXPECT_NE(message("rplidar:///dev/ttyUSB0?speed=9").find("unknown option 'speed=9'"),
            std::string::npos);
  EXPECT_NE(message("rplidar:///dev/ttyUSB0?baud=fast").find("bad baud rate"), std::string::npos);
  EXPECT_NE(message("hokuyo://x").find("unknown scheme 'hokuyo'"), std::string::npos);
}

// A device whose millisecond counter starts near the 24-bit wrap and runs 100 ppm fast;
// its scans come every 25 ms of its own clock (the mirror is timed by the device's
// oscillator) and arrive 20 ms after their stamp plus 0..3 ms of random delay.
struct DriftingDevice {
  double start_ms = 16777215.0 - 8000.0;  // wraps after 8 s
  double ppm = 100.0;
  int64_t host0 = 1'700'000'000'000'000;
  int64_t counter(int64_t host_us) const {
    const double ms = start_ms + (host_us - host0) * 1e-3 * (1.0 + ppm * 1e-6);
    return static_cast<int64_t>(std::floor(ms)) & 0xFFFFFF;
  }
};

TEST(DeviceClockSync, FollowsDriftAcrossTheWrapWithinAMillisecond) {
  DriftingDevice dev;
  DeviceClockSync sync;
  // Ten TM1 exchanges 3.3 ms apart, 0.4 ms round trips: the anchor to about 0.1 ms.
  for (int k = 0; k < 10; ++k) {
    const int64_t t_send = dev.host0 + 1000 + k * 3300;
    sync.anchor(dev.counter(t_send + 200), t_send, t_send + 400);
  }
  EXPECT_LT(sync.anchorUncertaintyUs(), 600.0);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> delay_us(0.0, 3000.0);
  double worst_after_fit_us = 0.0;
  for (int k = 0; k < 40 * 120; ++k) {  // 120 s of scans at 40 Hz
    const auto stamp_host = static_cast<int64_t>(dev.host0 + 40300 + k * 25000 / (1.0 + 1e-4));
    const int64_t raw = dev.counter(stamp_host);
    const auto arrival = static_cast<int64_t>(stamp_host + 20000 + delay_us(rng));
    const int64_t mapped = sync.observe(raw, arrival);
    // The truth: the instant the device stamped (its counter has 1 ms resolution).
    const auto truth_host = static_cast<double>(stamp_host);
    if (k > 40 * 10)
      worst_after_fit_us = std::max(worst_after_fit_us, std::abs(mapped - truth_host));
  }
  EXPECT_EQ(sync.wraps(), 1);
  EXPECT_EQ(sync.resets(), 0);
  EXPECT_NEAR(sync.ratePpm(), 100.0, 10.0);
  EXPECT_LT(worst_after_fit_us, 1000.0) << "worst error " << worst_after_fit_us << " us";
  std::cout << "clock sync: rate " << sync.ratePpm() << " ppm (true 100), worst error "
            << worst_after_fit_us << " us, latency " << sync.latencyUs() << " us\n";
}

TEST(DeviceClockSync, ResetsOnAJumpAndNotOnOneLateMessage) {
  DeviceClockSync sync;
  int64_t host = 1'000'000'000;
  int64_t raw = 5000;
  for (int k = 0; k < 100; ++k, host += 25000, raw += 25) sync.observe(raw, host + 10000);
  // One message held up 2 s (buffering): not a jump.
  sync.observe(raw, host + 2'010'000);
  host += 25000;
  raw += 25;
  for (int k = 0; k < 10; ++k, host += 25000, raw += 25) sync.observe(raw, host + 10000);
  EXPECT_EQ(sync.resets(), 0);
  // The device's clock restarts at 0 (power cycle): followed at once.
  raw = 0;
  int64_t mapped = 0;
  for (int k = 0; k < 10; ++k, host += 25000, raw += 25) mapped = sync.observe(raw, host + 10000);
  EXPECT_EQ(sync.resets(), 1);
  // No TM exchange here: anchored on arrival times, so mapped times carry the latency.
  EXPECT_NEAR(static_cast<double>(mapped), static_cast<double>(host - 25000 + 10000), 1000.0);
  // Forward jump of an hour: confirmed after three stamps.
  raw += 3'600'000;
  for (int k = 0; k < 5; ++k, host += 25000, raw += 25) mapped = sync.observe(raw, host + 10000);
  EXPECT_EQ(sync.resets(), 2);
  EXPECT_NEAR(static_cast<double>(mapped), static_cast<double>(host - 25000 + 10000), 1000.0);
}

TEST(ByteStream, TcpRefusedIsOneClearError) {
  // A port nobody listens on: bind one, note it, close it.
  const int s = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(::bind(s, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
  socklen_t len = sizeof a;
  ::getsockname(s, reinterpret_cast<sockaddr*>(&a), &len);
  const int port = ntohs(a.sin_port);
  ::close(s);
  try {
    openTcp("127.0.0.1", port, 500);
    FAIL() << "connected to a closed port";
  } catch (const StreamError& e) {
    EXPECT_EQ(std::string(e.what()),
              "tcp 127.0.0.1:" + std::to_string(port) + ": Connection refused");
  }
}

TEST(ByteStream, SerialOnAPtyReadsWritesAndSeesTheHangUp) {
  const int master = ::posix_openpt(O_RDWR | O_NOCTTY);
  ASSERT_GE(master, 0);
  ASSERT_EQ(::grantpt(master), 0);
  ASSERT_EQ(::unlockpt(master), 0);
  const std::string path = ::ptsname(master);
  auto port = openSerial(path, 128000);  // a rate termios has no constant for
  EXPECT_EQ(port->describe(), "serial " + path + " @128000");
  port->setDtr(true);  // a pty has no modem lines: ignored
  port->write(std::string("\xA5\x90", 2));
  char got[2] = {};
  ASSERT_EQ(::read(master, got, 2), 2);
  EXPECT_EQ(static_cast<uint8_t>(got[1]), 0x90);
  const uint8_t reply[3] = {0xA5, 0x5A, 0x14};
  ASSERT_EQ(::write(master, reply, 3), 3);
  uint8_t buf[16];
  EXPECT_EQ(port->read(buf, sizeof buf, 1000), 3u);
  EXPECT_EQ(buf[2], 0x14);
  EXPECT_EQ(port->read(buf, sizeof buf, 20), 0u);  // timeout: nothing, no error
  ::close(master);
  EXPECT_THROW(port->read(buf, sizeof buf, 1000), StreamError);
  try {
    openSerial("/dev/ttyNOPE", 115200);
    FAIL();
  } catch (const StreamError& e) {
    EXPECT_EQ(std::string(e.what()), "serial /dev/ttyNOPE: No such file or directory");
  }
}

}  // namespace
}  // namespace sweepmap
