#include "calib/plate_model.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace sweepmap {
namespace {

double logistic(double s) { return 1.0 / (1.0 + std::exp(-s)); }

// Where the ray crosses the plane z = z_m, if it goes down to it.
std::optional<Eigen::Vector3d> crossing(const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                                        double z_m) {
  if (!(d.z() < -1e-9)) return std::nullopt;
  const double t = (z_m - o.z()) / d.z();
  if (!(t > 0.0)) return std::nullopt;
  return o + t * d;
}

}  // namespace

PlateModel PlateModel::fromConfig(const PlateConfig& plate) {
  PlateModel m;
  m.height_m = plate.height_mm * 1e-3;
  m.thickness_m = plate.thickness_mm * 1e-3;
  m.hypotenuse_m = plate.hypotenuse_mm * 1e-3;
  m.base_distance_m = plate.base_distance_mm * 1e-3;
  m.range_gate_m = plate.range_gate_mm * 1e-3;
  return m;
}

namespace {

// The ray's margins inside the model plate at `angle_rad` [m]: beyond the hypotenuse, inside
// each leg, where it meets the solid (all >= 0: the ray ends on the plate). nullopt when the
// ray does not go down to the upper surface.
std::optional<Eigen::Vector3d> plateMargins(const PlateModel& m, const Eigen::Vector3d& o,
                                            const Eigen::Vector3d& d, double angle_rad) {
  const auto top = crossing(o, d, m.height_m);
  if (!top) return std::nullopt;
  const double c = std::cos(angle_rad), s = std::sin(angle_rad);
  const double half = 0.5 * m.hypotenuse_m;
  // Plate frame: u along the middle line (from the axis), v across it.
  const auto uv = [&](const Eigen::Vector3d& p) {
    return Eigen::Vector2d(c * p.x() + s * p.y(), -s * p.x() + c * p.y());
  };
  const Eigen::Vector2d a = uv(*top);
  // Where the ray meets the solid: its upper surface, or, when it passes inside the
  // hypotenuse there and beyond it at the lower surface, the hypotenuse's face (the rays go
  // outward, so one edge decides both: the lower crossing beyond the hypotenuse). One smooth
  // edge for the two: a sum of a top and a face term had a notch of 1 / slope (0.5 mm) where
  // they meet, which the real plate has not, and turned alpha by ~0.02 deg.
  Eigen::Vector2d b = a;
  if (m.thickness_m > 0.0) {
    const auto bottom = crossing(o, d, m.height_m - m.thickness_m);
    if (bottom) b = uv(*bottom);
  }
  Eigen::Vector2d hit = a;
  if (a.x() < m.base_distance_m && b.x() > a.x()) {
    hit = a + std::min(1.0, (m.base_distance_m - a.x()) / (b.x() - a.x())) * (b - a);
  }
  // Inside both legs (|v| <= half - (u - base)) where it meets the solid.
  const double legs = half - (hit.x() - m.base_distance_m);
  return Eigen::Vector3d(b.x() - m.base_distance_m, legs - hit.y(), legs + hit.y());
}

}  // namespace

double plateCoverage(const PlateModel& m, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                     double angle_rad) {
  const auto e = plateMargins(m, o, d, angle_rad);
  if (!e) return 0.0;
  const double k = 4.0 / m.edge_m;  // logistic slope: 0.12 .. 0.88 across edge_m
  return logistic(k * e->x()) * logistic(k * e->y()) * logistic(k * e->z());
}

bool plateCovers(const PlateModel& m, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                 double angle_rad) {
  const auto e = plateMargins(m, o, d, angle_rad);
  return e && e->x() >= 0.0 && e->y() >= 0.0 && e->z() >= 0.0;
}

namespace {

// Whether a ray's range agrees with its crossing of the upper surface.
bool inGate(const PlateModel& m, const PlateRay& r, const Eigen::Vector3d& top) {
  return std::fabs(r.range_m - (top - r.origin).norm()) <= m.range_gate_m;
}

}  // namespace

std::vector<char> plateHits(const PlateModel& m, const std::vector<PlateRay>& rays) {
  std::vector<char> hits(rays.size(), 0);
  for (size_t i = 0; i < rays.size(); ++i) {
    const auto top = crossing(rays[i].origin, rays[i].direction, m.height_m);
    hits[i] = top && inGate(m, rays[i], *top);
  }
  return hits;
}

namespace {

// The measured-minus-predicted centroid direction with the measured weight `hit(i, ray,
// crossing)` and the predicted coverage `cover(ray)`.
template <class Hit, class Cover>
std::optional<double> centroidMismatch(const PlateModel& m, const std::vector<PlateRay>& rays,
                                       Hit&& hit, Cover&& cover) {
  Eigen::Vector2d measured = Eigen::Vector2d::Zero(), predicted = Eigen::Vector2d::Zero();
  double hits = 0.0, weight = 0.0;
  for (size_t i = 0; i < rays.size(); ++i) {
    const PlateRay& r = rays[i];
    const auto top = crossing(r.origin, r.direction, m.height_m);
    if (!top) continue;
    const double h = hit(i, r, *top);
    if (h < 0.0) continue;  // in neither centroid
    measured += h * top->head<2>();
    hits += h;
    const double w = cover(r);
    predicted += w * top->head<2>();
    weight += w;
  }
  if (!(hits > 0.0) || !(weight > 0.0)) return std::nullopt;
  // Both sums' directions: the weights' totals do not change them.
  return std::atan2(predicted.x() * measured.y() - predicted.y() * measured.x(),
                    predicted.dot(measured));
}

}  // namespace

std::optional<double> plateCentroidMismatch(const PlateModel& m, const std::vector<PlateRay>& rays,
                                            double angle_rad, const std::vector<char>* given) {
  return centroidMismatch(
      m, rays,
      [&](size_t i, const PlateRay& r, const Eigen::Vector3d& top) {
        return (given ? (*given)[i] != 0 : inGate(m, r, top)) ? 1.0 : 0.0;
      },
      [&](const PlateRay& r) { return plateCoverage(m, r.origin, r.direction, angle_rad); });
}

std::optional<double> plateSampledMismatch(const PlateModel& m, const std::vector<PlateRay>& rays,
                                           double angle_rad, const std::vector<double>& weights) {
  return centroidMismatch(
      m, rays, [&](size_t i, const PlateRay&, const Eigen::Vector3d&) { return weights[i]; },
      [&](const PlateRay& r) {
        return plateCovers(m, r.origin, r.direction, angle_rad) ? 1.0 : 0.0;
      });
}

std::vector<double> plateHitWeights(const PlateModel& m, const std::vector<PlateRay>& rays,
                                    const std::vector<PlateRayBeams>& beams) {
  const std::vector<char> hits = plateHits(m, rays);
  std::vector<double> w(hits.begin(), hits.end());
  if (beams.empty()) return w;
  if (beams.size() != rays.size())
    throw std::invalid_argument("plateHitWeights: " + std::to_string(beams.size()) +
                                " neighbour records for " + std::to_string(rays.size()) + " rays");
  for (size_t i = 0; i < rays.size(); ++i) {
    const auto& b = beams[i];
    if (!hits[i]) {
      // Beside a beam that gave no return: its neighbour on the plate may have dropped out.
      if (b.range[0] == 0.0f || b.range[1] == 0.0f) w[i] = -1.0;
      continue;
    }
    for (size_t side = 0; side < 2; ++side) {
      const int j = b.next[side];
      // The run goes on, or no return next to it (no depth edge to mix at); else the ray past
      // it is the plate's last or the background's first.
      if (b.range[side] == 0.0f || (j >= 0 && hits[size_t(j)])) continue;
      if (j >= 0) w[size_t(j)] = -1.0;
    }
  }
  return w;
}

namespace {

// Where the step `mismatch(a) = v` that holds at `inside` ends towards `dir` (+-1): the first
// angle with another value, to ~1e-12 rad (within ~1 rad; else 1 rad out).
template <class F>
double stepEnd(F&& mismatch, double inside, double dir) {
  const auto v = mismatch(inside);
  double in = inside, out = inside, step = 1e-6;
  for (int i = 0; i < 20; ++i) {
    out = inside + dir * step;
    if (mismatch(out) != v) break;
    in = out;
    step *= 2.0;
  }
  for (int i = 0; i < 60 && std::fabs(out - in) > 1e-12; ++i) {
    const double mid = 0.5 * (in + out);
    (mismatch(mid) == v ? in : out) = mid;
  }
  return 0.5 * (in + out);
}

// The zero of a step function of the angle that jumps through 0 at `jump`: the zero of the
// line through the middles of the two steps that meet there (the steps as samples of the
// smooth mismatch). The jump itself lies where the model's next ray flips, which a measured
// set that no model angle gives exactly (mixed pixels, the gate's noise) picks at random.
template <class F>
double secantThroughSteps(double jump, F&& mismatch) {
  const double eps = 1e-10;
  const auto before = mismatch(jump - eps), after = mismatch(jump + eps);
  if (!before || !after || !(*before > 0.0) || !(*after < 0.0)) return jump;
  const double m1 = 0.5 * (stepEnd(mismatch, jump - eps, -1.0) + jump);
  const double m2 = 0.5 * (jump + stepEnd(mismatch, jump + eps, 1.0));
  return m1 + (m2 - m1) * *before / (*before - *after);
}

}  // namespace

std::optional<double> fitPlateSampled(const PlateModel& m, const std::vector<PlateRay>& rays,
                                      const std::vector<double>& weights, double start_rad) {
  // sign(a) = +1 while the predicted centroid lies short of the measured one (mismatch > 0).
  const auto above = [&](double a, bool strict) -> std::optional<bool> {
    const auto e = plateSampledMismatch(m, rays, a, weights);
    if (!e) return std::nullopt;
    return strict ? *e > 0.0 : *e >= 0.0;
  };
  // A bracket [lo, hi] around the sign change, widened from the start.
  double step = 1e-3, lo = start_rad - step, hi = start_rad + step;
  for (int i = 0;; ++i) {
    const auto a = above(lo, true), b = above(hi, false);
    if (!a || !b) return std::nullopt;
    if (*a && !*b) break;
    if (i == 20) return std::nullopt;
    step *= 2.0;
    if (!*a) lo -= step;
    if (*b) hi += step;
  }
  // The last angle still short (mismatch > 0) and the first past it (mismatch < 0): between
  // them the model's rays are exactly the measured ones (noise-free), or the centroid jumps.
  const auto edge = [&](bool strict) {
    double l = lo, h = hi;
    for (int i = 0; i < 60 && h - l > 1e-12; ++i) {
      const double mid = 0.5 * (l + h);
      (above(mid, strict).value_or(false) ? l : h) = mid;
    }
    return 0.5 * (l + h);
  };
  const double first = edge(true), last = edge(false);
  if (last - first > 1e-9) return 0.5 * (first + last);  // the model's rays are the measured
  return secantThroughSteps(first,
                            [&](double a) { return plateSampledMismatch(m, rays, a, weights); });
}

namespace {

// The angle where ray (o, d) flips in or out of the sharp plate between lo (covered: `in_lo`)
// and hi, which differ in coverage: bisection to ~1e-12 rad.
double flipAngle(const PlateModel& m, const PlateRay& r, double lo, double hi, bool in_lo) {
  for (int i = 0; i < 50 && hi - lo > 1e-12; ++i) {
    const double mid = 0.5 * (lo + hi);
    (plateCovers(m, r.origin, r.direction, mid) == in_lo ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

// The disagreements of the counted rays with the sharp plate over [lo, hi]: their count at lo
// and the angles where it steps (+1 / -1), in order. Coverage is sampled every `grid` rad; a
// ray is taken to flip at most once between two samples (0.05 deg moves the plate's edge by
// 0.1 mm, a fraction of the rays' spacing).
struct Disagreements {
  int at_lo = 0;
  std::vector<std::pair<double, int>> steps;
};

Disagreements disagreements(const PlateModel& m, const std::vector<PlateRay>& rays,
                            const std::vector<double>& weights, double lo, double hi) {
  const int n = std::max(1, int(std::ceil((hi - lo) / (0.05 * M_PI / 180.0))));
  Disagreements d;
  for (size_t i = 0; i < rays.size(); ++i) {
    if (weights[i] < 0.0) continue;
    const bool hit = weights[i] > 0.0;
    const PlateRay& r = rays[i];
    bool prev = plateCovers(m, r.origin, r.direction, lo);
    d.at_lo += prev != hit;
    for (int k = 1; k <= n; ++k) {
      const double a0 = lo + (hi - lo) * (k - 1) / n, a1 = lo + (hi - lo) * k / n;
      const bool now = plateCovers(m, r.origin, r.direction, a1);
      if (now == prev) continue;
      d.steps.emplace_back(flipAngle(m, r, a0, a1, prev), now == hit ? -1 : +1);
      prev = now;
    }
  }
  std::sort(d.steps.begin(), d.steps.end());
  return d;
}

// Where the disagreements over [lo, hi] are fewest (steps at the same angle taken together):
// the first and last such angle, and the widest range of them (of equally wide, the first).
struct Fewest {
  double first, last;
  std::pair<double, double> widest;
};
Fewest fewestDisagreements(const Disagreements& d, double lo, double hi) {
  int count = d.at_lo, best = d.at_lo;
  double start = lo;  // where the current run at the fewest began
  bool in_best = true, have = false;
  Fewest f{lo, hi, {lo, hi}};
  const auto close = [&](double end) {
    if (!have || end - start > f.widest.second - f.widest.first) f.widest = {start, end};
    if (!have) f.first = start;
    f.last = end;
    have = true;
  };
  for (size_t i = 0; i < d.steps.size();) {
    const double angle = d.steps[i].first;
    for (; i < d.steps.size() && d.steps[i].first == angle; ++i) count += d.steps[i].second;
    if (count < best) {  // a new fewest: the runs before are no longer the fewest
      best = count;
      have = false;
      in_best = true;
      start = angle;
    } else if (count == best && !in_best) {
      in_best = true;
      start = angle;
    } else if (count != best && in_best) {
      close(angle);
      in_best = false;
    }
  }
  if (in_best) close(hi);
  return f;
}

}  // namespace

std::optional<double> fitPlateAgreeing(const PlateModel& m, const std::vector<PlateRay>& rays,
                                       const std::vector<double>& weights, double start_rad,
                                       double window_rad) {
  if (weights.size() != rays.size())
    throw std::invalid_argument("fitPlateAgreeing: " + std::to_string(weights.size()) +
                                " weights for " + std::to_string(rays.size()) + " rays");
  if (std::none_of(weights.begin(), weights.end(), [](double w) { return w > 0.0; }))
    return std::nullopt;
  double centre = start_rad;
  for (int i = 0; i < 8; ++i) {
    const double lo = centre - window_rad, hi = centre + window_rad;
    const Fewest f = fewestDisagreements(disagreements(m, rays, weights, lo, hi), lo, hi);
    if (f.first > lo && f.last < hi) return 0.5 * (f.widest.first + f.widest.second);
    centre = f.first <= lo ? lo + 0.5 * window_rad : hi - 0.5 * window_rad;
  }
  return std::nullopt;
}

PlateModelFit fitPlateModel(const PlateModel& m, const std::vector<PlateRay>& rays, int min_hits) {
  PlateModelFit f;
  Eigen::Vector2d measured = Eigen::Vector2d::Zero();
  for (const PlateRay& r : rays) {
    const auto top = crossing(r.origin, r.direction, m.height_m);
    if (!top || std::fabs(r.range_m - (*top - r.origin).norm()) > m.range_gate_m) continue;
    measured += top->head<2>();
    ++f.hits;
  }
  if (f.hits < min_hits) {
    f.reason = "plate not found: " + std::to_string(f.hits) +
               " rays meet the plate's surface in the region, need " + std::to_string(min_hits);
    return f;
  }
  // mismatch(a) = measured - predicted direction ~ a_true - a: a <- a + mismatch(a).
  double a = std::atan2(measured.y(), measured.x());
  for (int i = 0; i < 30; ++i) {
    const auto e = plateCentroidMismatch(m, rays, a);
    if (!e) {
      f.reason = "plate model: no ray covered";
      return f;
    }
    a += *e;
    f.residual_rad = *e;
    if (std::fabs(*e) < 1e-10) break;
  }
  f.found = true;
  f.angle_rad = a;
  return f;
}

}  // namespace sweepmap
