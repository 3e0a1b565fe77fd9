#include "drivers/real_lidar.hpp"

namespace sweepmap {

RealLidar::RealLidar(const DeviceUri& uri, std::unique_ptr<LidarSession> session,
                     const RealLidarOptions& options, std::function<int64_t()> now)
    : StreamDevice(uri, options, std::move(now)),
      session_(std::move(session)),
      max_queued_scans_(options.max_queued_scans) {}

RealLidar::~RealLidar() { stopWorker(); }

std::vector<Scan2D> RealLidar::poll(int64_t) {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<Scan2D> out;
  out.swap(queue_);
  return out;
}

void RealLidar::startSession(ByteStream& stream) { session_->start(stream, clock()); }

int RealLidar::onBytes(const uint8_t* data, size_t size, int64_t arrival_utime,
                       std::vector<std::string>* errors) {
  decoded_.clear();
  session_->onBytes(data, size, arrival_utime, &decoded_, errors);
  LidarSession::Counters counters = session_->sessionCounters();
  std::lock_guard<std::mutex> lock(mutex_);
  session_counters_.swap(counters);
  for (Scan2D& s : decoded_) queue_.push_back(std::move(s));
  if (queue_.size() > max_queued_scans_) {
    const size_t drop = queue_.size() - max_queued_scans_;
    queue_.erase(queue_.begin(), queue_.begin() + static_cast<std::ptrdiff_t>(drop));
    queue_drops_ += static_cast<int64_t>(drop);
  }
  return static_cast<int>(decoded_.size());
}

std::vector<std::pair<std::string, int64_t>> RealLidar::extraCounters() {
  std::lock_guard<std::mutex> lock(mutex_);
  LidarSession::Counters out = {{"queue_drops", queue_drops_}};
  out.insert(out.end(), session_counters_.begin(), session_counters_.end());
  return out;
}

}  // namespace sweepmap
