#include <unistd.h>

#include <filesystem>
#include <iostream>

#include "core/exit_codes.hpp"
#include "tools/cli/commands.hpp"

namespace sweepmap {

// The jar built from lcmtypes/, found relative to this executable (build/bin/sweepmap ->
// build/share/sweepmap_lcmtypes.jar).
std::string lcmtypesJar(const std::string& argv0) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec) exe = fs::absolute(argv0);
  return (exe.parent_path().parent_path() / "share" / "sweepmap_lcmtypes.jar").string();
}

Runner addSpyCommand(CLI::App& app, const std::string& argv0) {
  auto* cmd = app.add_subcommand(
      "spy",
      "Start lcm-spy with sweepmap's message types on its CLASSPATH, so every channel decodes. "
      "Runs lcm-spy's Java class directly: Debian's lcm-spy script ignores CLASSPATH and passes "
      "-Xincgc, which Java 17 rejects");
  auto url = std::make_shared<std::string>();
  auto print_only = std::make_shared<bool>(false);
  cmd->add_option("--lcm-url", *url, "LCM URL to watch (default: LCM's default)");
  cmd->add_flag("--print-command", *print_only, "print the java command line and exit");
  return [=]() -> int {
    const std::string jar = lcmtypesJar(argv0);
    if (!std::filesystem::exists(jar)) {
      std::cerr << "spy: " << jar << " not found: build the lcmtypes_jar target (needs javac)\n";
      return kExitDeviceIo;
    }
    const std::string cp = "/usr/share/java/lcm.jar:/usr/share/java/jchart2d.jar:" + jar;
    setenv("CLASSPATH", cp.c_str(), 1);
    std::vector<std::string> args = {
        "java", "-server", "-Djava.net.preferIPv4Stack=true", "-Xmx128m", "-cp", cp, "lcm.spy.Spy"};
    if (!url->empty()) args.push_back("--lcm-url=" + *url);
    if (*print_only) {
      for (const auto& a : args) std::cout << a << " ";
      std::cout << "\n";
      return 0;
    }
    std::vector<char*> cargs;
    for (auto& a : args) cargs.push_back(a.data());
    cargs.push_back(nullptr);
    execvp("java", cargs.data());
    std::cerr << "spy: cannot start java\n";
    return kExitDeviceIo;
  };
}

}  // namespace sweepmap
