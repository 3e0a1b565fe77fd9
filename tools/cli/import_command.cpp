#include <iostream>

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
  return [=]() {
    const BreezySlamImport r = importBreezySlam(*in, *out);
    std::cerr << "import: " << r.scans << " scans of " << r.beams << " ranges, "
              << (r.last_utime - r.first_utime) / 1e6 << " s -> " << *out << "\n";
    return 0;
  };
}

}  // namespace sweepmap
