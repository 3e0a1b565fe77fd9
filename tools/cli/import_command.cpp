#include <iostream>

#include "core/command_line.hpp"
#include "tools/cli/commands.hpp"
#include "tools/import/import_mines.hpp"

namespace sweepmap {

Runner addImportCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("import", "Convert recordings from other tools into LCM logs");
  cmd->require_subcommand(1);
  auto* bs = cmd->add_subcommand(
      "breezyslam",
      "BreezySLAM/CoreSLAM 'Mines' data (e.g. examples/exp2.dat: timestamps, wheel encoder "
      "ticks, Hokuyo URG-04LX ranges) -> WHEEL_TICKS and LIDAR_SCAN with the original "
      "timestamps. Read as the original loader (examples/mines.py) reads it");
  auto in = std::make_shared<std::string>();
  auto out = std::make_shared<std::string>();
  bs->add_option("FILE", *in, "input .dat file")->required()->check(CLI::ExistingFile);
  bs->add_option("--out", *out, "output LCM log")->required();
  bs->footer(
      "Exit status: 0 imported; 1 the file is corrupt or holds no scan; 2 bad option or a "
      "missing input file; 4 the log cannot be written.");
  return [=]() -> int {
    checkOutputFile(*out, {*in});
    const BreezySlamImport r = importBreezySlam(*in, *out);  // bad data throws: exit status 1
    std::cerr << "import: " << r.scans << " scans of " << r.beams << " ranges, "
              << (r.last_utime - r.first_utime) / 1e6 << " s -> " << *out << "\n";
    if (r.scans == 0) {
      std::cerr << "import: " << *in << " holds no scan\n";
      return kExitBadInput;
    }
    return kExitOk;
  };
}

}  // namespace sweepmap
