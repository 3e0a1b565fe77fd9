// sweepmap: one tool, one subcommand per job (sim, replay, demo, spy, bench, calib, eval,
// import, emulate, capture, decode, dump, status, record, systemd, launch, export, view); each
// serves every rig kind its rig file names. Exit status: core/exit_codes.hpp
// (docs/reference/exit-codes.md).
#include <iostream>
#include <map>

#include "core/command_line.hpp"
#include "tools/cli/commands.hpp"

int main(int argc, char** argv) {
  CLI::App app{"sweepmap: a cheap 2D lidar turned into a calibrated 3D scanner and mapper",
               "sweepmap"};
  app.formatter(std::make_shared<sweepmap::BriefFormatter>());
  app.footer("Run `sweepmap COMMAND --help` for a command's options, outputs and exit status.");
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
  add(sweepmap::addViewCommand(app));
  add(sweepmap::addExportCommand(app));
  if (const auto code = sweepmap::parseCommandLine(app, argc, argv)) return *code;
  for (auto& [sub, run] : runners) {
    if (sub->parsed()) {
      try {
        return run();
      } catch (const std::exception& e) {
        const int code = sweepmap::exitCodeOf(e);
        std::cerr << "sweepmap " << sub->get_name() << ": "
                  << (code == sweepmap::kExitUsage ? "config error: " : "") << e.what() << "\n";
        return code;
      }
    }
  }
  return sweepmap::kExitUsage;
}
