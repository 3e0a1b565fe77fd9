// `sweepmap export las`: clouds as one LAS 1.4 file (mapping/las_io.hpp), from PLY files (as
// replay and eval write them) or LCM logs (every SWEEP_CLOUD chunk's points, each with its
// chunk's time as GPS time), in the order given.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "mapping/las_io.hpp"

namespace sweepmap {

struct ExportLasOptions {
  std::vector<std::string> inputs;  // .ply files or LCM logs
  std::string out;
};

struct ExportLasResult {
  LasSummary las;
  int64_t chunks = 0;           // SWEEP_CLOUD chunks read from logs
  int64_t chunks_rejected = 0;  // chunks that did not decode or validate
  bool log_error = false;       // corrupt bytes skipped in a log
  std::string error;
};

// Throws std::runtime_error for an input it cannot read (exit status 1), CommandError
// (kExitDeviceIo) when the file cannot be written.
ExportLasResult exportLas(const ExportLasOptions& options);

}  // namespace sweepmap
