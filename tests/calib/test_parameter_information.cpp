// The shared uncertainty of the calibrations (calib/parameter_information.hpp): the information
// of a parameter with the nuisance eliminated matches the textbook one, and does not depend on
// where the blocks sit in memory (ceres::Covariance orders them by address).
#include <ceres/ceres.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <vector>

#include "calib/parameter_information.hpp"

namespace sweepmap {
namespace {

// y = a_g + b t: a per group (the nuisance), b shared (the parameter).
struct LineCost {
  double t, y;
  template <class T>
  bool operator()(const T* a, const T* b, T* e) const {
    e[0] = a[0] + b[0] * T(t) - T(y);
    return true;
  }
};

struct Groups {
  std::vector<std::unique_ptr<double>> a;  // separate allocations: addresses as they come
  double b = 0.5;
};

// Three groups of points t = g + 0.3 i; the intercepts' blocks allocated in `order`.
Eigen::MatrixXd informationOf(const std::vector<int>& order, double* expected) {
  Groups g;
  g.a.resize(3);
  for (const int k : order) g.a[size_t(k)] = std::make_unique<double>(0.1 * k);
  ceres::Problem problem;
  *expected = 0.0;
  std::vector<double*> nuisance;
  for (int k = 0; k < 3; ++k) {
    std::vector<double> ts;
    for (int i = 0; i < 4 + k; ++i) ts.push_back(k + 0.3 * i * (k + 1));
    double mean = 0.0;
    for (const double t : ts) mean += t / double(ts.size());
    for (const double t : ts) {
      *expected += (t - mean) * (t - mean);
      problem.AddResidualBlock(
          new ceres::AutoDiffCostFunction<LineCost, 1, 1, 1>(new LineCost{t, 2.0 * t + k}), nullptr,
          g.a[size_t(k)].get(), &g.b);
    }
    nuisance.push_back(g.a[size_t(k)].get());
  }
  const ParameterInformation info = eliminatedInformation(&problem, nuisance, {&g.b});
  EXPECT_TRUE(info.ok);
  return info.information;
}

TEST(ParameterInformation, SlopeWithTheInterceptsEliminated) {
  double expected = 0.0;
  const Eigen::MatrixXd info = informationOf({0, 1, 2}, &expected);
  ASSERT_EQ(info.rows(), 1);
  EXPECT_NEAR(info(0, 0), expected, 1e-9 * expected);
  EXPECT_NEAR(covarianceFromInformation(info)(0, 0), 1.0 / expected, 1e-9 / expected);
}

TEST(ParameterInformation, TheSameBytesWhereverTheBlocksSit) {
  double e1 = 0.0, e2 = 0.0;
  const Eigen::MatrixXd first = informationOf({0, 1, 2}, &e1);
  const Eigen::MatrixXd second = informationOf({2, 0, 1}, &e2);
  ASSERT_EQ(first.size(), second.size());
  EXPECT_EQ(std::memcmp(first.data(), second.data(), sizeof(double) * size_t(first.size())), 0);
}

TEST(ParameterInformation, ASingularInformationGivesNaN) {
  const Eigen::MatrixXd c = covarianceFromInformation(Eigen::MatrixXd::Zero(2, 2));
  EXPECT_TRUE(std::isnan(c(0, 0)));
  EXPECT_TRUE(std::isnan(c(1, 1)));
}

}  // namespace
}  // namespace sweepmap
