#include "drivers/clock_sync.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace sweepmap {

DeviceClockSync::DeviceClockSync(const Options& options) : options_(options) {}

void DeviceClockSync::clear() {
  have_raw_ = false;
  have_anchor_ = false;
  exchanged_ = false;
  have_out_ = false;
  anchoring_ = false;
  have_latency_ = false;
  rho_ = 0.0;
  latency_us_ = 0.0;
  outliers_ = 0;
  envelope_.clear();
}

int64_t DeviceClockSync::unwrap(int64_t raw, bool* jumped) {
  const int64_t modulus = int64_t{1} << options_.counter_bits;
  raw &= modulus - 1;
  *jumped = false;
  if (!have_raw_) {
    have_raw_ = true;
    last_raw_ = raw;
    unwrapped_ = raw;
    return unwrapped_;
  }
  const int64_t step = (raw - last_raw_ + modulus) % modulus;
  if (step < modulus / 2) {
    if (raw < last_raw_) ++wraps_;
    unwrapped_ += step;
  } else {
    // Backwards. A little: a message stamped before the last one seen (a scan's stamp is its
    // first ray, older than a TM1 answer sent just before the stream). A lot: the counter
    // was reset or jumped; follow it at once.
    const int64_t back = modulus - step;
    unwrapped_ -= back;
    *jumped = static_cast<double>(back) * options_.tick_us > options_.max_backstep_us;
  }
  last_raw_ = raw;
  return unwrapped_;
}

double DeviceClockSync::mapped(int64_t u) const {
  return h0_ + static_cast<double>(u - u0_) * options_.tick_us * (1.0 + rho_);
}

void DeviceClockSync::anchor(int64_t raw, int64_t host_send_us, int64_t host_recv_us) {
  bool jumped = false;
  const int64_t u = unwrap(raw, &jumped);
  const double tick = options_.tick_us;
  const bool continues = anchoring_ && have_anchor_ && !jumped;
  if (!continues) u0_ = u;
  // When the counter became u0, given that it showed u in [send, recv] (drift over a series
  // of exchanges is negligible).
  const double lo = static_cast<double>(host_send_us) - static_cast<double>(u - u0_ + 1) * tick;
  const double hi = static_cast<double>(host_recv_us) - static_cast<double>(u - u0_) * tick;
  if (continues && std::max(lo, anchor_lo_) <= std::min(hi, anchor_hi_)) {
    anchor_lo_ = std::max(lo, anchor_lo_);
    anchor_hi_ = std::min(hi, anchor_hi_);
  } else {
    u0_ = u;
    anchor_lo_ = static_cast<double>(host_send_us) - tick;
    anchor_hi_ = static_cast<double>(host_recv_us);
  }
  h0_ = 0.5 * (anchor_lo_ + anchor_hi_) + 0.5 * tick;
  have_anchor_ = true;
  exchanged_ = true;
  have_out_ = false;  // an exchange is better than anything returned before it
  anchoring_ = true;
  envelope_.clear();
  have_latency_ = false;
  outliers_ = 0;
}

void DeviceClockSync::addEnvelope(int64_t u, int64_t arrival) {
  const double x = static_cast<double>(u - u0_) * options_.tick_us;
  const double y = static_cast<double>(arrival) - h0_ - x;
  const auto bucket =
      static_cast<int64_t>(std::floor(static_cast<double>(arrival) / (options_.bucket_s * 1e6)));
  if (!envelope_.empty() && envelope_.back().bucket == bucket) {
    if (y < envelope_.back().y_us) envelope_.back() = {bucket, x, y};
  } else {
    envelope_.push_back({bucket, x, y});
  }
  const auto keep = static_cast<int64_t>(options_.window_s / options_.bucket_s);
  while (!envelope_.empty() && envelope_.front().bucket < bucket - keep) envelope_.pop_front();
}

void DeviceClockSync::fitRate() {
  // Completed buckets only: the current one's minimum may still fall.
  if (envelope_.size() < 4) return;
  const size_t n = envelope_.size() - 1;
  if (envelope_[n - 1].x_us - envelope_.front().x_us < options_.min_span_s * 1e6) return;
  // The line below every point that is closest to them on average (Moon, Skelly, Towsley
  // 1999): an edge of the points' lower convex hull, the one spanning the mean x. Unlike a
  // least-squares fit of the minima it is not pulled up by delays, and it stays unbiased by
  // the counter's 1-tick quantisation once the window spans a quantisation period.
  std::vector<size_t> hull;
  for (size_t i = 0; i < n; ++i) {
    while (hull.size() >= 2) {
      const EnvelopePoint& a = envelope_[hull[hull.size() - 2]];
      const EnvelopePoint& b = envelope_[hull.back()];
      const EnvelopePoint& c = envelope_[i];
      const double cross =
          (b.x_us - a.x_us) * (c.y_us - a.y_us) - (b.y_us - a.y_us) * (c.x_us - a.x_us);
      if (cross > 0.0) break;  // a-b-c turns left: b stays on the lower hull
      hull.pop_back();
    }
    hull.push_back(i);
  }
  if (hull.size() < 2) return;
  double mean_x = 0.0;
  for (size_t i = 0; i < n; ++i) mean_x += envelope_[i].x_us;
  mean_x /= double(n);
  size_t k = 0;
  while (k + 2 < hull.size() && envelope_[hull[k + 1]].x_us < mean_x) ++k;
  const EnvelopePoint& a = envelope_[hull[k]];
  const EnvelopePoint& b = envelope_[hull[k + 1]];
  if (b.x_us <= a.x_us) return;
  // y = latency + rho * x (x from the anchor): with rho known, the mapping is exact at u0.
  const double rho = (b.y_us - a.y_us) / (b.x_us - a.x_us);
  // No crystal is this far off: an edge this steep comes from arrivals held up (a loaded
  // host at start-up) at the window's end; keep the previous estimate until it passes.
  if (std::fabs(rho) > options_.max_rate_ppm * 1e-6) return;
  rho_ = rho;
  latency_us_ = std::max(0.0, a.y_us - rho_ * a.x_us);
  have_latency_ = true;
}

int64_t DeviceClockSync::observe(int64_t raw, int64_t host_arrival_us) {
  bool jumped = false;
  const int64_t u = unwrap(raw, &jumped);
  anchoring_ = false;
  if (!have_anchor_) {
    // No exchange: anchor on the first stamp with zero latency (times run late by the
    // device's fixed latency, but steadily).
    u0_ = u;
    h0_ = static_cast<double>(host_arrival_us);
    have_anchor_ = true;
  }
  const double early = static_cast<double>(host_arrival_us) - mapped(u);
  if (!exchanged_ && !jumped && early < 0.0 && early > -options_.max_backstep_us) {
    // Arrived before its mapped time: the anchor (the first arrival) was late by as much.
    h0_ += early;
    for (EnvelopePoint& p : envelope_) p.y_us -= early;
  }
  if (!have_latency_) {
    // Until the rate is fitted: the smallest delay seen since the anchor.
    const double early = std::max(0.0, static_cast<double>(host_arrival_us) - mapped(u));
    latency_us_ = envelope_.empty() ? early : std::min(latency_us_, early);
  }
  const double residual = static_cast<double>(host_arrival_us) - mapped(u) - latency_us_;
  if (jumped || residual < -options_.max_early_us || residual > options_.max_late_us) {
    if (jumped || ++outliers_ >= options_.jump_confirm) {
      // Re-anchor so that this stamp has the learned latency; keep the rate.
      u0_ = u;
      h0_ = static_cast<double>(host_arrival_us) - latency_us_;
      envelope_.clear();
      outliers_ = 0;
      ++resets_;
      return slewed(u, /*discontinuous=*/true);
    }
    return slewed(u, jumped);
  }
  outliers_ = 0;
  addEnvelope(u, host_arrival_us);
  fitRate();
  return slewed(u, false);
}

int64_t DeviceClockSync::slewed(int64_t u, bool discontinuous) {
  double t = mapped(u);
  const double device_us = static_cast<double>(u - out_u_) * options_.tick_us;
  if (have_out_ && !discontinuous && device_us > 0.0) {
    t = std::clamp(t, out_us_ + device_us * (1.0 - options_.max_slew),
                   out_us_ + device_us * (1.0 + options_.max_slew));
  }
  if (!have_out_ || device_us > 0.0 || discontinuous) {
    have_out_ = true;
    out_u_ = u;
    out_us_ = t;
  }
  return static_cast<int64_t>(std::llround(t));
}

}  // namespace sweepmap
