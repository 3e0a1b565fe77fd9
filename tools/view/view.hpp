// `sweepmap view`: a live 3D view of a run in the browser (and for Foxglove/Lichtblick over
// the Foxglove WebSocket protocol), on one port. Live, it listens on an LCM URL (udpm://
// through sweepmap's own validating receiver, never liblcm's); from a log, it plays the log
// with a time slider, play/pause and speed that every page shares. It writes nothing and
// nothing a page sends reaches the rig: LCM is only received.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "tools/view/view_model.hpp"
#include "tools/view/view_server.hpp"

namespace sweepmap {

struct ViewOptions {
  std::string lcm_url;  // live (when log is "")
  std::string log;      // a recorded LCM log
  std::string rig;      // "" : the mapper's resolution defaults to ViewModelOptions'
  std::vector<std::string> rig_sets;
  ViewServerOptions server;
  ViewModelOptions model;
  double max_log_mb = 2048;  // a log's messages are held in memory
};

// The folder of the page's files: $SWEEPMAP_WEB_DIR, else <executable's folder>/../share/
// sweepmap/web (the build copies tools/view/web there; `make install` too).
std::string webDir();

// Serves until SIGINT/SIGTERM. 0 after a stop; 2 (kExitUsage) when the URL, the rig or the
// address is unusable or the log is missing; 1 (kExitBadInput) when the log cannot be read.
int runView(const ViewOptions& options);

}  // namespace sweepmap
