// Evaluation of rig A against Yuan 2021 section 5 and Appendix B: the attitude error
// phi_error of every sweep (uncorrected C_O', corrected C_O with both plate estimators),
// the mapping error E_map(d) = d * tan(phi_error) (Eq. 21) and the distance at which it
// reaches 50 mm, the plate angle alpha calibrated by LM over wall normals (Algorithm A1),
// and the wall-flatness deviations of Appendix B. Writes DIR/report.json, DIR/report.md
// and the PNG figures of the paper (Figs. 1, 8-11, A2).
//
// `evalRotatingLogs` evaluates existing logs; `runPaperExperiment` first simulates the
// paper's experiment (50 mode-7 sweeps for alpha, 7 modes x N sweeps, naive mode 1) into
// DIR/logs/, calibrates alpha, writes DIR/plate_calibration.yaml and then evaluates.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "rigs/rotating_lidar.hpp"
#include "tools/eval/metrics.hpp"  // mapErrorDistance, DeviationStats, wallDeviationsMm

namespace sweepmap {

struct EvalSettings {
  // Appendix B: wall points within band_m of a wall's plane count as that wall's points,
  // except those within edge_trim_m of the wall's ends (corners, floor, ceiling) and
  // those inside another wall's band. Histogram bins in mm over [-band, band].
  double band_m = 0.10;
  double edge_trim_m = 0.15;
  double histogram_bin_mm = 2.0;
  double within_mm = 40.0;          // UST-10LX accuracy: the paper's +-40 mm
  double map_error_limit_m = 0.05;  // Eq. 21 standard: +-50 mm
  double max_range_m = 10.0;        // UST-10LX range: d50 is capped here
  double wall_voxel_m = 0.05;       // extractWalls downsampling
  // Fig. 8: points with z in this band (frame O), at most this many per sweep.
  double top_view_z_min_m = -0.3;
  double top_view_z_max_m = 1.0;
  size_t top_view_points_per_sweep = 40000;
  bool plots = true;
  bool progress = true;  // progress lines on stderr
};

struct EvalRotatingOptions {
  std::vector<std::string> logs;
  std::string rig_path;                // for the report
  std::vector<std::string> overrides;  // for the report (already applied to `rig`)
  RotatingLidarConfig rig;             // plate.beta_method is replaced per method
  std::string out_dir;
  EvalSettings settings;
};

struct PaperExperimentOptions {
  std::string rig_path = "rig_a";  // path or name (rigs/rig_file.hpp)
  std::string scene_path = "scene_conference_room";
  std::vector<std::string> overrides;  // rig keys, or scene.<key>
  std::string out_dir;
  uint64_t seed = 1;        // mode m uses seed + m, the alpha log seed + 100, naive seed + 200
  int sweeps_per_mode = 5;  // paper: 5
  int calib_sweeps = 50;    // paper: 50 mode-7 sweeps
  bool naive = true;        // also simulate mode 1 with the naive action sequence (Fig. 1)
  EvalSettings settings;
};

struct EvalRotatingResult {
  int sweeps = 0;       // evaluated sweeps (modes, not counting alpha calibration logs)
  bool failed = false;  // a log was unreadable/corrupt, or no sweep was found
  std::string message;  // why it failed
  std::vector<std::string> figures;  // PNG file names written into out_dir
};

// Throws std::runtime_error for unusable arguments (no logs, missing files, unwritable
// DIR). Logs with a read error are reported in the result after writing every output.
// Without any sweep, report.json (with "sweeps": 0 and "error") and report.md are
// still written and the result is `failed`.
EvalRotatingResult evalRotatingLogs(const EvalRotatingOptions& options);
EvalRotatingResult runPaperExperiment(const PaperExperimentOptions& options);

}  // namespace sweepmap
