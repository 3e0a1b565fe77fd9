// sweepmap: one tool, one subcommand per job (sim, replay, demo, spy, bench, calib, eval,
// import, emulate, capture, decode, dump, status, record, systemd, launch); each serves every rig
// kind its rig file names.
#include <iostream>
#include <map>

#include "tools/cli/commands.hpp"

int main(int argc, char** argv) {
  CLI::App app{"sweepmap: a cheap 2D lidar turned into a calibrated 3D scanner and mapper"};
  app.require_subcommand(1);
  std::map<CLI::App*, sweepmap::Runner> runners;
  const auto add = [&](sweepmap::Runner r) { runners[app.get_subcommands({}).back()] = r; };
  add(sweepmap::addSimCommand(app));
  add(sweepmap::addReplayCommand(app));
  add(sweepmap::addDemoCommand(app));
  add(sweepmap::addSpyCommand(app, argv[0]));
  add(sweepmap::addBenchCommand(app));
  add(sweepmap::addCalibCommand(app));
  add(sweepmap::addEvalCommand(app));
  add(sweepmap::addImportCommand(app));
  add(sweepmap::addEmulateCommand(app));
  add(sweepmap::addCaptureCommand(app));
  add(sweepmap::addDecodeCommand(app));
  add(sweepmap::addDumpCommand(app));
  add(sweepmap::addStatusCommand(app));
  add(sweepmap::addRecordCommand(app));
  add(sweepmap::addSystemdCommand(app));
  add(sweepmap::addLaunchCommand(app));
  CLI11_PARSE(app, argc, argv);
  for (auto& [sub, run] : runners) {
    if (sub->parsed()) {
      try {
        return run();
      } catch (const std::exception& e) {
        std::cerr << "sweepmap " << sub->get_name() << ": " << e.what() << "\n";
        return 1;
      }
    }
  }
  return 1;
}
