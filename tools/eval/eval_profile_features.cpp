#include "tools/eval/eval_profile_features.hpp"

#include <ceres/ceres.h>
#include <pcl/ModelCoefficients.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/sample_consensus/method_types.h>
#include <pcl/sample_consensus/model_types.h>
#include <pcl/segmentation/sac_segmentation.h>

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <optional>

namespace sweepmap::eval {

const std::array<const char*, kPieceFeatureCount> kPieceFeatures = {
    "left_diameter", "left_depth", "right_diameter", "right_depth",
    "rect_length",   "rect_width", "rect_depth"};

namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kTopBand_mm = 0.3;      // |h| below this: the top face (range noise 0.02 mm)
constexpr double kBelowTop_mm = 0.5;     // h below -this: inside a groove
constexpr double kPlaneRansac_mm = 0.2;  // RANSAC inlier distances
constexpr double kCircleRansac_mm = 0.3;
constexpr double kCylinderBand_mm = 3.0;  // first cylinder fit: points this near the circle
// A rim's top-face and groove points at most this many points apart within a profile, and
// this far apart in fan angle (4 columns of a 1280-column 27 deg fan: no points missing).
constexpr size_t kMaxGap = 4;
constexpr double kMaxFanGap_rad = 0.0015;

// n . p = d, n unit.
struct Plane {
  Eigen::Vector3d n;
  double d = 0.0;
  size_t inliers = 0;
};

pcl::PointCloud<pcl::PointXYZ>::Ptr toPcl(const std::vector<Eigen::Vector3d>& pts) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr c(new pcl::PointCloud<pcl::PointXYZ>);
  c->reserve(pts.size());
  for (const auto& p : pts) {
    c->push_back(pcl::PointXYZ(static_cast<float>(p.x()), static_cast<float>(p.y()),
                               static_cast<float>(p.z())));
  }
  return c;
}

// PCL RANSAC of a plane (perpendicular to `axis` within 10 deg when given), then the least-
// squares plane (PCA) through the points within the threshold of it; normal with n . up > 0.
std::optional<Plane> fitPlane(const std::vector<Eigen::Vector3d>& pts, const Eigen::Vector3d& up,
                              bool perpendicular_to_up) {
  if (pts.size() < 10) return std::nullopt;
  pcl::SACSegmentation<pcl::PointXYZ> seg;
  seg.setModelType(perpendicular_to_up ? pcl::SACMODEL_PERPENDICULAR_PLANE : pcl::SACMODEL_PLANE);
  if (perpendicular_to_up) {
    seg.setAxis(up.cast<float>());
    seg.setEpsAngle(10.0 * M_PI / 180.0);
  }
  seg.setMethodType(pcl::SAC_RANSAC);
  // One thread: PCL's default (-1) runs RANSAC's samples in OpenMP threads, and which
  // sample wins then depends on the scheduler: results changed under load.
  seg.setNumberOfThreads(1);
  seg.setDistanceThreshold(kPlaneRansac_mm);
  seg.setMaxIterations(500);
  seg.setInputCloud(toPcl(pts));
  pcl::PointIndices inliers;
  pcl::ModelCoefficients coeffs;
  seg.segment(inliers, coeffs);
  if (inliers.indices.size() < 10 || coeffs.values.size() != 4) return std::nullopt;
  Eigen::Vector3d n(coeffs.values[0], coeffs.values[1], coeffs.values[2]);
  double d = -coeffs.values[3];
  const double norm = n.norm();
  n /= norm;
  d /= norm;
  // Least squares on the points within the threshold (in double precision).
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  std::vector<const Eigen::Vector3d*> in;
  for (const auto& p : pts) {
    if (std::fabs(n.dot(p) - d) <= kPlaneRansac_mm) in.push_back(&p), mean += p;
  }
  if (in.size() < 10) return std::nullopt;
  mean /= static_cast<double>(in.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto* p : in) cov += (*p - mean) * (*p - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  Eigen::Vector3d normal = eig.eigenvectors().col(0);
  if (normal.dot(perpendicular_to_up ? up : n) < 0) normal = -normal;
  return Plane{normal, normal.dot(mean), in.size()};
}

// A point's distance from the line through (x0, x1, 0) along (x2, x3, 1), minus the radius
// x4 [mm]. Residuals 1, parameters 5.
struct CylinderResidual {
  explicit CylinderResidual(const Eigen::Vector3d& p) : p_(p) {}
  template <class T>
  bool operator()(const T* x, T* r) const {
    const T norm = ceres::sqrt(x[2] * x[2] + x[3] * x[3] + T(1));
    const T d0 = x[2] / norm, d1 = x[3] / norm, d2 = T(1) / norm;
    const T q0 = T(p_.x()) - x[0], q1 = T(p_.y()) - x[1], q2 = T(p_.z());
    const T t = q0 * d0 + q1 * d1 + q2 * d2;
    const T e0 = q0 - t * d0, e1 = q1 - t * d1, e2 = q2 - t * d2;
    r[0] = ceres::sqrt(e0 * e0 + e1 * e1 + e2 * e2) - x[4];
    return true;
  }
  static ceres::CostFunction* create(const Eigen::Vector3d& p) {
    return new ceres::AutoDiffCostFunction<CylinderResidual, 1, 5>(new CylinderResidual(p));
  }
  Eigen::Vector3d p_;
};

struct Cylinder {
  double u = 0.0, v = 0.0, radius = 0.0;  // axis at the top face, radius
  int inliers = 0;
};

// PCL RANSAC of a circle on the wall points seen from above (u, v), then the least-squares
// cylinder (Ceres) through the points near it, its axis along the top face's normal (the
// drawing's). A free axis was tried: the walls are seen on partial arcs at different depths
// (the sensor looks into the grooves from the side at +-11 deg of turntable), and on a
// distorted cloud (wrong M, N) the axis's lean traded against the radius: +-1.9 % spread
// over ten scans where a perpendicular axis gives 0.1 %.
std::optional<Cylinder> fitCylinder(const std::vector<Eigen::Vector3d>& wall, double radius_mm) {
  if (wall.size() < 20) return std::nullopt;
  std::vector<Eigen::Vector3d> flat;
  flat.reserve(wall.size());
  for (const auto& p : wall) flat.emplace_back(p.x(), p.y(), 0.0);
  pcl::SACSegmentation<pcl::PointXYZ> seg;
  seg.setModelType(pcl::SACMODEL_CIRCLE2D);
  seg.setMethodType(pcl::SAC_RANSAC);
  // One thread: PCL's default (-1) runs RANSAC's samples in OpenMP threads, and which
  // sample wins then depends on the scheduler: results changed under load.
  seg.setNumberOfThreads(1);
  seg.setDistanceThreshold(kCircleRansac_mm);
  seg.setRadiusLimits(0.7 * radius_mm, 1.3 * radius_mm);
  seg.setMaxIterations(500);
  seg.setInputCloud(toPcl(flat));
  pcl::PointIndices inliers;
  pcl::ModelCoefficients c;
  seg.segment(inliers, c);
  if (inliers.indices.size() < 20 || c.values.size() != 3) return std::nullopt;
  double x[5] = {c.values[0], c.values[1], 0.0, 0.0, c.values[2]};
  // Least squares on the points near the RANSAC circle, then again on those within 3 RMS of
  // that fit: a true cylinder keeps a tight band, a distorted one (wrong M, N make the groove
  // elliptic) is fitted as a whole, not by whichever arc RANSAC happened to pick.
  double band = kCylinderBand_mm;
  int used = 0;
  for (int pass = 0; pass < 2; ++pass) {
    ceres::Problem problem;
    std::vector<const Eigen::Vector3d*> in;
    for (const auto& point : wall) {
      double r = 0.0;
      const CylinderResidual residual(point);
      residual(x, &r);
      if (std::fabs(r) > band) continue;
      problem.AddResidualBlock(CylinderResidual::create(point), nullptr, x);
      in.push_back(&point);
    }
    if (!in.empty()) problem.SetManifold(x, new ceres::SubsetManifold(5, {2, 3}));
    if (in.size() < 20) return std::nullopt;
    ceres::Solver::Options so;
    so.linear_solver_type = ceres::DENSE_QR;
    so.max_num_iterations = 50;
    so.num_threads = 1;
    ceres::Solver::Summary summary;
    ceres::Solve(so, &problem, &summary);
    if (!summary.IsSolutionUsable()) return std::nullopt;
    used = static_cast<int>(in.size());
    band = std::max(kCircleRansac_mm, 3.0 * std::sqrt(2.0 * summary.final_cost / in.size()));
  }
  return Cylinder{x[0], x[1], x[4], used};
}

// The plane's h at (u, v) of the piece's frame (plane n . (u, v, h) = d).
double heightAt(const Plane& p, double u, double v) {
  return (p.d - p.n.x() * u - p.n.y() * v) / p.n.z();
}

// The piece's frame from the top face; false when no top face is found.
struct Frame {
  Eigen::Vector3d origin, u, v, w;
  Eigen::Vector3d toPiece(const Eigen::Vector3d& p) const {
    const Eigen::Vector3d q = p - origin;
    return {q.dot(u), q.dot(v), q.dot(w)};
  }
};

std::optional<Frame> topFaceFrame(const std::vector<Eigen::Vector3d>& cloud,
                                  const ProfileGeometry& g, double middle_encoder_rad,
                                  const PieceDesign& d, int* top_points) {
  // Below the sensor at the sweep's middle, within the drawing's block (+ margin).
  const SensorPose pose = sensorPoseInRigFrame(g, middle_encoder_rad);
  const Eigen::Vector3d z = Eigen::Vector3d::UnitZ();
  Frame f;
  f.u = (pose.y_axis - pose.y_axis.dot(z) * z).normalized();
  f.v = z.cross(f.u);
  std::vector<Eigen::Vector3d> near;
  for (const auto& p : cloud) {
    const Eigen::Vector3d q = p - pose.origin;
    if (std::fabs(q.dot(f.u)) <= d.block_width_mm / 2 + 10 &&
        std::fabs(q.dot(f.v)) <= d.block_length_mm / 2 + 10) {
      near.push_back(p);
    }
  }
  const auto top = fitPlane(near, z, true);
  if (!top) return std::nullopt;
  *top_points = static_cast<int>(top->inliers);
  f.w = top->n;
  f.u = (f.u - f.u.dot(f.w) * f.w).normalized();
  f.v = f.w.cross(f.u);
  f.origin = pose.origin + (top->d - f.w.dot(pose.origin)) * f.w;  // below the sensor
  return f;
}

// The round groove centred (nominally) at v = `centre_v`: {diameter, depth}.
std::array<double, 2> measureRound(const std::vector<Eigen::Vector3d>& piece,
                                   const std::vector<bool>& at_rim, double centre_v,
                                   const PieceDesign& d, int* wall_points,
                                   std::vector<std::string>* problems, const char* name) {
  const double r = d.round_diameter_mm / 2, margin = 8.0;
  std::vector<Eigen::Vector3d> wall;
  for (size_t i = 0; i < piece.size(); ++i) {
    const Eigen::Vector3d& p = piece[i];
    if (at_rim[i]) continue;
    if (std::fabs(p.x()) > r + margin || std::fabs(p.y() - centre_v) > r + margin) continue;
    if (p.z() < -kBelowTop_mm - 0.5 && p.z() > -(d.round_depth_mm - 2.0)) wall.push_back(p);
  }
  std::array<double, 2> out = {kNan, kNan};
  const auto cyl = fitCylinder(wall, r);
  if (!cyl) {
    problems->push_back(std::string(name) + ": no cylinder in " + std::to_string(wall.size()) +
                        " wall points");
    return out;
  }
  *wall_points = cyl->inliers;
  out[0] = 2 * cyl->radius;
  std::vector<Eigen::Vector3d> bottom;
  for (const auto& p : piece) {
    if (p.z() < -(d.round_depth_mm - 5.0) &&
        std::hypot(p.x() - cyl->u, p.y() - cyl->v) < cyl->radius - 1.5) {
      bottom.push_back(p);
    }
  }
  const auto plane = fitPlane(bottom, Eigen::Vector3d::UnitZ(), true);
  if (!plane) {
    problems->push_back(std::string(name) + ": no bottom plane");
    return out;
  }
  out[1] = -heightAt(*plane, cyl->u, cyl->v);
  return out;
}

// The rectangular groove's width and depth: {width, depth}.
std::array<double, 2> measureRectWidthDepth(const std::vector<Eigen::Vector3d>& piece,
                                            const std::vector<bool>& at_rim, const PieceDesign& d,
                                            std::vector<std::string>* problems) {
  const double hw = d.rect_width_mm / 2, hl = d.rect_length_mm / 2;
  std::vector<Eigen::Vector3d> walls[2], bottom;
  for (size_t i = 0; i < piece.size(); ++i) {
    const Eigen::Vector3d& p = piece[i];
    if (!at_rim[i] && std::fabs(p.y()) < hl - 4 && p.z() < -1.5 && p.z() > -(d.rect_depth_mm - 2)) {
      if (std::fabs(p.x() - hw) < 5) walls[1].push_back(p);
      if (std::fabs(p.x() + hw) < 5) walls[0].push_back(p);
    }
    if (std::fabs(p.x()) < hw - 6 && std::fabs(p.y()) < hl - 4 && p.z() < -(d.rect_depth_mm - 4)) {
      bottom.push_back(p);
    }
  }
  std::array<double, 2> out = {kNan, kNan};
  const Eigen::Vector3d centre(0, 0, -d.rect_depth_mm / 2);
  const auto minus = fitPlane(walls[0], Eigen::Vector3d::UnitX(), false);
  const auto plus = fitPlane(walls[1], Eigen::Vector3d::UnitX(), false);
  if (minus && plus) {
    out[0] = std::fabs(plus->n.dot(centre) - plus->d) + std::fabs(minus->n.dot(centre) - minus->d);
  } else {
    problems->push_back("rect_width: a wall plane is missing (" + std::to_string(walls[0].size()) +
                        ", " + std::to_string(walls[1].size()) + " points)");
  }
  const auto b = fitPlane(bottom, Eigen::Vector3d::UnitZ(), true);
  if (b) {
    out[1] = -heightAt(*b, 0.0, 0.0);
  } else {
    problems->push_back("rect_depth: no bottom plane");
  }
  return out;
}

// Whether a point (piece frame) lies on the top face.
bool onTopFace(const Eigen::Vector3d& p) { return std::fabs(p.z()) < kTopBand_mm; }

// The angle of a profile point's ray in the laser's fan.
double fanAngle(const ProfileSample& s) { return std::atan2(s.y_mm, -s.z_mm); }

// Whether samples i and j are neighbouring columns of one profile (one missing between them at
// most: two columns of the fan).
bool neighbours(const std::vector<ProfileSample>& samples, size_t i, size_t j) {
  return samples[i].encoder_rad == samples[j].encoder_rad &&
         std::fabs(fanAngle(samples[i]) - fanAngle(samples[j])) <= kMaxFanGap_rad / 2;
}

// The first two points below the top face beside a top-face point of their profile: at a
// groove's rim the line's spot falls on both the top face and what lies below it, and the
// range comes out anywhere between the two (mixed pixels), close to the wall's radius but not
// on the wall. The top face's last column may itself be mixed (no longer on the top face), so
// the wall's first true column beside it is left out too. The walls are fitted without them.
std::vector<bool> atRim(const std::vector<ProfileSample>& samples,
                        const std::vector<Eigen::Vector3d>& piece) {
  std::vector<bool> rim(piece.size(), false);
  const auto top = [&](size_t i) { return onTopFace(piece[i]); };
  for (size_t i = 0; i < piece.size(); ++i) {
    if (!top(i)) continue;
    for (const int step : {-1, 1}) {
      size_t j = i;
      for (int k = 0; k < 2; ++k) {
        const size_t next = j + static_cast<size_t>(step);
        if (next >= piece.size() || top(next) || !neighbours(samples, j, next)) break;
        rim[next] = true;
        j = next;
      }
    }
  }
  return rim;
}

// The rectangular groove's length from its edges across the scan (see the header).
double measureRectLength(const std::vector<ProfileSample>& samples,
                         const std::vector<Eigen::Vector3d>& piece, const PieceDesign& d,
                         std::array<int, 2>* counts, std::vector<std::string>* problems) {
  const double hw = d.rect_width_mm / 2, hl = d.rect_length_mm / 2;
  std::vector<Eigen::Vector2d> edge[2];  // (u, v) of the last top-face point, v < 0 and v > 0
  // Each point: top face (T), in the groove (G) or between (a wall just below the rim).
  const auto kind = [&](size_t i) {
    return onTopFace(piece[i]) ? 'T' : piece[i].z() < -kBelowTop_mm ? 'G' : 'X';
  };
  // Consecutive T and G of one profile, at most kMaxGap columns apart (X between them): the
  // edge lies between them, the T on the top face within those columns of it.
  size_t last = samples.size();  // the last T or G of this profile
  for (size_t i = 0; i < samples.size(); ++i) {
    if (i > 0 && samples[i].encoder_rad != samples[i - 1].encoder_rad) last = samples.size();
    const char k = kind(i);
    if (k == 'X') continue;
    if (last < samples.size() && kind(last) != k && i - last <= kMaxGap &&
        std::fabs(fanAngle(samples[i]) - fanAngle(samples[last])) <= kMaxFanGap_rad) {
      const Eigen::Vector3d& top = piece[k == 'T' ? i : last];
      if (std::fabs(top.x()) <= hw - 2 && std::fabs(std::fabs(top.y()) - hl) <= 5) {
        edge[top.y() > 0].emplace_back(top.x(), top.y());
      }
    }
    last = i;
  }
  (*counts)[0] = static_cast<int>(edge[0].size());
  (*counts)[1] = static_cast<int>(edge[1].size());
  if (edge[0].size() < 2 || edge[1].size() < 2) {
    problems->push_back("rect_length: too few edge crossings (" + std::to_string(edge[0].size()) +
                        ", " + std::to_string(edge[1].size()) + ")");
    return kNan;
  }
  // v = c_side + k u, least squares with a common slope k.
  const size_t n = edge[0].size() + edge[1].size();
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(n), 3);
  Eigen::VectorXd rhs(static_cast<Eigen::Index>(n));
  Eigen::Index row = 0;
  for (int s = 0; s < 2; ++s) {
    for (const auto& e : edge[s]) {
      a(row, s) = 1.0;
      a(row, 2) = e.x();
      rhs(row++) = e.y();
    }
  }
  const Eigen::Vector3d x = a.colPivHouseholderQr().solve(rhs);
  return (x(1) - x(0)) / std::sqrt(1.0 + x(2) * x(2));
}

}  // namespace

PieceMeasurement measureTestPiece(const std::vector<ProfileSample>& samples,
                                  const ProfileGeometry& g, double middle_encoder_rad,
                                  const PieceDesign& d) {
  PieceMeasurement m;
  m.size_mm.fill(kNan);
  std::vector<Eigen::Vector3d> cloud;
  cloud.reserve(samples.size());
  for (const auto& s : samples) {
    cloud.push_back(profilePointInRigFrame(g, s.y_mm, s.z_mm, s.encoder_rad));
  }
  auto frame = topFaceFrame(cloud, g, middle_encoder_rad, d, &m.top_points);
  if (!frame) {
    m.problems.push_back("no top face found below the sensor");
    return m;
  }
  std::vector<Eigen::Vector3d> piece;
  piece.reserve(cloud.size());
  for (const auto& p : cloud) piece.push_back(frame->toPiece(p));
  // Centre on the rectangular groove's bottom (the piece may not sit exactly under the sensor).
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  int count = 0;
  for (const auto& p : piece) {
    if (std::fabs(p.x()) < d.rect_width_mm / 2 + 10 &&
        std::fabs(p.y()) < d.rect_length_mm / 2 + 10 && p.z() < -(d.rect_depth_mm - 3) &&
        p.z() > -(d.rect_depth_mm + 3)) {
      sum += p.head<2>();
      ++count;
    }
  }
  if (count > 0) {
    const Eigen::Vector2d c = sum / count;
    frame->origin += c.x() * frame->u + c.y() * frame->v;
    for (auto& p : piece) p.head<2>() -= c;
  }
  const std::vector<bool> rim = atRim(samples, piece);
  const auto left = measureRound(piece, rim, -d.spacing_mm, d, &m.round_wall_points[0], &m.problems,
                                 "left round groove");
  const auto right = measureRound(piece, rim, d.spacing_mm, d, &m.round_wall_points[1], &m.problems,
                                  "right round groove");
  const auto rect = measureRectWidthDepth(piece, rim, d, &m.problems);
  m.size_mm = {left[0],
               left[1],
               right[0],
               right[1],
               measureRectLength(samples, piece, d, &m.rect_edge_samples, &m.problems),
               rect[0],
               rect[1]};
  m.cloud.reserve(piece.size());
  for (const auto& p : piece) m.cloud.push_back(p.cast<float>());
  return m;
}

}  // namespace sweepmap::eval
