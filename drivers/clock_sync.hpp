// Maps a device's wrapping tick counter (SCIP: milliseconds, 24 bits, wraps every 4.66 h)
// onto host time.
//
// Model: host(u) = h0 + (u - u0) * tick_us * (1 + rho), u the unwrapped counter. The
// anchor (u0, h0) comes from a request/response exchange (SCIP TM1: host send and receive
// times around the device's answer; the midpoint, error <= half the round trip plus the
// counter's resolution), or, without one, from the first streamed stamp (then every mapped
// time is late by the device's fixed latency from stamp to arrival, but steadily so). The rate
// error rho (the two oscillators' relative drift, e.g. 100 ppm) is the slope of the lower envelope
// of (arrival - stamp): a message arrives a constant minimum latency after its stamp plus a
// non-negative delay, so the per-bucket minima lie above a line whose slope is rho whatever that
// latency is: the lower envelope, fitted as in Moon, Skelly & Towsley (1999).
//
// A stamp that does not fit (the device reset its clock, or it jumped) resets the mapping:
// after `jump_confirm` consecutive stamps whose residual is outside
// [-max_early_us, +max_late_us] around the learned latency, the anchor is moved so that the
// newest stamp has the learned latency again; the rate is kept (same oscillator). Without an
// exchange, a stamp that arrives before its mapped time shows that the anchor was late (its
// message was held up, as on a loaded host at start-up): the mapping moves earlier by as much.
//
// The times returned follow the device's own intervals: when the mapping moves (a later
// anchor, a new rate fit), they slew toward it by at most max_slew of each interval, so they
// never go back and never bunch up; only a reset of the device's clock is followed at once.
#pragma once

#include <cstdint>
#include <deque>

namespace sweepmap {

class DeviceClockSync {
 public:
  struct Options {
    int counter_bits = 24;
    double tick_us = 1000.0;
    double bucket_s = 0.25;          // one envelope point (the minimum) per bucket of host time
    double window_s = 120.0;         // envelope points kept for the rate fit
    double min_span_s = 2.0;         // fit the rate once the envelope spans this much
    double max_early_us = 20000.0;   // arrival this much before the mapped stamp: a jump
    double max_late_us = 1000000.0;  // or this much after it (beyond any buffering)
    int jump_confirm = 3;
    double max_backstep_us = 2000000.0;  // a counter going back further has been reset
    double max_rate_ppm = 500.0;         // a fitted rate beyond this is not believed
    double max_slew = 0.02;              // returned intervals within +-2 % of the device's
  };

  DeviceClockSync() : DeviceClockSync(Options{}) {}
  explicit DeviceClockSync(const Options& options);

  // A request/response exchange: the device's counter read `raw` at some instant between
  // host_send_us and host_recv_us. Consecutive exchanges (with no observe() between them)
  // narrow the anchor down: each says the counter became `raw` within
  // [host_send_us - 1 tick, host_recv_us]; their intersection is kept (a new series starts
  // when they disagree). Mapped times are the middle of a counter value's tick. Keeps the rate.
  void anchor(int64_t raw, int64_t host_send_us, int64_t host_recv_us);
  // Width of the anchor's uncertainty interval [us] (after anchor()).
  double anchorUncertaintyUs() const { return anchor_hi_ - anchor_lo_; }
  // A streamed stamp and the host time its message arrived (complete). Returns the host time
  // [us] of the stamp's instant.
  int64_t observe(int64_t raw, int64_t host_arrival_us);

  bool synced() const { return have_anchor_; }
  // How much faster the device's counter runs than the host clock [ppm].
  double ratePpm() const { return (1.0 / (1.0 + rho_) - 1.0) * 1e6; }
  // Minimum arrival - mapped stamp seen [us] (the device's + transport's fixed latency).
  double latencyUs() const { return latency_us_; }
  int64_t resets() const { return resets_; }
  int64_t wraps() const { return wraps_; }
  // Forget everything (a new connection to a device that may have been power-cycled).
  void clear();

 private:
  struct EnvelopePoint {
    int64_t bucket;
    double x_us;  // (u - u0) * tick_us
    double y_us;  // arrival - h0 - x_us: latency + rho * x
  };
  int64_t unwrap(int64_t raw, bool* jumped);
  double mapped(int64_t u) const;
  void addEnvelope(int64_t u, int64_t arrival);
  void fitRate();

  Options options_;
  bool have_raw_ = false;
  int64_t last_raw_ = 0;
  int64_t unwrapped_ = 0;
  bool have_anchor_ = false;
  bool anchoring_ = false;                    // inside a series of anchor() calls
  double anchor_lo_ = 0.0, anchor_hi_ = 0.0;  // host time at which the counter became u0
  int64_t u0_ = 0;
  double h0_ = 0.0;
  double rho_ = 0.0;
  double latency_us_ = 0.0;
  bool have_latency_ = false;
  int outliers_ = 0;
  int64_t resets_ = 0;
  int64_t wraps_ = 0;
  std::deque<EnvelopePoint> envelope_;
  bool exchanged_ = false;  // the anchor comes from anchor(), not from a first arrival
  // The last time returned, for the slew limit.
  bool have_out_ = false;
  int64_t out_u_ = 0;
  double out_us_ = 0.0;
  // The mapped time of u, slewed from the last one returned (discontinuous: follow at once).
  int64_t slewed(int64_t u, bool discontinuous);
};

}  // namespace sweepmap
