#include "tools/ops/deploy.hpp"

#include <arpa/inet.h>
#include <yaml-cpp/yaml.h>

#include <cctype>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "core/config.hpp"

namespace sweepmap {
namespace {

// Where a node is: "FILE:LINE:COL" (yaml-cpp counts from 0).
std::string where(const std::string& source, const YAML::Node& n) {
  const YAML::Mark m = n.Mark();
  if (m.is_null()) return source;
  return source + ":" + std::to_string(m.line + 1) + ":" + std::to_string(m.column + 1);
}

[[noreturn]] void fail(const std::string& source, const YAML::Node& at, const std::string& key,
                       const std::string& what) {
  throw ConfigError(where(source, at) + ": key '" + key + "': " + what);
}

// A map whose keys must all be in `allowed` and include every key of `required`.
class Map {
 public:
  Map(const std::string& source, const YAML::Node& node, const std::string& key,
      const std::set<std::string>& required, const std::set<std::string>& optional)
      : source_(source), node_(node), key_(key) {
    if (!node.IsMap()) fail(source, node, key, "expected a map");
    for (const auto& kv : node) {
      const std::string k = kv.first.as<std::string>();
      if (!required.count(k) && !optional.count(k)) {
        fail(source, kv.first, join(k),
             "unknown key (expected one of " + list(required, optional) + ")");
      }
    }
    for (const auto& k : required) {
      if (!node[k]) fail(source, node, join(k), "missing");
    }
  }
  std::string join(const std::string& k) const { return key_.empty() ? k : key_ + "." + k; }
  bool has(const std::string& k) const { return static_cast<bool>(node_[k]); }
  YAML::Node operator[](const std::string& k) const { return node_[k]; }

  std::string text(const std::string& k) const {
    const YAML::Node n = node_[k];
    if (!n.IsScalar() || n.Scalar().empty()) fail(source_, n, join(k), "expected a non-empty text");
    return n.Scalar();
  }
  double positive(const std::string& k) const {
    const YAML::Node n = node_[k];
    double v = 0;
    try {
      v = n.as<double>();
    } catch (const YAML::Exception&) {
      fail(source_, n, join(k), "expected a number, got '" + scalarOf(n) + "'");
    }
    if (!(v > 0)) fail(source_, n, join(k), "must be > 0, got " + scalarOf(n));
    return v;
  }
  bool flag(const std::string& k) const {
    const YAML::Node n = node_[k];
    try {
      return n.as<bool>();
    } catch (const YAML::Exception&) {
      fail(source_, n, join(k), "expected true or false, got '" + scalarOf(n) + "'");
    }
  }

 private:
  static std::string scalarOf(const YAML::Node& n) { return n.IsScalar() ? n.Scalar() : "?"; }
  static std::string list(const std::set<std::string>& a, const std::set<std::string>& b) {
    std::set<std::string> all(a);
    all.insert(b.begin(), b.end());
    std::string s;
    for (const auto& k : all) s += (s.empty() ? "" : ", ") + k;
    return s;
  }
  const std::string& source_;
  YAML::Node node_;
  std::string key_;
};

// Process and host names become unit and file names.
void checkName(const std::string& source, const YAML::Node& n, const std::string& key) {
  const std::string s = n.Scalar();
  for (char c : s) {
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_')) {
      fail(source, n, key, "'" + s + "': only letters, digits, '-' and '_'");
    }
  }
}

DeployProcess parseProcess(const std::string& source, const YAML::Node& node,
                           const std::string& key) {
  const Map m(source, node, key, {"name", "command"},
              {"args", "restart", "notify", "stop_timeout_s"});
  DeployProcess p;
  p.name = m.text("name");
  checkName(source, m["name"], m.join("name"));
  p.command = m.text("command");
  if (m.has("args")) {
    const YAML::Node args = m["args"];
    if (!args.IsSequence()) fail(source, args, m.join("args"), "expected a list of arguments");
    for (size_t i = 0; i < args.size(); ++i) {
      if (!args[i].IsScalar()) {
        fail(source, args[i], m.join("args") + "[" + std::to_string(i) + "]", "expected a text");
      }
      p.args.push_back(args[i].Scalar());
    }
  }
  if (m.has("restart")) {
    const std::string r = m.text("restart");
    if (r != "on-failure" && r != "always") {
      fail(source, m["restart"], m.join("restart"), "'" + r + "': expected on-failure or always");
    }
    p.restart_always = r == "always";
  }
  // The sweepmap processes speak sd_notify; another command says so with notify: true.
  const std::string base = std::filesystem::path(p.command).filename().string();
  p.notify = m.has("notify") ? m.flag("notify") : base.rfind("sweepmap-", 0) == 0;
  if (m.has("stop_timeout_s")) p.stop_timeout_s = m.positive("stop_timeout_s");
  return p;
}

RestartPolicy parseRestart(const std::string& source, const YAML::Node& node) {
  const Map m(source, node, "restart",
              {"delay_s", "max_delay_s", "stable_s", "watchdog_s", "stop_timeout_s"}, {});
  RestartPolicy r;
  r.delay_s = m.positive("delay_s");
  r.max_delay_s = m.positive("max_delay_s");
  r.stable_s = m.positive("stable_s");
  r.watchdog_s = m.positive("watchdog_s");
  r.stop_timeout_s = m.positive("stop_timeout_s");
  if (r.max_delay_s < r.delay_s) {
    fail(source, node["max_delay_s"], "restart.max_delay_s", "must be >= restart.delay_s");
  }
  return r;
}

}  // namespace

const DeployHost& Deployment::host(const std::string& name) const {
  std::string names;
  for (const auto& h : hosts) {
    if (h.name == name) return h;
    names += (names.empty() ? "" : ", ") + h.name;
  }
  throw ConfigError(path + ": no host '" + name + "' (hosts: " + names + ")");
}

std::vector<DeployProcess> Deployment::processes(const std::string& host_name) const {
  if (!host_name.empty()) return host(host_name).processes;
  std::vector<DeployProcess> all;
  for (const auto& h : hosts) all.insert(all.end(), h.processes.begin(), h.processes.end());
  return all;
}

Deployment parseDeployment(const std::string& yaml_text, const std::string& source) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw ConfigError(source + ":" + std::to_string(e.mark.line + 1) + ":" +
                      std::to_string(e.mark.column + 1) + ": " + e.msg);
  }
  const Map top(source, root, "", {"lcm_url", "restart", "hosts"}, {"description", "key_file"});
  Deployment d;
  d.path = source;
  d.lcm_url = top.text("lcm_url");
  if (top.has("key_file")) {
    d.key_file = top.text("key_file");
    if (d.key_file.front() != '/') {
      fail(source, top["key_file"], "key_file", "'" + d.key_file + "': expected an absolute path");
    }
  }
  d.restart = parseRestart(source, top["restart"]);
  const YAML::Node hosts = top["hosts"];
  if (!hosts.IsMap() || hosts.size() == 0) fail(source, hosts, "hosts", "expected a map of hosts");
  std::set<std::string> process_names;
  for (const auto& kv : hosts) {
    DeployHost h;
    h.name = kv.first.as<std::string>();
    const std::string hkey = "hosts." + h.name;
    checkName(source, kv.first, hkey);
    const Map hm(source, kv.second, hkey, {"address", "processes"}, {});
    h.address = hm.text("address");
    // The address is who the other hosts' processes hear (--allow-senders): an IPv4 address.
    in_addr unused{};
    if (::inet_pton(AF_INET, h.address.c_str(), &unused) != 1) {
      fail(source, hm["address"], hm.join("address"),
           "'" + h.address + "': expected an IPv4 address (a.b.c.d)");
    }
    const YAML::Node procs = hm["processes"];
    if (!procs.IsSequence()) fail(source, procs, hm.join("processes"), "expected a list");
    for (size_t i = 0; i < procs.size(); ++i) {
      const std::string pkey = hm.join("processes") + "[" + std::to_string(i) + "]";
      DeployProcess p = parseProcess(source, procs[i], pkey);
      if (!process_names.insert(p.name).second) {
        fail(source, procs[i]["name"], pkey + ".name",
             "'" + p.name + "' twice (names are unique across hosts)");
      }
      h.processes.push_back(std::move(p));
    }
    d.hosts.push_back(std::move(h));
  }
  return d;
}

Deployment loadDeployment(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw ConfigError(path + ": cannot open");
  std::ostringstream s;
  s << in.rdbuf();
  return parseDeployment(s.str(), path);
}

std::string Deployment::senderAddresses() const {
  std::string list;
  for (const auto& h : hosts) list += (list.empty() ? "" : ",") + h.address;
  return list;
}

bool takesSecurityOptions(const DeployProcess& p) {
  if (p.command.rfind("sweepmap-", 0) == 0) return true;
  return p.command == "sweepmap" && !p.args.empty() && p.args[0] == "record";
}

std::vector<std::string> processArgv(const Deployment& d, const DeployProcess& p,
                                     const std::string& bin_dir, bool secure) {
  const bool ours = p.command == "sweepmap" || p.command.rfind("sweepmap-", 0) == 0;
  std::vector<std::string> argv = {ours ? (std::filesystem::path(bin_dir) / p.command).string()
                                        : p.command};
  argv.insert(argv.end(), p.args.begin(), p.args.end());
  argv.insert(argv.end(), {"--lcm-url", d.lcm_url});
  if (secure && takesSecurityOptions(p)) {
    argv.insert(argv.end(), {"--allow-senders", d.senderAddresses(), "--key-file", d.key_file});
  }
  return argv;
}

}  // namespace sweepmap
