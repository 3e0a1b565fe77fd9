// LCM type definitions read at run time: the .lcm files this build was made from (embedded
// at build time), parsed, their fingerprints computed as lcm-gen computes them, and any
// message decoded field by field, by name, or validated against its type. `sweepmap dump`
// prints logs with it, every process checks what it receives with it; nothing
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

// The embedded .lcm files: {file name, text} (cmake/embed_text_files.cmake).
const std::vector<std::pair<std::string, std::string>>& lcmTypeSources();

struct LcmStruct;
// The text of the embedded .lcm file that defines `s` (NAME.lcm), or "" when none does: the
// schema that MCAP files and Foxglove clients get for a raw LCM channel.
std::string lcmTypeSource(const LcmStruct& s);

struct LcmMember {
  std::string type;  // int8_t ... double, string, boolean, byte, or a struct name
  std::string name;
  std::vector<std::string> dims;  // each a number or the name of an earlier integer member
  std::string comment;            // the line's // comment, if any (units)
  // An enum: the names of the values it takes, from the struct's constants (see LcmConst).
  std::map<int64_t, std::string> enum_names;
};

// A `const TYPE NAME = VALUE, ...;` of a struct. The constants of one declaration form a
// group; an integer member of their type takes the group as its enum when its comment names
// one of them or says "constants" (`int8_t health; // OK, DEGRADED or FAILED`).
struct LcmConst {
  std::string type, name, value;  // value as written
  int group = 0;                  // the declaration's index within the struct
};

struct LcmStruct {
  std::string package, name;  // name without the package
  std::vector<LcmMember> members;
  std::vector<LcmConst> constants;
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
  std::string enum_name;  // an enum member's value: its constant's name, "?" for none
};

class LcmSchema {
 public:
  // Parses `sources` (their structs, members, constants and the enums these make) and computes
  // the fingerprints; throws LcmSchemaError naming the file and line.
  explicit LcmSchema(const std::vector<std::pair<std::string, std::string>>& sources);
  // The embedded definitions.
  static const LcmSchema& builtIn();

  const LcmStruct* find(
      const std::string& name) const;  // "lidar_scan_t" or "sweepmap.lidar_scan_t"
  const LcmStruct* byFingerprint(int64_t fingerprint) const;
  // The type a whole message declares by its fingerprint (its first 8 bytes, big-endian), or
  // nullptr when it is shorter or the type unknown; reads nothing past the fingerprint.
  const LcmStruct* typeOf(const uint8_t* data, size_t size) const;
  const std::vector<LcmStruct>& structs() const { return structs_; }

  // Decodes a whole message (fingerprint first). Throws LcmSchemaError naming the field
  // and the byte offset when the bytes do not fit the type (never allocates from a count
  // the bytes cannot hold). Returns nullptr for an unknown fingerprint.
  const LcmStruct* decode(const uint8_t* data, size_t size, LcmValue* out) const;

  // Why a whole message (fingerprint first) is not a valid message of a known type, or "" when
  // it is; allocates nothing on the way. Beyond what decode() checks (every length and count
  // against the bytes present, no bytes left over): strings NUL-terminated, at most
  // kMaxStringBytes and valid UTF-8; floats and doubles finite unless their member's comment
  // says NaN is allowed; enum members one of their constants; booleans 0 or 1; an unknown
  // fingerprint is invalid. Every type is covered by its .lcm file: a new type cannot be
  // forgotten. The reason names the type, the member and the byte offset.
  static constexpr size_t kMaxStringBytes = 64 * 1024;
  std::string validate(const uint8_t* data, size_t size) const;

 private:
  void computeFingerprints();

  std::vector<LcmStruct> structs_;
  std::map<int64_t, size_t> by_fingerprint_;
};

}  // namespace sweepmap
