// Simulation only: publishes the true phi_offset of every sweep on TRUTH_SWEEP, from the
// simulated shaft's true motion, the lidar scans and the motor's SCAN_WINDOW. Runs beside
// the simulated lidar (offline in `sweepmap sim`, live in `sweepmap-lidar --sim`).
#pragma once

#include <deque>

#include "devices/shaft_trajectory.hpp"
#include "processes/node.hpp"

namespace sweepmap {

class TruthSweepNode : public Node {
 public:
  TruthSweepNode(const ShaftTrajectory* truth, double alpha_true_rad);
  std::vector<std::string> subscriptions() const override;

 protected:
  void handle(const Message& msg, Outbox& out) override;

 private:
  const ShaftTrajectory* truth_;
  double alpha_true_rad_;
  std::deque<int64_t> scan_utimes_;  // recent scans' first-ray times
  struct Window {
    int64_t sweep_id, start, end;
  };
  std::deque<Window> windows_;
  void publishReady(int64_t now, Outbox& out);
};

}  // namespace sweepmap
