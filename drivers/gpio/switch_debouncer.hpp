// Software debounce of a switch input from its kernel-timestamped edges: a change of level
// is accepted once the level has stayed the same for `debounce_ns`, and it is dated by the
// first edge of the transition. A contact that bounces (several toggles within the debounce
// time) gives one edge; a glitch that returns to the accepted level gives none.
#pragma once

#include <cstdint>
#include <vector>

namespace sweepmap {

struct DebouncedEdge {
  int64_t t_ns = 0;  // the first raw edge of the transition
  bool level = false;
};

class SwitchDebouncer {
 public:
  SwitchDebouncer(bool level, int64_t debounce_ns)
      : accepted_(level), raw_(level), debounce_ns_(debounce_ns) {}
  // A raw edge: the level after it, at the kernel's time `t_ns` (edges in time order).
  void onEdge(int64_t t_ns, bool level, std::vector<DebouncedEdge>& accepted);
  // Accepts a pending change that has been stable for the debounce time at `now_ns`.
  void update(int64_t now_ns, std::vector<DebouncedEdge>& accepted);
  bool level() const { return accepted_; }

 private:
  bool accepted_;
  bool raw_;
  bool pending_ = false;  // raw edges since the level was last stable
  int64_t first_ns_ = 0;  // first edge away from the accepted level
  int64_t last_ns_ = 0;   // latest raw edge
  int64_t debounce_ns_;
};

}  // namespace sweepmap
