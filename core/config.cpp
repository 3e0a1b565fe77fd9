#include "core/config.hpp"

#include <yaml-cpp/yaml.h>

#include <charconv>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <limits>
#include <ostream>
#include <set>
#include <sstream>

namespace sweepmap {
namespace {

// Shortest text that reads back as the same double ("40", "0.25", "29.3598").
std::string formatDouble(double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

double parseDouble(const std::string& text) {
  size_t used = 0;
  double v = 0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    throw std::invalid_argument("expected a number");  // not std::stod's bare "stod"
  }
  if (used != text.size() || !std::isfinite(v))
    throw std::invalid_argument("expected a finite number");
  return v;
}

int parseInt(const std::string& text) {
  size_t used = 0;
  long v = 0;
  try {
    v = std::stol(text, &used);
  } catch (const std::out_of_range&) {
    throw std::invalid_argument("expected an integer of at most 10 digits");
  } catch (const std::exception&) {
    throw std::invalid_argument("expected an integer");  // not std::stol's bare "stol"
  }
  if (used != text.size()) throw std::invalid_argument("expected an integer");
  if (v < std::numeric_limits<int>::min() || v > std::numeric_limits<int>::max()) {
    throw std::invalid_argument("expected an integer between " +
                                std::to_string(std::numeric_limits<int>::min()) + " and " +
                                std::to_string(std::numeric_limits<int>::max()));
  }
  return static_cast<int>(v);
}

void flatten(const YAML::Node& node, const std::string& prefix,
             std::vector<std::pair<std::string, YAML::Node>>* out, const std::string& source) {
  if (!node.IsMap()) {
    out->emplace_back(prefix, node);
    return;
  }
  for (const auto& kv : node) {
    const std::string name = kv.first.as<std::string>();
    const std::string key = prefix.empty() ? name : prefix + "." + name;
    if (kv.second.IsMap()) {
      flatten(kv.second, key, out, source);
    } else if (kv.second.IsScalar()) {
      out->emplace_back(key, kv.second);
    } else {
      throw ConfigError(source + ": key '" + key + "' must be a scalar or a map");
    }
  }
}

}  // namespace

void ConfigSchema::addEntry(Entry entry) {
  if (index_.count(entry.key)) throw std::logic_error("config key declared twice: " + entry.key);
  entry.default_text = entry.format();
  index_[entry.key] = entries_.size();
  entries_.push_back(std::move(entry));
}

void ConfigSchema::add(const std::string& key, double* value, const std::string& unit,
                       const std::string& help) {
  addEntry({key, unit, help, [value](const std::string& t) { *value = parseDouble(t); },
            [value] { return formatDouble(*value); }});
}

void ConfigSchema::add(const std::string& key, int* value, const std::string& unit,
                       const std::string& help) {
  addEntry({key, unit, help, [value](const std::string& t) { *value = parseInt(t); },
            [value] { return std::to_string(*value); }});
}

void ConfigSchema::add(const std::string& key, bool* value, const std::string& unit,
                       const std::string& help) {
  addEntry({key, unit, help,
            [value](const std::string& t) {
              if (t == "true") {
                *value = true;
              } else if (t == "false") {
                *value = false;
              } else {
                throw std::invalid_argument("expected true or false");
              }
            },
            [value] { return std::string(*value ? "true" : "false"); }});
}

void ConfigSchema::add(const std::string& key, std::string* value, const std::string& unit,
                       const std::string& help) {
  addEntry(
      {key, unit, help, [value](const std::string& t) { *value = t; }, [value] { return *value; }});
}

void ConfigSchema::assign(const std::string& key, const std::string& text,
                          const std::string& source) {
  const auto it = index_.find(key);
  if (it == index_.end()) throw ConfigError(source + ": unknown key '" + key + "'");
  try {
    entries_[it->second].parse(text);
  } catch (const std::exception& e) {
    throw ConfigError(source + ": key '" + key + "': bad value '" + text + "' (" + e.what() + ")");
  }
}

void ConfigSchema::loadString(const std::string& yaml_text, const std::string& source) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw ConfigError(source + ": line " + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  if (!root.IsMap()) throw ConfigError(source + ": top level must be a map of keys");
  std::vector<std::pair<std::string, YAML::Node>> flat;
  flatten(root, "", &flat, source);
  std::set<std::string> seen;
  for (const auto& [key, node] : flat) {
    const std::string where = source + ":" + std::to_string(node.Mark().line + 1);
    assign(key, node.as<std::string>(), where);
    seen.insert(key);
  }
  for (const auto& e : entries_) {
    if (!seen.count(e.key)) throw ConfigError(source + ": missing key '" + e.key + "'");
  }
}

void ConfigSchema::loadFile(const std::string& path) {
  YAML::Node probe;
  std::string text;
  {
    std::ifstream in(path);
    if (!in) throw ConfigError(path + ": cannot open");
    std::ostringstream s;
    s << in.rdbuf();
    text = s.str();
  }
  loadString(text, path);
}

void ConfigSchema::set(const std::string& assignment) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0) {
    throw ConfigError("--set: expected key=value, got '" + assignment + "'");
  }
  assign(assignment.substr(0, eq), assignment.substr(eq + 1), "--set");
}

void ConfigSchema::print(std::ostream& out, const ConfigSchema* defaults) const {
  size_t width = 0;
  for (const auto& e : entries_) width = std::max(width, e.key.size());
  for (const auto& e : entries_) {
    out << std::left << std::setw(static_cast<int>(width)) << e.key << " = " << e.format();
    if (!e.unit.empty()) out << " [" << e.unit << "]";
    std::string def = e.default_text;
    if (defaults && defaults->has(e.key))
      def = defaults->entries_[defaults->index_.at(e.key)].default_text;
    out << "  # " << e.help << " (default: " << (def.empty() ? "\"\"" : def) << ")\n";
  }
}

namespace {

// Emits `items` (dotted key -> value, declaration order) as nested maps.
void emitNested(YAML::Emitter& em, const std::vector<std::pair<std::string, std::string>>& items) {
  em << YAML::BeginMap;
  std::vector<std::string> order;
  std::map<std::string, std::vector<std::pair<std::string, std::string>>> children;
  for (const auto& [key, value] : items) {
    const auto dot = key.find('.');
    if (dot == std::string::npos) {
      em << YAML::Key << key << YAML::Value << value;
      continue;
    }
    const std::string head = key.substr(0, dot);
    if (!children.count(head)) order.push_back(head);
    children[head].emplace_back(key.substr(dot + 1), value);
  }
  for (const auto& head : order) {
    em << YAML::Key << head << YAML::Value;
    emitNested(em, children[head]);
  }
  em << YAML::EndMap;
}

}  // namespace

std::string ConfigSchema::toYaml() const {
  std::vector<std::pair<std::string, std::string>> items;
  for (const auto& e : entries_) items.emplace_back(e.key, e.format());
  YAML::Emitter em;
  emitNested(em, items);
  return std::string(em.c_str()) + "\n";
}

std::vector<std::string> ConfigSchema::keys() const {
  std::vector<std::string> k;
  for (const auto& e : entries_) k.push_back(e.key);
  return k;
}

}  // namespace sweepmap
