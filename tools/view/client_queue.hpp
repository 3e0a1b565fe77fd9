// One page's outgoing frames: bounded in bytes, so a slow or stalled page costs memory up to
// the bound and nothing else. When a frame does not fit, the oldest droppable (kBulk) frames go
// first, counted; a kLatest frame replaces the queued one of its key (newest wins); kControl
// frames always pass (they are small). It also counts what the page has been sent and still
// draws (points per view sweep, with the same thin/remove/reset arithmetic the page applies),
// so the page can check it draws exactly what it was sent.
#pragma once

#include <cstdint>
#include <deque>
#include <map>
#include <mutex>
#include <optional>
#include <vector>

#include "tools/view/view_model.hpp"

namespace sweepmap {

struct ClientCounters {
  int64_t frames_sent = 0;
  int64_t bytes_sent = 0;
  int64_t frames_dropped = 0;  // bulk frames dropped for the bound
  int64_t bytes_dropped = 0;
  int64_t replaced = 0;        // kLatest frames replaced by a newer one before being sent
  int64_t points_dropped = 0;  // cloud points in dropped frames
  int64_t voxel_resyncs = 0;   // the page's voxels replaced after it lost a voxel frame
  int64_t points_drawn = 0;    // points sent that the page still draws
  size_t queued_bytes = 0;
  size_t queued_frames = 0;
};

class ClientQueue {
 public:
  explicit ClientQueue(size_t max_bytes) : max_bytes_(max_bytes) {}
  void push(const ViewFrame& f);
  // The oldest frame, taken off the queue and counted as sent; nullopt when empty.
  std::optional<ViewFrame> pop();
  ClientCounters counters() const;
  // Whether a voxel frame was dropped (the page's voxels differ from the view's until it is
  // sent ViewModel::voxelSnapshot()) and the queue has drained since, so the snapshot has
  // room: a stalled page is not sent one snapshot after another. Take clears the flag and
  // counts a resync.
  bool takeVoxelsStale();
  bool voxelsStale() const;

 private:
  void dropForRoom(size_t incoming);
  void countDrop(const ViewFrame& f);
  void account(const ViewFrame& f);

  mutable std::mutex mutex_;
  size_t max_bytes_;
  std::deque<ViewFrame> frames_;
  size_t bytes_ = 0;
  ClientCounters counters_;
  bool voxels_stale_ = false;
  std::map<int64_t, std::vector<uint32_t>> drawn_;  // view sweep -> points of each chunk sent
};

}  // namespace sweepmap
