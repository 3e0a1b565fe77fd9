// Where the executables find their rig and scene files: bin/../share/sweepmap/config of their
// own tree. The build tree holds a copy of config/ (not a link into the checkout that built
// it), so that a copied or moved build or install tree reads its own files; a relative path
// inside a rig file is taken relative to the rig file's folder, not to the working directory.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <fstream>

#include "test_support.hpp"

namespace sweepmap {
namespace test {
namespace {

// Runs `command` with no SWEEPMAP_CONFIG_DIR in a shell from `cwd`, its output into `out`;
// returns the exit status.
int runIn(const fs::path& cwd, const std::string& command, const fs::path& out) {
  const std::string line = "cd '" + cwd.string() + "' && env -u SWEEPMAP_CONFIG_DIR " + command +
                           " > '" + out.string() + "' 2>&1";
  const int rc = std::system(line.c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

// Replaces `from` by `to` in the text file `path` (the key must be there).
void replaceIn(const fs::path& path, const std::string& from, const std::string& to) {
  std::string text = readFile(path);
  const size_t at = text.find(from);
  ASSERT_NE(at, std::string::npos) << path << " has no '" << from << "'";
  text.replace(at, from.size(), to);
  std::ofstream(path, std::ios::trunc) << text;
}

const fs::path kBuildConfig = fs::path(SWEEPMAP_BINARY_DIR) / "share" / "sweepmap" / "config";

// The build tree's config folder is a copy of the source's, up to date.
TEST(ConfigLocation, BuildTreeHoldsACopyOfTheSourceConfig) {
  ASSERT_FALSE(fs::is_symlink(kBuildConfig)) << kBuildConfig << " links into a checkout";
  ASSERT_TRUE(fs::is_directory(kBuildConfig));
  for (const auto& e : fs::directory_iterator(sourcePath("config"))) {
    const fs::path copy = kBuildConfig / e.path().filename();
    EXPECT_EQ(readFile(copy), readFile(e.path())) << copy << " differs from " << e.path();
  }
}

// A copy of the executable and of the share folder (as `cp -a` makes it, or an install tree
// moved elsewhere) reads the rig files beside it: a rig file changed in the copy is the one
// loaded (its error names it), and its relative calibration_file is looked up in the copy's
// config folder, not in the working directory (which holds a file of that name).
TEST(ConfigLocation, ACopiedTreeReadsItsOwnConfig) {
  const fs::path dir = scratchDir("config_location");
  const fs::path tree = dir / "moved";
  fs::create_directories(tree / "bin");
  fs::copy_file(binPath("sweepmap"), tree / "bin" / "sweepmap");
  fs::copy(fs::path(SWEEPMAP_BINARY_DIR) / "share", tree / "share",
           fs::copy_options::recursive | fs::copy_options::copy_symlinks);
  const fs::path config = tree / "share" / "sweepmap" / "config";
  // Never write through a link into a checkout.
  ASSERT_FALSE(fs::is_symlink(config)) << config;
  const fs::path cwd = dir / "cwd";
  fs::create_directories(cwd);
  const std::string sweepmap = (tree / "bin" / "sweepmap").string();

  std::ofstream(config / "rig_a.yaml", std::ios::app) << "no_such_key_in_the_copy: 1\n";
  const fs::path a_out = dir / "a.txt";
  EXPECT_EQ(runIn(cwd, sweepmap + " sim --rig rig_a --mode 1 --sweeps 1 --out a.lcmlog", a_out), 2)
      << readFile(a_out);
  const std::string rig_a = fs::weakly_canonical(config / "rig_a.yaml").string();
  EXPECT_NE(readFile(a_out).find(rig_a), std::string::npos) << readFile(a_out);
  EXPECT_NE(readFile(a_out).find("no_such_key_in_the_copy"), std::string::npos) << readFile(a_out);

  replaceIn(config / "rig_b.yaml", "  calibration_file: \"\"", "  calibration_file: mounting.yaml");
  std::ofstream(cwd / "mounting.yaml") << "not: a calibration\n";  // must not be read
  const fs::path b_out = dir / "b.txt";
  EXPECT_EQ(runIn(cwd, sweepmap + " sim --rig rig_b --set sim.duration_s=1 --out b.lcmlog", b_out),
            2)
      << readFile(b_out);
  const std::string calib = (fs::weakly_canonical(config) / "mounting.yaml").string();
  EXPECT_NE(readFile(b_out).find(calib + ": cannot open"), std::string::npos) << readFile(b_out);

  // The build's own files are untouched.
  EXPECT_EQ(readFile(kBuildConfig / "rig_a.yaml"), readFile(sourcePath("config/rig_a.yaml")));
}

}  // namespace
}  // namespace test
}  // namespace sweepmap
