// Progress of a long command on stderr: "replay: 42%, 12 s left", redrawn in place.
// Shown only on a terminal (never in a pipe, a log file or with --json) and only once the
// work has run for `delay_s` (2 s): a short command prints nothing. The terminal test and
// the clock are injectable, so the behaviour is testable without a terminal or waiting.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <iosfwd>
#include <mutex>
#include <string>
#include <thread>

namespace sweepmap {

struct ProgressOptions {
  bool enabled = true;                // false: --json, --quiet, or a caller that has no use
  std::function<bool()> is_terminal;  // default: stderr is a terminal (isatty(2))
  std::function<double()> now_s;      // default: a steady clock [s]
  std::ostream* out = nullptr;        // default: std::cerr
  double delay_s = 2.0;               // nothing shown before this much time has passed
  double min_interval_s = 0.2;        // redraws at most this often
};

class Progress {
 public:
  // `what`: the command ("replay"), the first word of every line.
  explicit Progress(std::string what, ProgressOptions options = {});
  ~Progress();  // ends the line if one was drawn
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  // A new stage ("mode 3", "ours"): its fraction starts again, and its time left with it.
  void stage(const std::string& name);
  // The fraction of the current stage done, 0..1 (clamped); a negative one is unknown (the
  // stage's time so far is shown instead of the time left).
  void update(double fraction);
  // Redraws with the last fraction (ProgressTicker: a stage with no fractions of its own).
  void tick();
  // Ends the line now (before printing a result).
  void finish();

  bool shown() const { return drawn_; }    // a line has been drawn
  bool active() const { return active_; }  // enabled, and stderr is a terminal

 private:
  void draw(double fraction, double now);

  std::mutex mutex_;  // update() and a ProgressTicker's tick() may run on two threads
  std::string what_;
  ProgressOptions o_;
  bool active_;
  std::string stage_;
  double start_s_ = 0, stage_start_s_ = 0, last_draw_s_ = -1e300;
  bool drawn_ = false;
  size_t last_width_ = 0;
  double last_fraction_ = -1;
};

// Redraws a Progress every `period_s` on a thread of its own while it lives: for a stage that
// is one long call (a solver) with no fraction to report.
class ProgressTicker {
 public:
  explicit ProgressTicker(Progress& progress, double period_s = 0.5);
  ~ProgressTicker();
  ProgressTicker(const ProgressTicker&) = delete;
  ProgressTicker& operator=(const ProgressTicker&) = delete;

 private:
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace sweepmap
