#include "drivers/gpio/switch_debouncer.hpp"

namespace sweepmap {

void SwitchDebouncer::onEdge(int64_t t_ns, bool level, std::vector<DebouncedEdge>& accepted) {
  update(t_ns, accepted);  // stable until this edge: accepted first
  if (!pending_ && level != accepted_) first_ns_ = t_ns;
  if (level != raw_ || level != accepted_) pending_ = true;
  raw_ = level;
  last_ns_ = t_ns;
}

void SwitchDebouncer::update(int64_t now_ns, std::vector<DebouncedEdge>& accepted) {
  if (!pending_ || now_ns - last_ns_ < debounce_ns_) return;
  if (raw_ != accepted_) {
    accepted_ = raw_;
    accepted.push_back({first_ns_, accepted_});
  }
  pending_ = false;
}

}  // namespace sweepmap
