// LCM type definitions read at run time: the .lcm files this build was made from (embedded
// at build time), parsed, their fingerprints computed as lcm-gen computes them, and any
// message decoded field by field, by name. `sweepmap dump` prints logs with it; nothing
// here depends on the generated C++ types.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace sweepmap {

// The embedded .lcm files: {file name, text} (tools/offline/embed_lcm.cmake).
const std::vector<std::pair<std::string, std::string>>& lcmTypeSources();

struct LcmMember {
  std::string type;  // int8_t ... double, string, boolean, byte, or a struct name
  std::string name;
  std::vector<std::string> dims;  // each a number or the name of an earlier integer member
  std::string comment;            // the line's // comment, if any (units)
};

struct LcmStruct {
  std::string package, name;  // name without the package
  std::vector<LcmMember> members;
  int64_t base_hash = 0;    // lcm-gen's hash of the members
  int64_t fingerprint = 0;  // what a message starts with (the generated getHash())
};

class LcmSchemaError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A decoded value: a number, a string, or an array/struct of values.
struct LcmValue {
  enum class Kind { kInt, kDouble, kString, kBool, kArray, kStruct } kind = Kind::kInt;
  int64_t i = 0;
  double d = 0.0;
  std::string s;
  std::vector<LcmValue> items;                           // array elements
  std::vector<std::pair<std::string, LcmValue>> fields;  // struct members in order
};

class LcmSchema {
 public:
  // Parses `sources`; throws LcmSchemaError naming the file and line.
  explicit LcmSchema(const std::vector<std::pair<std::string, std::string>>& sources);
  // The embedded definitions.
  static const LcmSchema& builtIn();

  const LcmStruct* find(
      const std::string& name) const;  // "lidar_scan_t" or "sweepmap.lidar_scan_t"
  const LcmStruct* byFingerprint(int64_t fingerprint) const;
  const std::vector<LcmStruct>& structs() const { return structs_; }

  // Decodes a whole message (fingerprint first). Throws LcmSchemaError naming the field
  // and the byte offset when the bytes do not fit the type (never allocates from a count
  // the bytes cannot hold). Returns nullptr for an unknown fingerprint.
  const LcmStruct* decode(const uint8_t* data, size_t size, LcmValue* out) const;

 private:
  std::vector<LcmStruct> structs_;
  std::map<int64_t, size_t> by_fingerprint_;
};

}  // namespace sweepmap
