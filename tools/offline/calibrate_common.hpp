// What the calibration workflows (calibrate_plate.cpp, calibrate_mounting.cpp) share: the
// checks of their inputs, with the message each prints on stderr when one fails, and the
// provenance of the file they write.
#pragma once

#include <chrono>
#include <exception>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "rigs/rig_file.hpp"

namespace sweepmap::calib_workflow {

using Clock = std::chrono::steady_clock;

// The calibration commands' names, which begin their errors and warnings.
inline const std::string kCalibAxisOffset = "calib axis-offset";
inline const std::string kCalibMounting = "calib mounting";
inline const std::string kCalibPlateAngle = "calib plate-angle";
inline const std::string kCalibRig = "calib rig";

inline double seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

// The rig as its kind T into *rig; false after "WHAT: config error: ..." if it cannot be
// loaded or is of another kind.
template <class T>
bool loadRigOfKind(const std::string& path_or_name, const std::vector<std::string>& sets,
                   const std::string& what, T* rig) {
  try {
    *rig = requireKind<T>(loadRig(path_or_name, sets), what);
  } catch (const std::exception& e) {
    std::cerr << what << ": config error: " << e.what() << "\n";
    return false;
  }
  return true;
}

// False after "WHAT: log 'LOG' does not exist or is not a file" unless it is a file.
inline bool logFileExists(const std::string& log, const std::string& what) {
  if (std::filesystem::is_regular_file(log)) return true;
  std::cerr << what << ": log '" << log << "' does not exist or is not a file\n";
  return false;
}

// False after "WHAT: output directory 'DIR' does not exist" unless `out`'s folder exists.
inline bool outputDirExists(const std::string& out, const std::string& what) {
  const std::filesystem::path out_dir = std::filesystem::absolute(out).parent_path();
  if (std::filesystem::is_directory(out_dir)) return true;
  std::cerr << what << ": output directory '" << out_dir.string() << "' does not exist\n";
  return false;
}

}  // namespace sweepmap::calib_workflow
