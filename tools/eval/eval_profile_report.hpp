// What rig C's paper experiment measured (tools/eval/eval_profile.hpp), and report.json and
// report.md made from it: Zhao 2021 Table 2 beside ours.
#pragma once

#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include "calib/axis_offset.hpp"
#include "sim/profiler.hpp"
#include "tools/eval/eval_profile_features.hpp"
#include "tools/eval/figures.hpp"

namespace sweepmap::eval {

// One setting of (M, N, tilt, encoder zero) and the sizes it measured on every scan.
struct ProfileSetting {
  std::string name;   // ours | grid | too_small | too_large (report.json's keys)
  std::string label;  // for people
  ProfileGeometry geometry;
  std::vector<std::array<double, kPieceFeatureCount>> sizes_mm;  // per scan; NaN: not measured
  std::vector<std::string> problems;
};

struct ProfileEvaluation {
  std::string rig_path;
  uint64_t seed = 0;
  int repeats = 0;
  ProfileGeometry truth;    // TRUTH_PROFILE_RIG
  ProfileGeometry nominal;  // the rig file's (ours starts there)
  TestPieceConfig piece;    // TRUTH_TEST_PIECE's sizes
  GridSearchOptions grid_options;
  GridSearchResult grid;
  AxisOffsetResult ours;
  std::vector<size_t> plate_points, plate_points_used;  // per plate pose
  std::vector<ProfileSetting> settings;                 // ours, grid, too_small, too_large
  std::vector<std::string> logs;                        // relative to the report's directory
  ProfilerConfig profiler;
  TurntableConfig turntable;
  double range_noise_sigma_mm = 0.0;
  double encoder_noise_counts = 0.0;
  PieceMeasurement example;  // the first scan under ours (the cloud figure)
};

// The true size of feature k (kPieceFeatures order).
double trueSize(const TestPieceConfig& piece, int k);

// Mean and standard deviation (n - 1) of the finite values; count of them.
struct Stats {
  double mean = 0.0, std = 0.0;
  int count = 0;
};
Stats errorPctStats(const ProfileSetting& s, const TestPieceConfig& piece, int feature);

// True when every feature of `ours` has |mean error| <= limit_pct.
bool withinPct(const ProfileEvaluation& ev, const ProfileSetting& s, double limit_pct);

void writeProfileReport(const std::filesystem::path& dir, const ProfileEvaluation& ev,
                        const std::vector<Figures::Entry>& figures,
                        const std::vector<std::string>& figure_errors);

}  // namespace sweepmap::eval
