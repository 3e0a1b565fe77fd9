// The real-lidar driver's connection handling (RealLidar) with a line-based fake protocol
// over loopback TCP: streaming, reconnect after a hang-up, read timeouts, refused
// connections reported once, a fatal identity mismatch, and the capture tap.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <thread>

#include "drivers/real_lidar.hpp"

namespace sweepmap {
namespace {

// "HELLO\n" -> "ID <name>\n"; then every "SCAN <n>\n" is a scan with seq n.
class LineSession : public LidarSession {
 public:
  explicit LineSession(std::string expected_id) : expected_(std::move(expected_id)) {}
  void start(ByteStream& stream, const std::function<int64_t()>& now) override {
    buffer_.clear();
    counters_ = {};
    stream.write(std::string("HELLO\n"));
    uint8_t b[256];
    std::string line;
    const int64_t deadline = now() + 1000000;
    while (line.find('\n') == std::string::npos) {
      if (now() > deadline) throw StreamError("no ID reply");
      const size_t n = stream.read(b, sizeof b, 100);
      line.append(reinterpret_cast<char*>(b), n);
    }
    const std::string id = line.substr(0, line.find('\n'));
    buffer_ = line.substr(line.find('\n') + 1);
    if (id != "ID " + expected_) {
      throw IdentityMismatch("device is '" + id.substr(3) + "', the rig file says '" + expected_ +
                             "'");
    }
    identity_ = id.substr(3);
  }
  void onBytes(const uint8_t* data, size_t size, int64_t arrival, std::vector<Scan2D>* scans,
               std::vector<std::string>* errors) override {
    counters_.bytes += static_cast<int64_t>(size);
    buffer_.append(reinterpret_cast<const char*>(data), size);
    size_t nl;
    while ((nl = buffer_.find('\n')) != std::string::npos) {
      const std::string line = buffer_.substr(0, nl);
      buffer_.erase(0, nl + 1);
      if (line.rfind("SCAN ", 0) == 0) {
        Scan2D s;
        s.seq = std::stoll(line.substr(5));
        s.utime = arrival;
        scans->push_back(s);
        ++counters_.scans;
      } else {
        ++counters_.checksum_errors;
        errors->push_back("bad line '" + line + "'");
      }
    }
  }
  DecoderCounters decoderCounters() const override { return counters_; }
  std::string identity() const override { return identity_; }

 private:
  std::string expected_, identity_, buffer_;
  DecoderCounters counters_;
};

// A one-client-at-a-time loopback server run by the test.
class FakeDevice {
 public:
  FakeDevice() {
    listener_ = ::socket(AF_INET, SOCK_STREAM, 0);
    const int one = 1;
    ::setsockopt(listener_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ::bind(listener_, reinterpret_cast<sockaddr*>(&a), sizeof a);
    socklen_t len = sizeof a;
    ::getsockname(listener_, reinterpret_cast<sockaddr*>(&a), &len);
    port_ = ntohs(a.sin_port);
    ::listen(listener_, 1);
  }
  ~FakeDevice() {
    if (client_ >= 0) ::close(client_);
    if (listener_ >= 0) ::close(listener_);
  }
  int port() const { return port_; }
  // Accepts the driver and answers its HELLO with `id`.
  void accept(const std::string& id) {
    client_ = ::accept(listener_, nullptr, nullptr);
    char b[16];
    ASSERT_EQ(::read(client_, b, 6), 6);
    send("ID " + id + "\n");
  }
  void send(const std::string& s) {
    ASSERT_EQ(::write(client_, s.data(), s.size()), ssize_t(s.size()));
  }
  void hangUp() {
    ::close(client_);
    client_ = -1;
  }

 private:
  int listener_ = -1, client_ = -1, port_ = 0;
};

int64_t nowUs() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

DeviceUri tcpUri(int port) { return parseDeviceUri("scip://127.0.0.1:" + std::to_string(port)); }

// Polls until `pred` or 5 s.
template <class Pred>
bool eventually(Pred pred) {
  for (int i = 0; i < 500; ++i) {
    if (pred()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return false;
}

TEST(RealLidar, StreamsAndReconnectsAfterAHangUp) {
  FakeDevice dev;
  RealLidarOptions o;
  std::atomic<int64_t> tapped{0};
  o.tap = [&](int64_t, const uint8_t*, size_t n) { tapped += static_cast<int64_t>(n); };
  RealLidar lidar(tcpUri(dev.port()), std::make_unique<LineSession>("UST"), o, nowUs);
  lidar.start();
  dev.accept("UST");
  dev.send("SCAN 1\nSCAN 2\nSC");
  dev.send("AN 3\n");
  std::vector<Scan2D> got;
  ASSERT_TRUE(eventually([&] {
    for (auto& s : lidar.poll(0)) got.push_back(s);
    return got.size() == 3;
  }));
  EXPECT_EQ(got[2].seq, 3);
  dev.hangUp();
  dev.accept("UST");  // the driver comes back by itself
  dev.send("SCAN 4\n");
  ASSERT_TRUE(eventually([&] {
    for (auto& s : lidar.poll(0)) got.push_back(s);
    return got.size() == 4;
  }));
  const DeviceHealth h = lidar.health();
  EXPECT_EQ(h.counter("reconnects"), 1);
  EXPECT_EQ(h.counter("device_scans"), 4);
  EXPECT_EQ(tapped.load(), 2 * 7 + 28);  // the tap sees everything
}

// A session stuck in a call that does not return (here: onBytes on a "HANG" line, until
// released): the worker's loop stops turning and workerStalled() says so — the process then
// withholds its watchdog ping. Waiting on a silent device (reads with timeouts, reconnect
// backoff) is no stall.
class HangingSession : public LineSession {
 public:
  explicit HangingSession(std::atomic<bool>* hang) : LineSession("UST"), hang_(hang) {}
  void onBytes(const uint8_t* data, size_t size, int64_t arrival, std::vector<Scan2D>* scans,
               std::vector<std::string>* errors) override {
    if (std::string(reinterpret_cast<const char*>(data), size).find("HANG") != std::string::npos) {
      while (*hang_) std::this_thread::sleep_for(std::chrono::milliseconds(5));
      return;
    }
    LineSession::onBytes(data, size, arrival, scans, errors);
  }

 private:
  std::atomic<bool>* hang_;
};

TEST(RealLidar, AStuckWorkerIsStalledAWaitingOneIsNot) {
  FakeDevice dev;
  std::atomic<bool> hang{true};
  RealLidar lidar(tcpUri(dev.port()), std::make_unique<HangingSession>(&hang), RealLidarOptions{},
                  nowUs);
  EXPECT_FALSE(lidar.workerStalled(0));  // not started
  lidar.start();
  dev.accept("UST");
  std::this_thread::sleep_for(std::chrono::milliseconds(600));  // silent, reading with timeouts
  EXPECT_FALSE(lidar.workerStalled(400));
  dev.send("HANG\n");
  EXPECT_TRUE(eventually([&] { return lidar.workerStalled(400); }));
  hang = false;
  EXPECT_TRUE(eventually([&] { return !lidar.workerStalled(400); }));
}

TEST(RealLidar, SilenceIsATimeoutThenAReconnect) {
  FakeDevice dev;
  RealLidarOptions o;
  o.read_timeout_ms = 300;
  RealLidar lidar(tcpUri(dev.port()), std::make_unique<LineSession>("UST"), o, nowUs);
  lidar.start();
  dev.accept("UST");
  dev.accept("UST");  // after 300 ms of silence the driver reconnects
  ASSERT_TRUE(eventually([&] { return lidar.health().counter("timeouts") == 1; }));
  EXPECT_EQ(lidar.health().counter("reconnects"), 1);
}

TEST(RealLidar, RefusedIsReportedOnceAndRetried) {
  int port = 0;
  {
    FakeDevice gone;
    port = gone.port();
  }
  RealLidarOptions o;
  o.backoff_min_ms = 20;
  o.backoff_max_ms = 40;
  RealLidar lidar(tcpUri(port), std::make_unique<LineSession>("UST"), o, nowUs);
  lidar.start();
  std::vector<std::string> events;
  ASSERT_TRUE(eventually([&] {
    DeviceHealth h = lidar.health();
    events.insert(events.end(), h.events.begin(), h.events.end());
    return h.counter("connect_failures") >= 5;
  }));
  ASSERT_EQ(events.size(), 1u);
  EXPECT_NE(events[0].find("Connection refused; retrying"), std::string::npos) << events[0];
}

TEST(RealLidar, IdentityMismatchIsFatal) {
  FakeDevice dev;
  RealLidar lidar(tcpUri(dev.port()), std::make_unique<LineSession>("UST"), RealLidarOptions{},
                  nowUs);
  lidar.start();
  dev.accept("X4");
  std::string fatal;
  ASSERT_TRUE(eventually([&] { return !(fatal = lidar.health().fatal).empty(); }));
  EXPECT_EQ(fatal, "scip://127.0.0.1:" + std::to_string(dev.port()) +
                       ": device is 'X4', the rig file says 'UST'");
}

TEST(RealLidar, ARunOfErrorsReconnects) {
  FakeDevice dev;
  RealLidarOptions o;
  o.error_run = 5;
  RealLidar lidar(tcpUri(dev.port()), std::make_unique<LineSession>("UST"), o, nowUs);
  lidar.start();
  dev.accept("UST");
  dev.send("x\nx\nx\nx\nx\n");
  dev.accept("UST");
  ASSERT_TRUE(eventually([&] { return lidar.health().counter("reconnects") == 1; }));
  EXPECT_EQ(lidar.health().counter("checksum_errors"), 5);
}

}  // namespace
}  // namespace sweepmap
