// Typed configuration with strict loading.
//
// Each component declares its keys once (name, unit, help, bound to a field of its
// options struct) in a ConfigSchema. The same schema then loads a YAML file (every
// declared key must be present, every key present must be declared), applies
// `key=value` overrides from the command line, and prints every key with its
// default and unit. Errors name the file (or "--set") and the dotted key.
#pragma once

#include <functional>
#include <iosfwd>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace sweepmap {

class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class ConfigSchema {
 public:
  void add(const std::string& key, double* value, const std::string& unit, const std::string& help);
  void add(const std::string& key, int* value, const std::string& unit, const std::string& help);
  void add(const std::string& key, bool* value, const std::string& unit, const std::string& help);
  void add(const std::string& key, std::string* value, const std::string& unit,
           const std::string& help);

  // Loads a YAML file; every declared key under `prefix` must be present and no other.
  // Throws ConfigError naming the file and the key.
  void loadFile(const std::string& path);
  void loadString(const std::string& yaml_text, const std::string& source_name);

  // Applies "dotted.key=value"; throws ConfigError for unknown keys or bad values.
  void set(const std::string& assignment);

  // One line per key: key = value [unit]  # help (default: D). D is the key's value when
  // it was declared here, or in `defaults` (a schema declared over default-constructed
  // structs) when given.
  void print(std::ostream& out, const ConfigSchema* defaults = nullptr) const;

  // Writes the current values as a YAML document (nested maps), keys in declaration order.
  std::string toYaml() const;

  bool has(const std::string& key) const { return index_.count(key) != 0; }
  std::vector<std::string> keys() const;

 private:
  struct Entry {
    std::string key;
    std::string unit;
    std::string help;
    std::function<void(const std::string& text)> parse;  // throws std::invalid_argument
    std::function<std::string()> format;
    std::string default_text = {};  // value when declared (set by addEntry)
  };
  void addEntry(Entry entry);
  void assign(const std::string& key, const std::string& text, const std::string& source);

  std::vector<Entry> entries_;
  std::map<std::string, size_t> index_;
};

}  // namespace sweepmap
