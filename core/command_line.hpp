// The command line every sweepmap executable shares, over CLI11: one parse step that maps the
// parser's own codes onto the exit-status convention (core/exit_codes.hpp), --version, a
// top-level help with one line per subcommand, number checks that print their limit, and the
// checks of an --out folder or file. Header-only but for versionText() (core/version.hpp).
#pragma once

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

#include "core/config.hpp"
#include "core/exit_codes.hpp"
#include "core/version.hpp"

namespace sweepmap {

// An error that knows its exit status (core/exit_codes.hpp), for what a ConfigError (usage,
// 2) is not: bad input (1), a device identity (3) or an I/O failure (4).
class CommandError : public std::runtime_error {
 public:
  CommandError(ExitCode code, const std::string& what) : std::runtime_error(what), code_(code) {}
  ExitCode code() const { return code_; }

 private:
  ExitCode code_;
};

// The exit status of an exception a command let through: its own code for a CommandError, a
// usage error for a ConfigError, an I/O failure for a file-system or stream error, else bad
// input.
inline int exitCodeOf(const std::exception& e) {
  if (const auto* c = dynamic_cast<const CommandError*>(&e)) return c->code();
  if (dynamic_cast<const ConfigError*>(&e)) return kExitUsage;
  if (dynamic_cast<const std::filesystem::filesystem_error*>(&e)) return kExitDeviceIo;
  if (dynamic_cast<const std::ios_base::failure*>(&e)) return kExitDeviceIo;
  return kExitBadInput;
}

// The exit status for an error of the parser: 0 for --help and --version, a usage error for
// every other (CLI11's own codes 105 FileError/ValidationError, 106 RequiredError, 109 ...).
inline int exitCodeOfParseError(const CLI::ParseError& e) {
  return e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success) ? kExitOk : kExitUsage;
}

// Lists each subcommand on one line, its description's first sentence (the full text stays in
// the subcommand's own --help).
class BriefFormatter : public CLI::Formatter {
 public:
  std::string make_subcommand(const CLI::App* sub) const override {
    std::string text = sub->get_description();
    // Cut at the first sentence or clause end that leaves a meaningful line.
    size_t cut = std::string::npos;
    for (const char* end : {". ", ": ", "; ", " ("}) {
      for (size_t at = text.find(end); at != std::string::npos; at = text.find(end, at + 1)) {
        if (at >= 24) {
          cut = std::min(cut, at);
          break;
        }
      }
    }
    if (cut != std::string::npos) text = text.substr(0, cut);
    if (!text.empty() && text.back() == '.') text.pop_back();
    const size_t kMax = 62;
    if (text.size() > kMax) text = text.substr(0, text.rfind(' ', kMax - 4)) + " ...";
    std::ostringstream out;
    CLI::detail::format_help(out, sub->get_name(), text, 16);
    return out.str();
  }
};

// Parses argv into `app` (with --version added). Returns nothing when the command is to run,
// else the exit status: 0 after --help or --version (printed on stdout), kExitUsage after a
// parse error (the parser's message and a pointer to --help on stderr).
inline std::optional<int> parseCommandLine(CLI::App& app, int argc, const char* const* argv) {
  const std::string name = !app.get_name().empty() ? app.get_name()
                           : argc > 0 ? std::filesystem::path(argv[0]).filename().string()
                                      : std::string("sweepmap");
  app.set_version_flag("--version", name + " " + versionText(),
                       "print the version and the git commit, then exit");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return exitCodeOfParseError(e);
  }
  return std::nullopt;
}

namespace detail_cli {
inline std::string formatLimit(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

// A check of a number against `limit`: `ok(value)`, else "must be WHAT LIMIT, got TEXT".
inline CLI::Validator limitCheck(double limit, bool (*ok)(double value, double limit),
                                 const std::string& what, const std::string& symbol) {
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        double v = 0;
        if (!CLI::detail::lexical_cast(text, v) || !std::isfinite(v))
          return "not a number: " + text;
        if (!ok(v, limit)) return "must be " + what + " " + formatLimit(limit) + ", got " + text;
        return "";
      },
      symbol + formatLimit(limit));
}
}  // namespace detail_cli

// Number checks that say their limit: "must be at least 1, got 0" (CLI::PositiveNumber prints
// a 300-digit range).
inline CLI::Validator atLeast(double min) {
  return detail_cli::limitCheck(
      min, [](double v, double limit) { return v >= limit; }, "at least", ">=");
}
inline CLI::Validator greaterThan(double min) {
  return detail_cli::limitCheck(
      min, [](double v, double limit) { return v > limit; }, "more than", ">");
}

// --out DIR of a command that writes a folder: made if missing. A non-empty folder is refused
// (its old files would mix with the new ones) unless `force`, which empties it first; a file
// there is refused. Throws ConfigError (a usage error) naming the folder and the fix.
inline void prepareOutputDir(const std::string& dir, bool force) {
  namespace fs = std::filesystem;
  const fs::path p(dir);
  std::error_code ec;
  if (fs::exists(p, ec) && !fs::is_directory(p, ec)) {
    throw ConfigError("--out '" + dir + "' is a file; give a folder (it will hold several files)");
  }
  if (fs::is_directory(p, ec) && !fs::is_empty(p, ec)) {
    if (!force) {
      throw ConfigError("--out '" + dir +
                        "' is a folder that is not empty (an earlier run's files would mix with "
                        "this one's): give a new folder, or add --force to empty it first");
    }
    const fs::path canon = fs::weakly_canonical(p);
    const fs::path cwd = fs::current_path();
    if (canon == canon.root_path() || cwd == canon ||
        std::mismatch(canon.begin(), canon.end(), cwd.begin(), cwd.end()).first == canon.end()) {
      throw ConfigError("--out '" + dir + "' --force: refusing to empty " + canon.string() +
                        " (the root or the current folder, or a folder above it)");
    }
    for (const auto& entry : fs::directory_iterator(p)) fs::remove_all(entry.path());
  }
  fs::create_directories(p);
}

// --out FILE of a command that writes one file: refused when it names a folder, when its
// folder does not exist, or when it is one of the command's `inputs` (it would overwrite the
// capture it reads). Throws ConfigError naming the path and the fix.
inline void checkOutputFile(const std::string& file, const std::vector<std::string>& inputs = {}) {
  namespace fs = std::filesystem;
  std::error_code ec;
  for (const std::string& in : inputs) {
    if (fs::exists(file, ec) && fs::equivalent(file, in, ec)) {
      throw ConfigError("--out '" + file + "' is the input '" + in +
                        "': it would be overwritten; give another file name");
    }
  }
  if (fs::is_directory(file, ec)) {
    throw ConfigError("--out '" + file + "' is a folder; give a file name (e.g. " +
                      (fs::path(file) / "run.lcmlog").string() + ")");
  }
  const fs::path parent = fs::absolute(file).parent_path();
  if (!fs::is_directory(parent, ec)) {
    throw ConfigError("--out '" + file + "': its folder " + parent.string() + " does not exist");
  }
}

}  // namespace sweepmap
