#include "tools/view/client_queue.hpp"

namespace sweepmap {
namespace {

size_t sizeOf(const ViewFrame& f) { return f.data ? f.data->size() : 0; }

}  // namespace

void ClientQueue::push(const ViewFrame& f) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (f.kind == ViewFrame::kLatest) {
    for (ViewFrame& q : frames_) {
      if (q.kind == ViewFrame::kLatest && q.key == f.key) {
        bytes_ = bytes_ - sizeOf(q) + sizeOf(f);
        q = f;
        ++counters_.replaced;
        return;
      }
    }
  }
  if (f.kind != ViewFrame::kControl) dropForRoom(sizeOf(f));
  if (f.kind == ViewFrame::kBulk && bytes_ + sizeOf(f) > max_bytes_) {
    countDrop(f);  // larger than the whole bound
    return;
  }
  bytes_ += sizeOf(f);
  frames_.push_back(f);
}

void ClientQueue::dropForRoom(size_t incoming) {
  for (auto it = frames_.begin(); it != frames_.end() && bytes_ + incoming > max_bytes_;) {
    if (it->kind != ViewFrame::kBulk) {
      ++it;
      continue;
    }
    countDrop(*it);
    bytes_ -= sizeOf(*it);
    it = frames_.erase(it);
  }
}

void ClientQueue::countDrop(const ViewFrame& f) {
  ++counters_.frames_dropped;
  counters_.bytes_dropped += static_cast<int64_t>(sizeOf(f));
  counters_.points_dropped += f.points;
  if (f.effect == ViewFrame::kVoxels) voxels_stale_ = true;
}

bool ClientQueue::takeVoxelsStale() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!voxels_stale_ || !frames_.empty()) return false;
  voxels_stale_ = false;
  ++counters_.voxel_resyncs;
  return true;
}

bool ClientQueue::voxelsStale() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return voxels_stale_ && frames_.empty();
}

std::optional<ViewFrame> ClientQueue::pop() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (frames_.empty()) return std::nullopt;
  ViewFrame f = std::move(frames_.front());
  frames_.pop_front();
  bytes_ -= sizeOf(f);
  ++counters_.frames_sent;
  counters_.bytes_sent += static_cast<int64_t>(sizeOf(f));
  account(f);
  return f;
}

// The page's arithmetic (view.js): a thin keeps ceil(m/2) of each chunk's m points.
void ClientQueue::account(const ViewFrame& f) {
  switch (f.effect) {
    case ViewFrame::kAddPoints:
      drawn_[f.sweep].push_back(f.points);
      counters_.points_drawn += f.points;
      break;
    case ViewFrame::kThin:
      if (auto it = drawn_.find(f.sweep); it != drawn_.end()) {
        for (uint32_t& m : it->second) {
          counters_.points_drawn -= m / 2;
          m -= m / 2;
        }
      }
      break;
    case ViewFrame::kRemove:
      if (auto it = drawn_.find(f.sweep); it != drawn_.end()) {
        for (uint32_t m : it->second) counters_.points_drawn -= m;
        drawn_.erase(it);
      }
      break;
    case ViewFrame::kReset:
      drawn_.clear();
      counters_.points_drawn = 0;
      break;
    case ViewFrame::kNone:
    case ViewFrame::kVoxels:
      break;
  }
}

ClientCounters ClientQueue::counters() const {
  std::lock_guard<std::mutex> lock(mutex_);
  ClientCounters c = counters_;
  c.queued_bytes = bytes_;
  c.queued_frames = frames_.size();
  return c;
}

}  // namespace sweepmap
