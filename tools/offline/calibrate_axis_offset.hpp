// `sweepmap calib axis-offset` as a library call: the axis offsets M, N of a rotating_profile
// rig (rig C, Zhao 2021) from logs of a flat plate in m poses (a turntable sweep per pose),
// by the paper's grid search (Algorithm 1, with the S(M, N) figure) and by ours (Ceres, with
// standard deviations and an observability check), written as a calibration file
// (core/calibration_file.hpp) that the rig's geometry.calibration_file points to.
#pragma once

#include <string>
#include <vector>

#include "calib/axis_offset.hpp"
#include "sim/profiler.hpp"

namespace sweepmap {

struct AxisOffsetCalibRequest {
  std::vector<std::string> logs;  // rig C logs (sweepmap sim --rig rig_c, lcm-logger)
  std::string rig;                // rig file or name (rotating_profile)
  std::vector<std::string> sets;  // rig overrides, key=value
  std::string out;                // calibration file to write (YAML, atomically)
  bool json = false;              // the result as JSON on stdout
  GridSearchOptions grid;         // the paper's interval and step
  bool no_grid = false;           // skip the paper's method
  std::string figure;             // S(M, N) PNG; "" = OUT's name with _S.png
  bool estimate_tilt = true;
  bool estimate_encoder_zero = false;
  int max_points_per_sweep = 20000;  // both methods use the same evenly strided subset
  int min_points_per_sweep = 100;    // sweeps with fewer are not a plate pose
};

// Reads the logs' sweeps, runs both methods, writes `out` (ours) and the figure. Human report
// on stderr; with `json` the result on stdout. Returns the exit status: 0 calibrated; 1 not
// calibrated (no usable sweep, M or N not observable from the planes); 2 bad rig, log or
// output path.
int calibrateAxisOffsetFromLogs(const AxisOffsetCalibRequest& request);

// A sweep whose plane (placed with the rig file's geometry) leans within this of the base's
// reference face is a sweep over it: a nominal zero off by e moves the normal by e sin(tilt),
// while calib plan's plate poses lean 29 deg or more away from it.
constexpr double kReferenceToleranceDeg = 5.0;

// The sweeps over the base's reference face, recognised among `planes` by their normals with
// options->initial, when the rig file declares a face (`ref`). Exactly one: into options (that
// plane, the face's azimuth and its construction sigma), so the encoder zero is fitted against
// it. More than one: none is used (a plate pose laid like the face cannot be told from it).
std::vector<size_t> useReferenceFace(const TurntableReference& ref,
                                     const std::vector<PlanePoints>& planes,
                                     AxisOffsetOptions* options);

// The paper's S(M, N) of a grid search drawn as its Fig. 6 (a surface with the minimum
// marked) into `png`; returns "" when drawn, else why not (no gnuplot, gnuplot failed).
std::string drawAxisOffsetSurface(const std::string& png, const GridSearchResult& grid);

}  // namespace sweepmap
