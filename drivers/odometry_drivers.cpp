#include "drivers/odometry_drivers.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

namespace sweepmap {
namespace {

DeviceClockSync::Options deviceClock(double tick_us) {
  DeviceClockSync::Options o;
  o.counter_bits = 32;
  o.tick_us = tick_us;
  return o;
}

// Appends `samples` to `queue`, dropping the oldest beyond `max` (counted in *drops).
template <class T>
void enqueue(std::vector<T>* queue, std::vector<T>* samples, size_t max, int64_t* drops) {
  for (T& s : *samples) queue->push_back(std::move(s));
  if (queue->size() > max) {
    const size_t drop = queue->size() - max;
    queue->erase(queue->begin(), queue->begin() + static_cast<std::ptrdiff_t>(drop));
    *drops += static_cast<int64_t>(drop);
  }
}

// Start-up of a device that streams on its own: flush what is buffered, then read until the
// session decodes one item (kept in *read_ahead for the first onBytes), or throw.
template <class Decode>
void awaitFirstFrame(ByteStream& stream, int timeout_ms, const std::string& what,
                     std::vector<uint8_t>* read_ahead, Decode decode) {
  // What the port buffered before we opened it is stale: drop it (the device never pauses, so
  // waiting for a quiet line would wait for ever).
  std::vector<uint8_t> buffer(4096);
  for (int i = 0; i < 16 && stream.read(buffer.data(), buffer.size(), 0) > 0; ++i) {
  }
  read_ahead->clear();
  const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  while (std::chrono::steady_clock::now() < until) {
    const size_t n = stream.read(buffer.data(), buffer.size(), 50);
    if (n == 0) continue;
    read_ahead->insert(read_ahead->end(), buffer.begin(), buffer.begin() + n);
    if (decode(*read_ahead)) return;
    if (read_ahead->size() > 64 * 1024) break;
  }
  throw StreamError("no valid " + what + " frame within " + std::to_string(timeout_ms) + " ms (" +
                    std::to_string(read_ahead->size()) + " bytes read)");
}

// What both sessions' onBytes share: the chunk through the decoder (or, `at_end`, the end of
// the input: Decoder::finish), the line clock set for it, each decode error reported with its
// stream offset, every other event to `on_event`.
template <class Decoder, class Event, class OnEvent>
void decodeChunk(Decoder& decoder, std::vector<Event>* events, const uint8_t* data, size_t size,
                 int64_t arrival_utime, int64_t* fed, LineClock* line,
                 std::vector<std::string>* errors, OnEvent on_event, bool at_end = false) {
  events->clear();
  if (at_end) {
    decoder.finish(events);
  } else {
    decoder.feed(data, size, events);
  }
  *fed += static_cast<int64_t>(size);
  line->chunk(arrival_utime, *fed);
  for (const Event& e : *events) {
    if (const auto* d = std::get_if<DecodeError>(&e)) {
      errors->push_back("byte " + std::to_string(d->offset) + ": " + d->what);
    } else {
      on_event(e);
    }
  }
}

}  // namespace

// ---- HI219 ----

Hi219Session::Hi219Session(int baud, bool raw)
    : clock_(deviceClock(1000.0)), line_(baud, !raw), raw_(raw) {}

void Hi219Session::reset() {
  decoder_.reset();
  clock_.clear();
  fed_ = 0;
}

int Hi219Session::onBytes(const uint8_t* data, size_t size, int64_t arrival_utime,
                          std::vector<ImuSample>* samples, std::vector<std::string>* errors) {
  return decode(data, size, arrival_utime, false, samples, errors);
}

int Hi219Session::finish(std::vector<ImuSample>* samples, std::vector<std::string>* errors) {
  return decode(nullptr, 0, line_.arrival(), true, samples, errors);
}

int Hi219Session::decode(const uint8_t* data, size_t size, int64_t arrival_utime, bool at_end,
                         std::vector<ImuSample>* samples, std::vector<std::string>* errors) {
  int n = 0;
  decodeChunk(
      decoder_, &events_, data, size, arrival_utime, &fed_, &line_, errors,
      [&](const hi219::Event& e) {
        const auto& f = std::get<hi219::Frame>(e);
        if (f.id >= 0) user_id_ = f.id;
        if (!f.has_gyro || !f.has_accel) return;  // not a sample the odometry can use
        ImuSample s{};
        if (f.has_time) {
          // Raw: the IMU's clock; else the frame arrived complete at the receive time
          // of its last byte.
          s.utime = raw_ ? int64_t{f.time_ms} * 1000
                         : clock_.observe(f.time_ms, line_.at(f.offset + f.size));
        } else {
          s.utime = line_.at(f.offset);
        }
        for (int k = 0; k < 3; ++k) {
          s.gyro[k] = f.gyro_rad_s[k];
          s.accel[k] = f.accel_m_s2[k];
          s.rpy[k] = f.has_euler ? f.rpy_rad[k] : std::numeric_limits<double>::quiet_NaN();
        }
        samples->push_back(s);
        ++n;
      },
      at_end);
  return n;
}

Hi219Driver::Hi219Driver(const DeviceUri& uri, const OdometryDriverOptions& options,
                         std::function<int64_t()> now)
    : SampleStreamDevice(uri, options, std::move(now), "HI219") {}

Hi219Driver::~Hi219Driver() { stopWorker(); }

std::string Hi219Driver::identity() const {
  const int id = session_.userId();
  return id >= 0 ? "HI219 (user ID " + std::to_string(id) + ")" : "HI219";
}

// ---- wheel board ----

WheelBoardSession::WheelBoardSession(int baud, bool raw)
    : clock_(deviceClock(1.0)), line_(baud, !raw), raw_(raw) {}

void WheelBoardSession::reset() {
  decoder_.reset();
  clock_.clear();
  fed_ = 0;
  // The counts stay cumulative across a reconnect: a board that kept running continues
  // where it was; one that restarted from 0 is a jump the odometry rejects once.
}

int WheelBoardSession::onBytes(const uint8_t* data, size_t size, int64_t arrival_utime,
                               std::vector<WheelTicks>* ticks, std::vector<std::string>* errors) {
  return decode(data, size, arrival_utime, false, ticks, errors);
}

int WheelBoardSession::finish(std::vector<WheelTicks>* ticks, std::vector<std::string>* errors) {
  return decode(nullptr, 0, line_.arrival(), true, ticks, errors);
}

int WheelBoardSession::decode(const uint8_t* data, size_t size, int64_t arrival_utime, bool at_end,
                              std::vector<WheelTicks>* ticks, std::vector<std::string>* errors) {
  int n = 0;
  decodeChunk(
      decoder_, &events_, data, size, arrival_utime, &fed_, &line_, errors,
      [&](const wheelboard::Event& e) {
        const auto* t = std::get_if<wheelboard::Ticks>(&e);
        if (!t) return;  // a SPEED frame of a two-way capture
        WheelTicks w{};
        if (raw_) {
          // The board's own clock, unwrapped past 32 bits, from its first reading.
          if (!board_clock_.have) {
            board_clock0_ = int64_t{t->time_us} - static_cast<int32_t>(t->time_us);
          }
          w.utime = board_clock0_ + board_clock_(t->time_us);
        } else {
          const int64_t complete = line_.at(t->offset + wheelboard::kTicksFrameBytes);
          w.utime = clock_.observe(t->time_us, complete);
        }
        w.left = left_(static_cast<uint32_t>(t->left));
        w.right = right_(static_cast<uint32_t>(t->right));
        w.flags = t->flags;
        ticks->push_back(w);
        ++n;
      },
      at_end);
  return n;
}

WheelBoardDriver::WheelBoardDriver(const DeviceUri& uri, const OdometryDriverOptions& options,
                                   std::function<int64_t()> now)
    : SampleStreamDevice(uri, options, std::move(now), "wheel board TICKS") {}

WheelBoardDriver::~WheelBoardDriver() { stopWorker(); }

void WheelBoardDriver::command(int64_t, double v_m_s, double w_rad_s) {
  std::lock_guard<std::mutex> lock(mutex_);
  commands_.emplace_back(v_m_s, w_rad_s);
  while (commands_.size() > 16) commands_.pop_front();  // only the newest matter
}

void WheelBoardDriver::onSessionStart() {
  frames_lost_total_ += frames_lost_now_;
  frames_lost_now_ = 0;
}

void WheelBoardDriver::onDecoded(const std::vector<WheelTicks>& ticks) {
  for (const WheelTicks& t : ticks) {
    const bool stopped = (t.flags & wheelboard::kFlagWatchdog) != 0;
    if (stopped && !(last_flags_ & wheelboard::kFlagWatchdog)) ++watchdog_stops_;
    last_flags_ = t.flags;
  }
  frames_lost_now_ = session_.framesLost();
}

void WheelBoardDriver::service(ByteStream& stream, int64_t) {
  std::deque<std::pair<double, double>> due;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    due.swap(commands_);
  }
  for (const auto& [v, w] : due) {
    stream.write(wheelboard::encodeSpeed(tx_seq_++, v, w), 100);
    std::lock_guard<std::mutex> lock(mutex_);
    ++commands_sent_;
  }
}

void WheelBoardDriver::stopSession(ByteStream& stream) {
  // Leaving: stop the wheels now rather than after the board's watchdog.
  stream.write(wheelboard::encodeSpeed(tx_seq_++, 0.0, 0.0), 100);
}

std::vector<std::pair<std::string, int64_t>> WheelBoardDriver::extraCounters() {
  auto counters = SampleStreamDevice::extraCounters();
  std::lock_guard<std::mutex> lock(mutex_);
  counters.insert(counters.end(), {{"frames_lost", frames_lost_total_ + frames_lost_now_},
                                   {"commands_sent", commands_sent_},
                                   {"watchdog_stops", watchdog_stops_},
                                   {"board_flags", last_flags_}});
  return counters;
}

// ---- what both drivers share ----

template <class Session, class Sample, class Frame>
SampleStreamDevice<Session, Sample, Frame>::SampleStreamDevice(const DeviceUri& uri,
                                                               const OdometryDriverOptions& options,
                                                               std::function<int64_t()> now,
                                                               const char* frame_name)
    : StreamDevice(uri, options, std::move(now)),
      options_(options),
      session_(uri.baud, /*raw=*/false),
      frame_name_(frame_name) {}

template <class Session, class Sample, class Frame>
std::vector<Sample> SampleStreamDevice<Session, Sample, Frame>::take() {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<Sample> out;
  out.swap(queue_);
  return out;
}

template <class Session, class Sample, class Frame>
void SampleStreamDevice<Session, Sample, Frame>::startSession(ByteStream& stream) {
  awaitFirstFrame(stream, options_.identify_timeout_ms, frame_name_, &read_ahead_,
                  [](const std::vector<uint8_t>& bytes) {
                    typename Session::Decoder probe;
                    std::vector<typename Session::Event> events;
                    probe.feed(bytes.data(), bytes.size(), &events);
                    return std::any_of(events.begin(), events.end(), [](const auto& e) {
                      return std::holds_alternative<Frame>(e);
                    });
                  });
  session_.reset();
  std::lock_guard<std::mutex> lock(mutex_);
  onSessionStart();
}

template <class Session, class Sample, class Frame>
int SampleStreamDevice<Session, Sample, Frame>::onBytes(const uint8_t* data, size_t size,
                                                        int64_t arrival_utime,
                                                        std::vector<std::string>* errors) {
  decoded_.clear();
  int n = 0;
  if (size == 0 && !read_ahead_.empty()) {  // the start-up's bytes first
    n = session_.onBytes(read_ahead_.data(), read_ahead_.size(), arrival_utime, &decoded_, errors);
    read_ahead_.clear();
  } else {
    n = session_.onBytes(data, size, arrival_utime, &decoded_, errors);
  }
  std::lock_guard<std::mutex> lock(mutex_);
  onDecoded(decoded_);
  enqueue(&queue_, &decoded_, options_.max_queued, &queue_drops_);
  return n;
}

template <class Session, class Sample, class Frame>
std::vector<std::pair<std::string, int64_t>>
SampleStreamDevice<Session, Sample, Frame>::extraCounters() {
  std::lock_guard<std::mutex> lock(mutex_);
  return {{"queue_drops", queue_drops_}};
}

template class SampleStreamDevice<Hi219Session, ImuSample, hi219::Frame>;
template class SampleStreamDevice<WheelBoardSession, WheelTicks, wheelboard::Ticks>;

}  // namespace sweepmap
