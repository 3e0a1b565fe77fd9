// Subcommands of the `sweepmap` tool. Each registers itself on the CLI11 app and returns
// the function that runs it.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <string>

namespace sweepmap {

using Runner = std::function<int()>;

Runner addSimCommand(CLI::App& app);
Runner addReplayCommand(CLI::App& app);
Runner addDemoCommand(CLI::App& app);
Runner addSpyCommand(CLI::App& app, const std::string& argv0);
Runner addBenchCommand(CLI::App& app);
Runner addCalibCommand(CLI::App& app);  // group: calib plate-angle, calib mounting
Runner addEvalCommand(CLI::App& app);
Runner addImportCommand(CLI::App& app);  // group: import breezyslam
Runner addEmulateCommand(CLI::App& app);
Runner addCaptureCommand(CLI::App& app);
Runner addDecodeCommand(CLI::App& app);
Runner addDumpCommand(CLI::App& app);
Runner addStatusCommand(CLI::App& app);
Runner addRecordCommand(CLI::App& app);
Runner addSystemdCommand(CLI::App& app);
Runner addLaunchCommand(CLI::App& app);
Runner addViewCommand(CLI::App& app);
Runner addExportCommand(CLI::App& app);  // group: export mcap, export las

}  // namespace sweepmap
