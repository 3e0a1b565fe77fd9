#include "drivers/real_lidar.hpp"

#include <algorithm>
#include <chrono>

namespace sweepmap {
namespace {

void addCounters(DecoderCounters* total, const DecoderCounters& c) {
  total->bytes += c.bytes;
  total->packets += c.packets;
  total->scans += c.scans;
  total->checksum_errors += c.checksum_errors;
  total->resyncs += c.resyncs;
  total->discarded_bytes += c.discarded_bytes;
  total->device_errors += c.device_errors;
}

// Hands every chunk read to the tap before the session sees it.
class TappedStream : public ByteStream {
 public:
  TappedStream(std::unique_ptr<ByteStream> inner, const RealLidarOptions& options,
               std::function<int64_t()> now)
      : inner_(std::move(inner)), tap_(options.tap), now_(std::move(now)) {}
  size_t read(uint8_t* buffer, size_t capacity, int timeout_ms) override {
    const size_t n = inner_->read(buffer, capacity, timeout_ms);
    if (n > 0) tap_(now_(), buffer, n);
    return n;
  }
  using ByteStream::write;
  void write(const void* data, size_t size, int timeout_ms) override {
    inner_->write(data, size, timeout_ms);
  }
  void setDtr(bool on) override { inner_->setDtr(on); }
  int fd() const override { return inner_->fd(); }
  std::string describe() const override { return inner_->describe(); }

 private:
  std::unique_ptr<ByteStream> inner_;
  std::function<void(int64_t, const uint8_t*, size_t)> tap_;
  std::function<int64_t()> now_;
};

}  // namespace

RealLidar::RealLidar(const DeviceUri& uri, std::unique_ptr<LidarSession> session,
                     const RealLidarOptions& options, std::function<int64_t()> now)
    : uri_(uri), session_(std::move(session)), options_(options), now_(std::move(now)) {}

void RealLidar::start() {
  if (!worker_.joinable()) worker_ = std::thread([this] { run(); });
}

RealLidar::~RealLidar() {
  stop_ = true;
  if (worker_.joinable()) worker_.join();
}

std::vector<Scan2D> RealLidar::poll(int64_t) {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<Scan2D> out;
  out.swap(queue_);
  return out;
}

DeviceHealth RealLidar::health() {
  std::lock_guard<std::mutex> lock(mutex_);
  DecoderCounters d = decoded_total_;
  addCounters(&d, decoded_now_);
  DeviceHealth h;
  h.counters = {{"device_scans", scans_},
                {"bytes", d.bytes},
                {"checksum_errors", d.checksum_errors},
                {"resyncs", d.resyncs},
                {"discarded_bytes", d.discarded_bytes},
                {"device_errors", d.device_errors},
                {"timeouts", timeouts_},
                {"reconnects", reconnects_},
                {"connect_failures", connect_failures_},
                {"clock_resets", clock_resets_total_ + clock_resets_now_},
                {"queue_drops", queue_drops_},
                {"repeated_events", events_suppressed_}};
  h.events.swap(events_);
  h.fatal = fatal_;
  return h;
}

void RealLidar::event(const std::string& what) {
  std::lock_guard<std::mutex> lock(mutex_);
  // One line per distinct event: a port that stays missing is reported once, then retried
  // quietly (counted).
  if (what == last_event_) {
    ++events_suppressed_;
    return;
  }
  last_event_ = what;
  if (events_.size() < 100) events_.push_back(what);
}

void RealLidar::run() {
  int backoff_ms = options_.backoff_min_ms;
  bool was_connected = false;
  const auto sleepInterruptibly = [this](int ms) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(ms);
    while (!stop_ && std::chrono::steady_clock::now() < until) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  };
  while (!stop_) {
    std::unique_ptr<ByteStream> stream;
    try {
      stream = uri_.protocol == DeviceProtocol::kScip
                   ? openTcp(uri_.host, uri_.port, options_.connect_timeout_ms)
                   : openSerial(uri_.path, uri_.baud);
    } catch (const StreamError& e) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        ++connect_failures_;
      }
      event(uri_.text + ": " + e.what() + "; retrying");
      sleepInterruptibly(backoff_ms);
      backoff_ms = std::min(2 * backoff_ms, options_.backoff_max_ms);
      continue;
    }
    if (options_.tap) stream = std::make_unique<TappedStream>(std::move(stream), options_, now_);
    if (was_connected) {
      std::lock_guard<std::mutex> lock(mutex_);
      ++reconnects_;
    }
    try {
      session_->start(*stream, now_);
      event(uri_.text + ": streaming from " + session_->identity());
      was_connected = true;
      backoff_ms = options_.backoff_min_ms;
      streaming_ = true;
      streamOnce(*stream);
    } catch (const IdentityMismatch& e) {
      std::lock_guard<std::mutex> lock(mutex_);
      fatal_ = uri_.text + ": " + e.what();
      streaming_ = false;
      return;
    } catch (const std::exception& e) {
      event(uri_.text + ": " + e.what());
    }
    streaming_ = false;
    if (stop_) {
      try {
        session_->stop(*stream);
      } catch (const std::exception&) {
      }
    }
    {
      std::lock_guard<std::mutex> lock(mutex_);
      addCounters(&decoded_total_, session_->decoderCounters());
      decoded_now_ = {};
      clock_resets_total_ += clock_resets_now_;
      clock_resets_now_ = 0;
    }
    stream.reset();
    if (!stop_) {
      sleepInterruptibly(backoff_ms);
      backoff_ms = std::min(2 * backoff_ms, options_.backoff_max_ms);
    }
  }
}

void RealLidar::streamOnce(ByteStream& stream) {
  std::vector<uint8_t> buffer(64 * 1024);
  std::vector<Scan2D> scans;
  std::vector<std::string> errors;
  int64_t last_byte_utime = now_();
  int errors_in_a_row = 0;
  bool first = true;  // decode what start() read ahead
  while (!stop_) {
    const size_t n = first ? 0 : stream.read(buffer.data(), buffer.size(), 100);
    const int64_t now = now_();
    if (n == 0 && !first) {
      if (now - last_byte_utime > int64_t{options_.read_timeout_ms} * 1000) {
        std::lock_guard<std::mutex> lock(mutex_);
        ++timeouts_;
        throw StreamError("no data for " + std::to_string(options_.read_timeout_ms) +
                          " ms; reconnecting");
      }
      continue;
    }
    first = false;
    last_byte_utime = now;
    scans.clear();
    errors.clear();
    session_->onBytes(buffer.data(), n, now, &scans, &errors);
    errors_in_a_row = scans.empty() ? errors_in_a_row + static_cast<int>(errors.size()) : 0;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      decoded_now_ = session_->decoderCounters();
      clock_resets_now_ = session_->clockResets();
      scans_ += static_cast<int64_t>(scans.size());
      for (Scan2D& s : scans) queue_.push_back(std::move(s));
      if (queue_.size() > options_.max_queued_scans) {
        const size_t drop = queue_.size() - options_.max_queued_scans;
        queue_.erase(queue_.begin(), queue_.begin() + static_cast<std::ptrdiff_t>(drop));
        queue_drops_ += static_cast<int64_t>(drop);
      }
    }
    for (const std::string& e : errors) event(uri_.text + ": " + e);
    if (errors_in_a_row >= options_.error_run) {
      throw StreamError(std::to_string(errors_in_a_row) +
                        " decode errors in a row without a scan; reconnecting");
    }
  }
}

}  // namespace sweepmap
