// Deployment files (tools/ops/deploy.hpp): the shipped ones load; a bad key, a missing key, a
// bad value or an unknown host is one error naming the file, the line and column and the key;
// the systemd units written from them say what the deployment says.
#include <gtest/gtest.h>

#include <filesystem>

#include "core/config.hpp"
#include "rigs/rig_file.hpp"
#include "tools/ops/deploy.hpp"
#include "tools/ops/systemd_units.hpp"

namespace sweepmap {
namespace {

const std::string kValid = R"(lcm_url: udpm://239.255.76.67:7667?ttl=1
restart:
  delay_s: 0.5
  max_delay_s: 10
  stable_s: 60
  watchdog_s: 5
  stop_timeout_s: 30
hosts:
  laptop:
    address: 192.168.1.10
    processes:
      - {name: logger, command: lcm-logger, args: [-i, run.lcmlog]}
      - name: mapper
        command: sweepmap-mapper
        args: [--rig, rig_a, --save, "my map.bt"]
        stop_timeout_s: 120
  pi:
    address: 192.168.1.20
    processes:
      - {name: motor, command: sweepmap-motor, args: [--rig, rig_a], restart: always}
)";

// The error that parsing `text` throws ("" if none).
std::string errorOf(const std::string& text) {
  try {
    parseDeployment(text, "deploy.yaml");
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return text.replace(at, from.size(), to);
}

TEST(DeployFile, ParsesHostsProcessesAndPolicy) {
  const Deployment d = parseDeployment(kValid, "deploy.yaml");
  EXPECT_EQ(d.lcm_url, "udpm://239.255.76.67:7667?ttl=1");
  EXPECT_DOUBLE_EQ(d.restart.delay_s, 0.5);
  EXPECT_DOUBLE_EQ(d.restart.watchdog_s, 5.0);
  ASSERT_EQ(d.hosts.size(), 2u);
  EXPECT_EQ(d.hosts[0].name, "laptop");  // file order
  EXPECT_EQ(d.hosts[1].address, "192.168.1.20");
  const auto& logger = d.hosts[0].processes[0];
  EXPECT_EQ(logger.command, "lcm-logger");
  EXPECT_FALSE(logger.notify);  // only the sweepmap-* processes speak sd_notify by default
  EXPECT_TRUE(d.hosts[0].processes[1].notify);
  EXPECT_DOUBLE_EQ(d.stopTimeout(d.hosts[0].processes[1]), 120.0);
  EXPECT_DOUBLE_EQ(d.stopTimeout(logger), 30.0);
  EXPECT_TRUE(d.hosts[1].processes[0].restart_always);
  EXPECT_FALSE(logger.restart_always);
  EXPECT_EQ(d.processes("").size(), 3u);
  EXPECT_EQ(d.processes("pi").size(), 1u);
  EXPECT_EQ(processArgv(d, d.hosts[1].processes[0], "/opt/bin"),
            (std::vector<std::string>{"/opt/bin/sweepmap-motor", "--rig", "rig_a", "--lcm-url",
                                      "udpm://239.255.76.67:7667?ttl=1"}));
  EXPECT_EQ(processArgv(d, logger, "/opt/bin")[0], "lcm-logger");  // from PATH
}

TEST(DeployFile, ShippedFilesLoad) {
  for (const char* name : {"deploy_rig_a.yaml", "deploy_rig_b.yaml"}) {
    const Deployment d = loadDeployment(std::string(SWEEPMAP_SOURCE_DIR) + "/config/" + name);
    EXPECT_NE(d.lcm_url.find("ttl=1"), std::string::npos) << name;
    EXPECT_EQ(d.key_file, "/etc/sweepmap/lcm.key") << name;
    EXPECT_EQ(d.senderAddresses(), "192.168.1.10,192.168.1.20") << name;
    EXPECT_EQ(d.host("pi").processes.size(), 2u) << name;
    EXPECT_EQ(d.host("laptop").processes.size(), 3u) << name;
    // Every sweepmap process's rig loads with its --set overrides (the rig names resolve in
    // the config folder, the overridden keys exist).
    for (const auto& p : d.processes("")) {
      std::string rig;
      std::vector<std::string> sets;
      for (size_t i = 0; i + 1 < p.args.size(); ++i) {
        if (p.args[i] == "--rig") rig = p.args[i + 1];
        if (p.args[i] == "--set") sets.push_back(p.args[i + 1]);
      }
      if (p.command.rfind("sweepmap-", 0) != 0) continue;
      ASSERT_FALSE(rig.empty()) << name << " " << p.name;
      ::setenv("SWEEPMAP_CONFIG_DIR", SWEEPMAP_SOURCE_DIR "/config", 1);
      EXPECT_NO_THROW(loadRig(rig, sets)) << name << " " << p.name;
    }
  }
}

TEST(DeployFile, UnknownKeyNamesFileLineColumnAndKey) {
  const std::string e = errorOf(replaced(kValid, "        stop_timeout_s: 120",
                                         "        stop_timeout_s: 120\n        nice: 5"));
  EXPECT_NE(e.find("deploy.yaml:17:9: key 'hosts.laptop.processes[1].nice': unknown key"),
            std::string::npos)
      << e;
}

TEST(DeployFile, MissingKeyIsNamed) {
  EXPECT_NE(
      errorOf(replaced(kValid, "  watchdog_s: 5\n", "")).find("key 'restart.watchdog_s': missing"),
      std::string::npos);
  EXPECT_NE(errorOf(replaced(kValid, "    address: 192.168.1.20\n", ""))
                .find("key 'hosts.pi.address': missing"),
            std::string::npos);
  EXPECT_NE(errorOf(replaced(kValid, "command: sweepmap-motor, ", ""))
                .find("key 'hosts.pi.processes[0].command': missing"),
            std::string::npos);
}

TEST(DeployFile, BadValuesAreNamed) {
  const std::string e = errorOf(replaced(kValid, "delay_s: 0.5", "delay_s: soon"));
  EXPECT_NE(e.find("deploy.yaml:3:12: key 'restart.delay_s': expected a number, got 'soon'"),
            std::string::npos)
      << e;
  EXPECT_NE(
      errorOf(replaced(kValid, "restart: always", "restart: sometimes"))
          .find("key 'hosts.pi.processes[0].restart': 'sometimes': expected on-failure or always"),
      std::string::npos);
  EXPECT_NE(errorOf(replaced(kValid, "max_delay_s: 10", "max_delay_s: 0.1"))
                .find("restart.max_delay_s': must be >= restart.delay_s"),
            std::string::npos);
  EXPECT_NE(errorOf(replaced(kValid, "{name: motor,", "{name: logger,")).find("'logger' twice"),
            std::string::npos);
  EXPECT_NE(errorOf(replaced(kValid, "name: mapper", "name: map/per")).find("only letters"),
            std::string::npos);
  EXPECT_NE(errorOf("hosts: [").find("deploy.yaml:1:"), std::string::npos);  // YAML syntax
}

TEST(DeployFile, UnknownHostListsTheHosts) {
  const Deployment d = parseDeployment(kValid, "deploy.yaml");
  try {
    d.host("robot");
    FAIL() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()), "deploy.yaml: no host 'robot' (hosts: laptop, pi)");
  }
  EXPECT_THROW(systemdUnits(d, "robot", "/usr/bin"), ConfigError);
}

TEST(SystemdUnits, OneServicePerProcessAndATarget) {
  const Deployment d = parseDeployment(kValid, "deploy.yaml");
  const auto units = systemdUnits(d, "laptop", "/usr/bin");
  ASSERT_EQ(units.size(), 3u);
  EXPECT_EQ(units[0].name, "sweepmap-logger.service");
  EXPECT_EQ(units[1].name, "sweepmap-mapper.service");
  EXPECT_EQ(units[2].name, "sweepmap-laptop.target");
  const std::string& mapper = units[1].text;
  for (const char* line :
       {"\nType=notify\n", "\nWatchdogSec=5\n", "\nRestart=on-failure\n", "\nRestartSec=0.5\n",
        "\nTimeoutStopSec=120\n", "\nKillSignal=SIGINT\n", "\nPartOf=sweepmap-laptop.target\n",
        "\nWantedBy=sweepmap-laptop.target\n", "\nAfter=network-online.target time-sync.target\n",
        "\nEnvironment=LCM_DEFAULT_URL=udpm://239.255.76.67:7667?ttl=1\n",
        "\nExecStart=/usr/bin/sweepmap-mapper --rig rig_a --save \"my map.bt\" --lcm-url "
        "udpm://239.255.76.67:7667?ttl=1 --allow-senders 192.168.1.10,192.168.1.20 --key-file "
        "/etc/sweepmap/lcm.key\n",
        "\nRestartPreventExitStatus=2\n"}) {
    EXPECT_NE(mapper.find(line), std::string::npos) << line << " not in\n" << mapper;
  }
  // lcm-logger does not speak sd_notify: a simple service without a watchdog.
  EXPECT_NE(units[0].text.find("\nType=simple\n"), std::string::npos);
  EXPECT_EQ(units[0].text.find("WatchdogSec"), std::string::npos);
  EXPECT_NE(units[0].text.find("\nExecStart=lcm-logger -i run.lcmlog --lcm-url "
                               "udpm://239.255.76.67:7667?ttl=1\n"),
            std::string::npos);  // lcm-logger takes no --allow-senders nor --key-file
  EXPECT_EQ(units[0].text.find("RestartPreventExitStatus"), std::string::npos);
  EXPECT_NE(units[2].text.find("\nWants=sweepmap-logger.service sweepmap-mapper.service\n"),
            std::string::npos);
  EXPECT_NE(units[2].text.find("\nWantedBy=multi-user.target\n"), std::string::npos);
  EXPECT_NE(systemdUnits(d, "pi", "/usr/bin")[0].text.find("\nRestart=always\n"),
            std::string::npos);
}

// On by default in the units, off on a bench (`launch` without --secure, `systemd --insecure`):
// every sweepmap process and `sweepmap record` hear only the file's hosts and sign with its key.
TEST(SystemdUnits, SecureByDefaultWithTheHostsAndTheKeyFile) {
  const Deployment d =
      parseDeployment(replaced(kValid, "hosts:\n", "key_file: /etc/robot/k.key\nhosts:\n") +
                          "      - {name: rec, command: sweepmap, args: [record, --out, logs]}\n"
                          "      - {name: dump, command: sweepmap, args: [dump, x.lcmlog]}\n",
                      "deploy.yaml");
  EXPECT_EQ(d.key_file, "/etc/robot/k.key");
  EXPECT_EQ(d.senderAddresses(), "192.168.1.10,192.168.1.20");
  const auto units = systemdUnits(d, "pi", "/usr/bin");
  ASSERT_EQ(units.size(), 4u);
  const std::string secure =
      " --allow-senders 192.168.1.10,192.168.1.20 --key-file /etc/robot/k.key\n";
  EXPECT_NE(units[0].text.find("\nExecStart=/usr/bin/sweepmap-motor --rig rig_a --lcm-url "
                               "udpm://239.255.76.67:7667?ttl=1" +
                               secure),
            std::string::npos)
      << units[0].text;
  EXPECT_NE(units[1].text.find("\nExecStart=/usr/bin/sweepmap record --out logs --lcm-url "
                               "udpm://239.255.76.67:7667?ttl=1" +
                               secure),
            std::string::npos)
      << units[1].text;
  EXPECT_EQ(units[2].text.find("--key-file"), std::string::npos);  // `sweepmap dump` takes none
  for (const auto& u : systemdUnits(d, "pi", "/usr/bin", false)) {
    EXPECT_EQ(u.text.find("--allow-senders"), std::string::npos) << u.text;
    EXPECT_EQ(u.text.find("--key-file"), std::string::npos) << u.text;
  }
  // A bench: launch's command lines have neither unless asked.
  const DeployProcess& motor = d.host("pi").processes[0];
  EXPECT_EQ(processArgv(d, motor, "/b").size(), 5u);
  EXPECT_EQ(processArgv(d, motor, "/b", true).size(), 9u);
}

TEST(DeployFile, KeyFileAndAddressesAreChecked) {
  const Deployment d = parseDeployment(kValid, "deploy.yaml");
  EXPECT_EQ(d.key_file, "/etc/sweepmap/lcm.key");  // the default
  EXPECT_NE(errorOf(replaced(kValid, "hosts:\n", "key_file: lcm.key\nhosts:\n"))
                .find("key 'key_file': 'lcm.key': expected an absolute path"),
            std::string::npos);
  EXPECT_NE(errorOf(replaced(kValid, "address: 192.168.1.20", "address: the-pi"))
                .find("key 'hosts.pi.address': 'the-pi': expected an IPv4 address"),
            std::string::npos);
}

TEST(SystemdUnits, QuotesWhatSystemdWouldSplitOrExpand) {
  EXPECT_EQ(systemdQuote("plain"), "plain");
  EXPECT_EQ(systemdQuote("a b"), "\"a b\"");
  EXPECT_EQ(systemdQuote(""), "\"\"");
  EXPECT_EQ(systemdQuote("50%"), "50%%");
  EXPECT_EQ(systemdQuote("$HOME"), "$$HOME");
  EXPECT_EQ(systemdQuote("say \"hi\""), "\"say \\\"hi\\\"\"");
  EXPECT_EQ(systemdQuote("a\\b"), "\"a\\\\b\"");
}

TEST(SystemdUnits, WrittenAtomicallyIntoTheFolder) {
  const Deployment d = parseDeployment(kValid, "deploy.yaml");
  const auto dir = std::filesystem::path(SWEEPMAP_BINARY_DIR) / "test_scratch" / "systemd_units";
  std::filesystem::remove_all(dir);
  const auto paths = writeSystemdUnits(d, "pi", "/usr/bin", dir.string());
  ASSERT_EQ(paths.size(), 2u);
  for (const auto& p : paths) EXPECT_TRUE(std::filesystem::exists(p)) << p;
  size_t files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) files += e.is_regular_file();
  EXPECT_EQ(files, 2u);  // no temporary left behind
}

}  // namespace
}  // namespace sweepmap
