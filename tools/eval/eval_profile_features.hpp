// Zhao 2021 Table 2's features of the test piece (Fig. 7), measured on one sweep's cloud
// assembled with a given geometry (M, N, tilt, encoder zero): the two round grooves'
// diameters and depths, the rectangular groove's length (along the scan), width (along the
// laser line) and depth.
//
// Where the features are comes from the nominal drawing (PieceDesign) and the setup (the
// piece lies under the sensor at the sweep's middle), never from the simulator's truth:
//  1. the top face: PCL RANSAC (a plane perpendicular to the axis) over the points below the
//     sensor, refined by least squares on its inliers; the piece's frame: w its normal, u the
//     laser line at the sweep's middle, v = w x u, centred on the rectangular groove's bottom;
//  2. crop boxes from the drawing (with margins of several mm) around each feature;
//  3. round grooves: PCL RANSAC of a circle (SACMODEL_CIRCLE2D) on the wall points seen from
//     above, then our own least-squares cylinder (Ceres: axis point, axis direction, radius)
//     on its inliers; the bottom by a RANSAC plane. We fit the cylinder ourselves rather than
//     with SACMODEL_CYLINDER because that needs surface normals, and the walls are seen as
//     short vertical stripes at each end of a profile's chord, 0.1 mm apart along the line
//     but ~0.9 mm apart across it: normals from such neighbourhoods are poor, while the
//     point-to-axis distance needs none;
//  4. the rectangular groove: its walls across the line (u = +-width/2) are seen by the
//     fan's oblique rays, so the width is the distance between two RANSAC planes; the walls
//     across the scan (v = +-length/2) are parallel to the laser plane and not seen, so the
//     length comes from the top face's edges: where a profile passes from the top face into
//     the groove (the laser line crosses those edges at the turntable's angle, 2-3 deg), the
//     last top-face point lies on the edge within one column; a line through those points on
//     each side (common direction) gives the edge, the length is their distance.
#pragma once

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "calib/axis_offset.hpp"
#include "core/profile_geometry.hpp"

namespace sweepmap::eval {

// Table 2's rows, in its order.
constexpr int kPieceFeatureCount = 7;
extern const std::array<const char*, kPieceFeatureCount> kPieceFeatures;

// The nominal drawing of Zhao 2021's test piece (Fig. 7): where to look, not the truth.
struct PieceDesign {
  double round_diameter_mm = 50.0;
  double round_depth_mm = 30.0;
  double spacing_mm = 80.0;  // groove centres along the scan: -80, 0, +80
  double rect_length_mm = 40.0;
  double rect_width_mm = 80.0;
  double rect_depth_mm = 20.0;
  double block_length_mm = 260.0;
  double block_width_mm = 160.0;
};

struct PieceMeasurement {
  std::array<double, kPieceFeatureCount> size_mm;  // NaN: not measured (see problems)
  std::vector<std::string> problems;
  std::vector<Eigen::Vector3f> cloud;  // every point in the piece's frame (u, v, h) [mm]
  int top_points = 0;
  std::array<int, 2> round_wall_points{};  // cylinder inliers, left and right
  std::array<int, 2> rect_edge_samples{};  // at v = -length/2 and +length/2
};

// `samples`: one sweep's points in profile order (a profile's points share encoder_rad and
// come in column order); `middle_encoder_rad`: the turntable angle at which the piece lies
// under the sensor (the sweep's middle).
PieceMeasurement measureTestPiece(const std::vector<ProfileSample>& samples,
                                  const ProfileGeometry& geometry, double middle_encoder_rad,
                                  const PieceDesign& design = {});

}  // namespace sweepmap::eval
