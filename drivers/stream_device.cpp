#include "drivers/stream_device.hpp"

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
  total->anomalies += c.anomalies;
}

// Hands every chunk read to the tap before the session sees it.
class TappedStream : public ByteStream {
 public:
  TappedStream(std::unique_ptr<ByteStream> inner, const StreamDeviceOptions& options,
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

StreamDevice::StreamDevice(const DeviceUri& uri, const StreamDeviceOptions& options,
                           std::function<int64_t()> now)
    : uri_(uri), options_(options), now_(std::move(now)) {}

StreamDevice::~StreamDevice() { stopWorker(); }

namespace {
int64_t steadyMs() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}
}  // namespace

void StreamDevice::startWorker() {
  if (worker_.joinable()) return;
  beat();
  running_ = true;
  worker_ = std::thread([this] {
    run();
    running_ = false;
  });
}

void StreamDevice::beat() { beat_ms_ = steadyMs(); }

bool StreamDevice::workerStalled(int64_t max_silence_ms) const {
  return running_ && !stop_ && steadyMs() - beat_ms_ > max_silence_ms;
}

void StreamDevice::stopWorker() {
  stop_ = true;
  if (worker_.joinable()) worker_.join();
}

DeviceHealth StreamDevice::health() {
  std::vector<std::pair<std::string, int64_t>> extra = extraCounters();
  std::lock_guard<std::mutex> lock(mutex_);
  DecoderCounters d = decoded_total_;
  addCounters(&d, decoded_now_);
  DeviceHealth h;
  h.counters = {{itemsName(), items_},
                {"bytes", d.bytes},
                {"checksum_errors", d.checksum_errors},
                {"resyncs", d.resyncs},
                {"discarded_bytes", d.discarded_bytes},
                {"device_errors", d.device_errors},
                {"packets", d.packets},
                {"anomalies", d.anomalies},
                {"timeouts", timeouts_},
                {"reconnects", reconnects_},
                {"connect_failures", connect_failures_},
                {"clock_resets", clock_resets_total_ + clock_resets_now_},
                {"repeated_events", events_suppressed_}};
  h.counters.insert(h.counters.end(), extra.begin(), extra.end());
  h.events.swap(events_);
  h.fatal = fatal_;
  return h;
}

void StreamDevice::event(const std::string& what) {
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

void StreamDevice::run() {
  int backoff_ms = options_.backoff_min_ms;
  bool was_connected = false;
  const auto sleepInterruptibly = [this](int ms) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(ms);
    while (!stop_ && std::chrono::steady_clock::now() < until) {
      beat();
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  };
  while (!stop_) {
    beat();
    std::unique_ptr<ByteStream> stream;
    try {
      // SCIP over TCP (UST, UTM-30LX-EW), or on a serial / USB port (URG-04LX: a path).
      stream = uri_.protocol == DeviceProtocol::kScip && uri_.path.empty()
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
      startSession(*stream);
      event(uri_.text + ": streaming from " + identity());
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
        stopSession(*stream);
      } catch (const std::exception&) {
      }
    }
    {
      std::lock_guard<std::mutex> lock(mutex_);
      addCounters(&decoded_total_, decoderCounters());
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

void StreamDevice::streamOnce(ByteStream& stream) {
  std::vector<uint8_t> buffer(64 * 1024);
  std::vector<std::string> errors;
  int64_t last_byte_utime = now_();
  int errors_in_a_row = 0;
  bool first = true;  // decode what startSession read ahead
  while (!stop_) {
    beat();
    const size_t n = first ? 0 : stream.read(buffer.data(), buffer.size(), options_.read_poll_ms);
    const int64_t now = now_();
    service(stream, now);
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
    errors.clear();
    const int items = onBytes(buffer.data(), n, now, &errors);
    errors_in_a_row = items == 0 ? errors_in_a_row + static_cast<int>(errors.size()) : 0;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      decoded_now_ = decoderCounters();
      clock_resets_now_ = clockResets();
      items_ += items;
    }
    for (const std::string& e : errors) event(uri_.text + ": " + e);
    if (errors_in_a_row >= options_.error_run) {
      throw StreamError(std::to_string(errors_in_a_row) +
                        " decode errors in a row with nothing decoded; reconnecting");
    }
  }
}

}  // namespace sweepmap
