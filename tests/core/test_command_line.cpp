// The shared parse step's exit statuses (core/command_line.hpp): CLI11's own codes map onto
// the convention of core/exit_codes.hpp; --out folder checks.
#include <gtest/gtest.h>

#include <fstream>

#include "core/command_line.hpp"

namespace sweepmap {
namespace {

namespace fs = std::filesystem;

// Parses `args` (after the program name) into a small app with a required option and a file.
std::optional<int> parse(std::vector<std::string> args) {
  CLI::App app{"test", "test"};
  std::string out, in;
  int n = 1;
  app.add_option("--out", out)->required();
  app.add_option("--in", in)->check(CLI::ExistingFile);
  app.add_option("--n", n)->check(atLeast(1));
  args.insert(args.begin(), "test");
  std::vector<const char*> argv;
  for (const auto& a : args) argv.push_back(a.c_str());
  return parseCommandLine(app, static_cast<int>(argv.size()), argv.data());
}

TEST(CommandLine, ParserCodesMapOntoTheConvention) {
  EXPECT_EQ(exitCodeOfParseError(CLI::RequiredError("--out")), kExitUsage);     // CLI11: 106
  EXPECT_EQ(exitCodeOfParseError(CLI::FileError("x")), kExitUsage);             // CLI11: 103
  EXPECT_EQ(exitCodeOfParseError(CLI::ValidationError("x", "y")), kExitUsage);  // 105
  EXPECT_EQ(exitCodeOfParseError(CLI::ExtrasError({"--x"})), kExitUsage);
  EXPECT_EQ(exitCodeOfParseError(CLI::CallForHelp()), kExitOk);
  EXPECT_EQ(exitCodeOfParseError(CLI::CallForVersion()), kExitOk);
}

TEST(CommandLine, ParseReturnsTheStatusOrNothingToRun) {
  EXPECT_EQ(parse({"--out", "x"}), std::nullopt);
  EXPECT_EQ(parse({}), kExitUsage);                                       // a required option
  EXPECT_EQ(parse({"--out", "x", "--nope"}), kExitUsage);                 // an unknown one
  EXPECT_EQ(parse({"--out", "x", "--in", "/no/such/file"}), kExitUsage);  // a missing file
  EXPECT_EQ(parse({"--out", "x", "--n", "0"}), kExitUsage);               // below its limit
  EXPECT_EQ(parse({"--help"}), kExitOk);
  EXPECT_EQ(parse({"--version"}), kExitOk);
}

TEST(CommandLine, NumberChecksSayTheirLimit) {
  std::string zero = "0", two = "2", word = "many";
  EXPECT_EQ(atLeast(1)(zero), "must be at least 1, got 0");
  EXPECT_EQ(atLeast(1)(two), "");
  EXPECT_EQ(greaterThan(0)(zero), "must be more than 0, got 0");
  EXPECT_EQ(atLeast(1)(word), "not a number: many");
}

TEST(CommandLine, ExceptionsMapOntoTheConvention) {
  EXPECT_EQ(exitCodeOf(ConfigError("x")), kExitUsage);
  EXPECT_EQ(exitCodeOf(CommandError(kExitDeviceIdentity, "x")), kExitDeviceIdentity);
  EXPECT_EQ(exitCodeOf(fs::filesystem_error("x", std::error_code())), kExitDeviceIo);
  EXPECT_EQ(exitCodeOf(std::runtime_error("corrupt")), kExitBadInput);
}

TEST(CommandLine, OutputFolderRefusedUnlessForced) {
  const fs::path dir = fs::temp_directory_path() / "sweepmap_test_command_line";
  fs::remove_all(dir);
  prepareOutputDir((dir / "new").string(), false);  // made
  EXPECT_TRUE(fs::is_directory(dir / "new"));
  prepareOutputDir((dir / "new").string(), false);  // empty: fine
  std::ofstream(dir / "new" / "old.txt") << "x";
  try {
    prepareOutputDir((dir / "new").string(), false);
    ADD_FAILURE() << "a non-empty folder was accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("--force"), std::string::npos) << e.what();
  }
  prepareOutputDir((dir / "new").string(), true);
  EXPECT_TRUE(fs::is_empty(dir / "new"));
  std::ofstream(dir / "file") << "x";
  EXPECT_THROW(prepareOutputDir((dir / "file").string(), true), ConfigError);
  EXPECT_THROW(checkOutputFile((dir / "new").string()), ConfigError);  // a folder
  EXPECT_THROW(checkOutputFile((dir / "no" / "x.log").string()), ConfigError);
  EXPECT_NO_THROW(checkOutputFile((dir / "x.log").string()));
  // Issue 21: `--out` equal to the input overwrote the capture. Also through another spelling.
  EXPECT_THROW(checkOutputFile((dir / "file").string(), {(dir / "file").string()}), ConfigError);
  EXPECT_THROW(checkOutputFile((dir / "new" / ".." / "file").string(), {(dir / "file").string()}),
               ConfigError);
  EXPECT_NO_THROW(checkOutputFile((dir / "x.log").string(), {(dir / "file").string()}));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace sweepmap
