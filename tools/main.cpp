// sweepmap: one tool, several subcommands (sim, replay, demo, spy, bench, calib, eval, import,
// replay-mobile).
#include <iostream>
#include <map>

#include "tools/commands.hpp"

int main(int argc, char** argv) {
  CLI::App app{"sweepmap: a rotating 2D lidar turned into a calibrated 3D scanner and mapper"};
  app.require_subcommand(1);
  std::map<CLI::App*, sweepmap::Runner> runners;
  const auto add = [&](sweepmap::Runner r) { runners[app.get_subcommands({}).back()] = r; };
  add(sweepmap::addSimCommand(app));
  add(sweepmap::addReplayCommand(app));
  add(sweepmap::addDemoCommand(app, argv[0]));
  add(sweepmap::addSpyCommand(app, argv[0]));
  add(sweepmap::addBenchCommand(app));
  add(sweepmap::addCalibCommand(app));
  add(sweepmap::addEvalCommand(app));
  add(sweepmap::addImportCommand(app));
  add(sweepmap::addReplayMobileCommand(app));
  add(sweepmap::addSimMobileCommand(app));
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
