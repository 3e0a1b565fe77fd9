#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

namespace sweepmap::calib {

struct CalibParameter {
  std::string key;
  double value;
  double sigma;
  std::string unit;
  bool observable;
  std::optional<double> truth;
};
struct RigCalibration {
  std::vector<CalibParameter> parameters;
  Eigen::MatrixXd correlation;
  double rms_before;
  double rms_after;
  std::vector<std::string> warnings;
};

}  // namespace sweepmap::calib
