// How a lidar sits on a moving body (rig B, Miao 2022 Eq. 11-14).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/angles.hpp"

namespace sweepmap {

// Mounting of the lidar on the body: a nominal rotation (how the lidar is meant to sit,
// e.g. horizontal or vertical) followed by the small mounting error (gamma about x,
// beta about y, alpha about z) that calibration estimates, and the lidar's position.
struct LidarMounting {
  Eigen::Vector3d nominal_rpy_rad = Eigen::Vector3d::Zero();  // roll, pitch, yaw
  double gamma_rad = 0.0;                                     // about body x
  double beta_rad = 0.0;                                      // about body y
  double alpha_rad = 0.0;                                     // about body z
  Eigen::Vector3d t_BL_m = Eigen::Vector3d::Zero();           // (l1, 0, h) in Miao 2022
  Eigen::Isometry3d T_BL() const {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = rotationXYZ(gamma_rad, beta_rad, alpha_rad) *
                 rotationXYZ(nominal_rpy_rad.x(), nominal_rpy_rad.y(), nominal_rpy_rad.z());
    T.translation() = t_BL_m;
    return T;
  }
};

}  // namespace sweepmap
