#include "core/progress.hpp"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <sstream>

namespace sweepmap {

namespace {

double steadySeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

std::string formatSeconds(double s) {
  std::ostringstream out;
  if (s < 90) {
    out << static_cast<int>(std::ceil(s)) << " s";
  } else {
    out << static_cast<int>(std::ceil(s / 60)) << " min";
  }
  return out.str();
}

}  // namespace

Progress::Progress(std::string what, ProgressOptions options)
    : what_(std::move(what)), o_(std::move(options)) {
  if (!o_.is_terminal) o_.is_terminal = [] { return isatty(STDERR_FILENO) == 1; };
  if (!o_.now_s) o_.now_s = steadySeconds;
  if (!o_.out) o_.out = &std::cerr;
  active_ = o_.enabled && o_.is_terminal();
  if (active_) start_s_ = stage_start_s_ = o_.now_s();
}

Progress::~Progress() { finish(); }

void Progress::stage(const std::string& name) {
  if (!active_) return;
  std::lock_guard<std::mutex> lock(mutex_);
  stage_ = name;
  last_fraction_ = -1;
  stage_start_s_ = o_.now_s();
  last_draw_s_ = -1e300;  // a new stage shows at once
}

void Progress::update(double fraction) {
  if (!active_) return;
  std::lock_guard<std::mutex> lock(mutex_);
  last_fraction_ = fraction;
  const double now = o_.now_s();
  if (now - start_s_ < o_.delay_s) return;
  if (now - last_draw_s_ < o_.min_interval_s && fraction < 1.0) return;
  draw(fraction, now);
}

void Progress::tick() {
  if (!active_) return;
  double fraction;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    fraction = last_fraction_;
    last_draw_s_ = -1e300;
  }
  update(fraction);
}

void Progress::draw(double fraction, double now) {
  std::ostringstream line;
  line << what_ << ":";
  if (!stage_.empty()) line << " " << stage_;
  if (fraction >= 0) {
    const double f = std::min(1.0, fraction);
    line << " " << static_cast<int>(std::floor(100 * f)) << "%";
    const double elapsed = now - stage_start_s_;
    if (f > 0.01 && f < 1.0 && elapsed > 0) {
      line << ", " << formatSeconds(elapsed * (1 - f) / f) << " left";
    }
  } else {
    line << ", " << formatSeconds(now - stage_start_s_);
  }
  std::string text = line.str();
  const size_t width = text.size();
  if (width < last_width_) text += std::string(last_width_ - width, ' ');  // erase the rest
  *o_.out << "\r" << text << std::flush;
  last_width_ = width;
  last_draw_s_ = now;
  drawn_ = true;
}

void Progress::finish() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (drawn_ && last_width_ > 0) {
    *o_.out << "\n" << std::flush;
    last_width_ = 0;
  }
}

ProgressTicker::ProgressTicker(Progress& progress, double period_s) {
  thread_ = std::thread([this, &progress, period_s] {
    // Short sleeps, so that the ticker's end never waits for a whole period.
    const int steps = std::max(1, static_cast<int>(period_s / 0.05));
    for (int n = 1; !stop_; ++n) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      if (n % steps == 0 && !stop_) progress.tick();
    }
  });
}

ProgressTicker::~ProgressTicker() {
  stop_ = true;
  thread_.join();
}

}  // namespace sweepmap
