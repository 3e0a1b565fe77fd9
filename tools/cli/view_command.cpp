// `sweepmap view`: the live 3D view in a browser and the Foxglove WebSocket protocol
// (tools/view/view.hpp).
#include "core/command_line.hpp"
#include "processes/channels.hpp"
#include "tools/cli/commands.hpp"
#include "tools/view/view.hpp"

namespace sweepmap {

Runner addViewCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "view",
      "A 3D view of a run in the browser, served on --listen:--port (http://127.0.0.1:8080/ by "
      "default; --listen 0.0.0.0 shares it on the LAN). Live (no LOG): what the processes "
      "publish on --lcm-url: the sweep clouds as they are assembled (coloured by height, "
      "sweep or range), the voxels their points occupy at the mapper's resolution (--rig), the "
      "rig's pose and path (ODOMETRY_POSE), the lidar's latest scan and every process's health "
      "(STATUS_*, as `sweepmap status` shows it). With LOG: the same view of a recorded log "
      "(one with the derived channels: `sweepmap demo`'s or `lcm-logger`'s, or `sweepmap "
      "replay`'s derived.lcmlog) with a time slider, play/pause and speed that every page "
      "shares. Clouds go to the page in binary, within --point-budget points (older sweeps "
      "thinned first); each page has a bounded queue (newest wins, drops counted in the view's "
      "status), so a slow page slows nothing else. The same port speaks the Foxglove WebSocket "
      "protocol (foxglove.websocket.v1) at ws://HOST:PORT/ for Foxglove and Lichtblick: with "
      "--rig the topics of `sweepmap export mcap` in Foxglove's JSON schemas, and every LCM "
      "channel raw as /lcm/CHANNEL (encoding lcm, its type's .lcm text as the schema). "
      "Read-only: it only receives LCM and writes no file. Runs until Ctrl-C. Exit status: 0 "
      "after Ctrl-C; 1 when LOG cannot be read; 2 for a bad option, rig, URL or address (a "
      "port in use), or a missing LOG");
  auto o = std::make_shared<ViewOptions>();
  o->lcm_url = kDefaultLcmUrl;
  cmd->add_option("log", o->log, "a recorded LCM log (none: live on --lcm-url)");
  cmd->add_option("--lcm-url", o->lcm_url, "LCM URL the processes publish on (live)")
      ->capture_default_str();
  cmd->add_option("--rig", o->rig,
                  "rig file or name: the voxels take its mapper's resolution (default 0.05 m), "
                  "Foxglove's converted topics its frames");
  cmd->add_option("--set", o->rig_sets, "override a rig config key: key=value (repeatable)");
  cmd->add_option("--port", o->server.port, "HTTP and WebSocket port (0: any free port)")
      ->capture_default_str();
  cmd->add_option("--listen", o->server.listen, "address to bind (0.0.0.0: every interface)")
      ->capture_default_str();
  cmd->add_option("--point-budget", o->model.point_budget, "cloud points on screen at most")
      ->capture_default_str()
      ->check(atLeast(1000));
  cmd->add_option_function<double>(
         "--client-queue-mb",
         [o](double mb) { o->server.queue_bytes = static_cast<size_t>(mb * (1 << 20)); },
         "per-connection queue bound [MiB] (default 64); beyond it the oldest clouds and voxels "
         "are dropped and counted")
      ->check(CLI::Range(0.0625, 4096.0));
  cmd->add_option("--max-log-mb", o->max_log_mb, "a LOG's messages held in memory at most [MB]")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  return [o]() { return runView(*o); };
}

}  // namespace sweepmap
