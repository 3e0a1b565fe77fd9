// Rig B's odometry drivers: the sessions (bytes → samples, the devices' clocks mapped to host
// time, counts unwrapped, frames lost), and the HI219 and wheel board drivers on
// pseudo-terminals: samples, SPEED frames for commands and a zero speed on stop, the board's
// watchdog flag, and a reconnect after the IMU's port hangs up. The tests wait for events
// (with a generous deadline); they assert no timing.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <functional>
#include <mutex>
#include <thread>

#include "core/device_uri.hpp"
#include "drivers/odometry_drivers.hpp"

namespace sweepmap {
namespace {

namespace fs = std::filesystem;

int64_t hostUtime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

bool waitUntil(const std::function<bool()>& done, double timeout_s = 10.0) {
  const auto until = std::chrono::steady_clock::now() +
                     std::chrono::milliseconds(static_cast<int>(timeout_s * 1000));
  while (std::chrono::steady_clock::now() < until) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return done();
}

std::string ticksFrame(uint16_t seq, uint32_t time_us, int32_t left, int32_t right,
                       uint16_t flags = 0) {
  wheelboard::Ticks t;
  t.seq = seq;
  t.time_us = time_us;
  t.left = left;
  t.right = right;
  t.flags = flags;
  return wheelboard::encodeTicks(t);
}

std::string imuFrame(uint32_t time_ms, double gyro_z) {
  hi219::Frame f;
  f.id = 0;
  f.time_ms = time_ms;
  f.accel_m_s2 = {0.1, -0.2, 9.81};
  f.gyro_rad_s = {0.01, -0.02, gyro_z};
  f.rpy_rad = {0.0, 0.0, 0.5};
  f.quat_wxyz = {1.0, 0.0, 0.0, 0.0};
  return hi219::encodeFrame(hi219::encodeImusol(f));
}

const uint8_t* bytes(const std::string& s) { return reinterpret_cast<const uint8_t*>(s.data()); }

// The board's clock crosses its 32-bit wrap and the counts their int32 wrap; two frames are
// lost; each frame arrives 0.3-1.8 ms after it was sent (host read jitter). The stamps follow
// the board's clock to the lower envelope of the delays, the counts run on, the gap is counted.
TEST(WheelBoardSession, MapsTheBoardClockUnwrapsAndCountsLostFrames) {
  WheelBoardSession session(115200, /*raw=*/false);
  const int64_t host0 = 1'700'000'000'000'000;
  const uint32_t board0 = 0xFFFFFFFFu - 1'000'000u;  // wraps 1 s in
  const int32_t left0 = 0x7FFFFFFF - 1000;           // wraps after 20 frames
  uint64_t lcg = 12345;
  std::vector<WheelTicks> ticks;
  std::vector<std::string> errors;
  std::vector<int64_t> sent;
  for (int k = 0; k < 300; ++k) {
    if (k == 150 || k == 151) continue;  // lost on the line
    lcg = lcg * 6364136223846793005ull + 1442695040888963407ull;
    const int64_t delay = 300 + static_cast<int64_t>((lcg >> 33) % 1500);
    const std::string f =
        ticksFrame(static_cast<uint16_t>(k), board0 + 20000u * uint32_t(k),
                   static_cast<int32_t>(uint32_t(left0) + 50u * uint32_t(k)), -40 * k);
    session.onBytes(bytes(f), f.size(), host0 + 20000 * k + delay, &ticks, &errors);
    sent.push_back(host0 + 20000 * k);
  }
  EXPECT_TRUE(errors.empty());
  ASSERT_EQ(ticks.size(), 298u);
  EXPECT_EQ(session.framesLost(), 2);
  for (size_t i = 1; i < ticks.size(); ++i) {
    const int64_t dk = (sent[i] - sent[i - 1]) / 20000;
    EXPECT_EQ(ticks[i].left - ticks[i - 1].left, 50 * dk) << i;
    EXPECT_EQ(ticks[i].right - ticks[i - 1].right, -40 * dk) << i;
    EXPECT_GT(ticks[i].utime, ticks[i - 1].utime) << i;
  }
  // Once the envelope has seen a quick arrival, every stamp is within the read jitter of the
  // time the frame was sent (plus its ~1.9 ms on the line at 115200 baud).
  double worst = 0.0;
  for (size_t i = 50; i < ticks.size(); ++i) {
    worst = std::max(worst, std::fabs(double(ticks[i].utime - sent[i])));
  }
  std::cout << "wheel board stamps: worst |stamp - sent| " << worst << " us\n";
  EXPECT_LT(worst, 2500.0);
  EXPECT_EQ(session.clockResets(), 0);
}

// A loaded host: the first frame is read 60 ms late, and every few seconds a stall holds the
// line for up to 80 ms, then the backlog comes at once. The stamps never go back, their
// intervals stay within 2 % of the board's, and once the quick arrivals have shown how late
// the first one was, they are back within the read jitter of the send times. (Anchored on the
// first arrival, they used to jump back 30-50 ms when the quick ones came, and the odometry
// dropped those readings.)
TEST(WheelBoardSession, StampsStayMonotonicAndSmoothOnALoadedHost) {
  WheelBoardSession session(115200, /*raw=*/false);
  const int64_t host0 = 1'700'000'000'000'000;
  uint64_t lcg = 99;
  std::vector<WheelTicks> ticks;
  std::vector<std::string> errors;
  std::vector<int64_t> sent;
  int64_t stalled_until = 0;
  for (int k = 0; k < 1500; ++k) {  // 30 s at 50 Hz
    lcg = lcg * 6364136223846793005ull + 1442695040888963407ull;
    const int64_t t = host0 + 20000 * k;
    int64_t arrival = t + 300 + static_cast<int64_t>((lcg >> 33) % 1500);
    if (k == 0) arrival += 60000;
    if (k % 200 == 100) stalled_until = t + 80000;  // a stall: held up to then
    arrival = std::max(arrival, stalled_until);
    const std::string f = ticksFrame(uint16_t(k), 5'000'000u + 20000u * uint32_t(k), k, k);
    session.onBytes(bytes(f), f.size(), arrival, &ticks, &errors);
    sent.push_back(t);
  }
  ASSERT_EQ(ticks.size(), 1500u);
  double worst_interval = 0.0, worst_late = 0.0;
  for (size_t i = 1; i < ticks.size(); ++i) {
    const double dt = double(ticks[i].utime - ticks[i - 1].utime);
    worst_interval = std::max(worst_interval, std::fabs(dt - 20000.0));
    if (i >= 250) worst_late = std::max(worst_late, std::fabs(double(ticks[i].utime - sent[i])));
  }
  std::cout << "loaded host: worst interval error " << worst_interval
            << " us, worst |stamp - sent| " << worst_late << " us after 5 s\n";
  EXPECT_LE(worst_interval, 0.02 * 20000 + 1);
  EXPECT_LT(worst_late, 2500.0);
  EXPECT_EQ(session.clockResets(), 0);
}

// Raw bytes (no receive times): the board's own clock, its wrap unwrapped.
TEST(WheelBoardSession, RawBytesKeepTheBoardsIntervals) {
  WheelBoardSession session(115200, /*raw=*/true);
  std::string all;
  for (int k = 0; k < 100; ++k) all += ticksFrame(uint16_t(k), 0xFFFF0000u + 20000u * k, k, k);
  std::vector<WheelTicks> ticks;
  std::vector<std::string> errors;
  for (size_t i = 0; i < all.size(); i += 7) {  // split anywhere
    session.onBytes(bytes(all) + i, std::min<size_t>(7, all.size() - i), 0, &ticks, &errors);
  }
  ASSERT_EQ(ticks.size(), 100u);
  for (size_t i = 1; i < ticks.size(); ++i) EXPECT_EQ(ticks[i].utime - ticks[i - 1].utime, 20000);
}

// The 0x91 record into SI units; raw bytes keep the IMU's millisecond clock.
TEST(Hi219Session, RecordsBecomeSamplesInSiUnits) {
  Hi219Session session(115200, /*raw=*/true);
  std::string all;
  for (int k = 0; k < 20; ++k) all += imuFrame(1000u + 5u * uint32_t(k), 0.25);
  all.insert(100, "garbage\x5A", 8);  // between or inside frames: resynchronised
  std::vector<ImuSample> samples;
  std::vector<std::string> errors;
  session.onBytes(bytes(all), all.size(), 0, &samples, &errors);
  ASSERT_GE(samples.size(), 18u);
  EXPECT_FALSE(errors.empty());
  for (const ImuSample& s : samples) {
    EXPECT_NEAR(s.gyro[2], 0.25, 1e-6);
    EXPECT_NEAR(s.accel[2], 9.81, 1e-5);
    EXPECT_NEAR(s.rpy[2], 0.5, 1e-6);
  }
  for (size_t i = 1; i < samples.size(); ++i) {
    EXPECT_EQ((samples[i].utime - samples[i - 1].utime) % 5000, 0);
  }
}

// A device behind a pseudo-terminal whose slave the driver opens through a symlink, so that
// unplugging and plugging in again gives the driver a new port behind the same path.
class PtyDevice {
 public:
  explicit PtyDevice(fs::path link) : link_(std::move(link)) { plug(); }
  ~PtyDevice() {
    stop();
    unplug();
    fs::remove(link_);
  }
  void plug() {
    std::lock_guard<std::mutex> lock(mutex_);
    master_ = ::posix_openpt(O_RDWR | O_NOCTTY | O_NONBLOCK);
    ASSERT_GE(master_, 0);
    ASSERT_EQ(::grantpt(master_), 0);
    ASSERT_EQ(::unlockpt(master_), 0);
    fs::remove(link_);
    fs::create_symlink(::ptsname(master_), link_);
  }
  void unplug() {
    std::lock_guard<std::mutex> lock(mutex_);
    if (master_ >= 0) ::close(master_);
    master_ = -1;
  }
  // Calls `frame(k)` every period_ms and sends what it returns; collects what the host sends.
  void stream(int period_ms, std::function<std::string(int)> frame) {
    thread_ = std::thread([this, period_ms, frame] {
      for (int k = 0; !stop_; ++k) {
        {
          std::lock_guard<std::mutex> lock(mutex_);
          if (master_ >= 0) {
            const std::string f = frame(k);
            (void)!::write(master_, f.data(), f.size());
            char b[256];
            ssize_t n;
            while ((n = ::read(master_, b, sizeof b)) > 0) received_.append(b, size_t(n));
          }
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(period_ms));
      }
    });
  }
  void stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }
  std::string received() {
    std::lock_guard<std::mutex> lock(mutex_);
    return received_;
  }
  std::string uri(const std::string& scheme) const { return scheme + "://" + link_.string(); }

 private:
  fs::path link_;
  std::mutex mutex_;
  int master_ = -1;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::string received_;
};

std::vector<wheelboard::Speed> speedsIn(const std::string& bytes_sent) {
  wheelboard::Decoder d;
  std::vector<wheelboard::Event> events;
  d.feed(bytes(bytes_sent), bytes_sent.size(), &events);
  std::vector<wheelboard::Speed> out;
  for (const auto& e : events) {
    if (const auto* s = std::get_if<wheelboard::Speed>(&e)) out.push_back(*s);
  }
  return out;
}

// Readings flow; each command goes out once as a SPEED frame; a watchdog stop reported by the
// board is counted once per stop; on stop the driver sends a zero speed.
TEST(WheelBoardDriver, ReadingsCommandsWatchdogAndAZeroSpeedOnStop) {
  PtyDevice board(fs::temp_directory_path() /
                  ("sweepmap_wheelboard_" + std::to_string(::getpid())));
  std::atomic<bool> watchdog{false};
  board.stream(20, [&](int k) {
    return ticksFrame(uint16_t(k), 20000u * uint32_t(k), 10 * k, 12 * k,
                      watchdog ? wheelboard::kFlagWatchdog : 0);
  });
  {
    WheelBoardDriver driver(parseDeviceUri(board.uri("wheelboard")), OdometryDriverOptions{},
                            hostUtime);
    driver.start();
    std::vector<WheelTicks> got;
    ASSERT_TRUE(waitUntil([&] {
      for (const auto& t : driver.poll(hostUtime())) got.push_back(t);
      return got.size() >= 10;
    }));
    for (size_t i = 1; i < got.size(); ++i) {
      EXPECT_EQ(got[i].left - got[i - 1].left, 10 * (got[i].right - got[i - 1].right) / 12);
      EXPECT_GT(got[i].utime, got[i - 1].utime);
    }
    driver.command(hostUtime(), 0.30, -0.5);
    driver.command(hostUtime(), 0.25, 0.1);
    ASSERT_TRUE(waitUntil([&] { return speedsIn(board.received()).size() >= 2; }));
    const auto speeds = speedsIn(board.received());
    EXPECT_NEAR(speeds[0].v_m_s, 0.30, 1e-9);
    EXPECT_NEAR(speeds[0].w_rad_s, -0.5, 1e-9);
    EXPECT_NEAR(speeds[1].v_m_s, 0.25, 1e-9);
    EXPECT_EQ(uint16_t(speeds[1].seq - speeds[0].seq), 1);
    watchdog = true;
    ASSERT_TRUE(waitUntil([&] { return driver.health().counter("watchdog_stops") == 1; }));
    EXPECT_EQ(driver.health().counter("commands_sent"), 2);
    EXPECT_EQ(driver.health().counter("frames_lost"), 0);
  }
  // The driver is gone: its last words were a zero speed.
  ASSERT_TRUE(waitUntil([&] { return speedsIn(board.received()).size() >= 3; }));
  const auto speeds = speedsIn(board.received());
  EXPECT_EQ(speeds.back().v_m_s, 0.0);
  EXPECT_EQ(speeds.back().w_rad_s, 0.0);
}

// The IMU's port hangs up (unplugged) and comes back: the driver reopens it, counts the
// reconnect and delivers samples again.
TEST(Hi219Driver, ReconnectsAfterTheIMUsPortHangsUp) {
  PtyDevice imu(fs::temp_directory_path() / ("sweepmap_hi219_" + std::to_string(::getpid())));
  imu.stream(5, [](int k) { return imuFrame(5u * uint32_t(k), 0.1); });
  Hi219Driver driver(parseDeviceUri(imu.uri("hi219")), OdometryDriverOptions{}, hostUtime);
  driver.start();
  size_t before = 0;
  ASSERT_TRUE(waitUntil([&] {
    before += driver.poll(hostUtime()).size();
    return before >= 20;
  }));
  EXPECT_TRUE(driver.streaming());
  imu.unplug();
  ASSERT_TRUE(waitUntil([&] { return !driver.streaming(); }));
  driver.poll(hostUtime());
  imu.plug();
  size_t after = 0;
  ASSERT_TRUE(waitUntil([&] {
    after += driver.poll(hostUtime()).size();
    return after >= 20;
  }));
  const DeviceHealth h = driver.health();
  EXPECT_GE(h.counter("reconnects"), 1);
  EXPECT_EQ(h.counter("checksum_errors"), 0);
}

// A port that is not there: one clear error naming it, then quiet retries.
TEST(Hi219Driver, AMissingPortIsReportedOnce) {
  Hi219Driver driver(parseDeviceUri("hi219:///dev/ttyNOPE_sweepmap"), OdometryDriverOptions{},
                     hostUtime);
  driver.start();
  std::vector<std::string> events;
  ASSERT_TRUE(waitUntil([&] {
    for (auto& e : driver.health().events) events.push_back(e);
    return !events.empty();
  }));
  EXPECT_NE(events[0].find("/dev/ttyNOPE_sweepmap"), std::string::npos) << events[0];
  EXPECT_NE(events[0].find("No such file or directory"), std::string::npos) << events[0];
  EXPECT_TRUE(driver.poll(hostUtime()).empty());
}

}  // namespace
}  // namespace sweepmap
