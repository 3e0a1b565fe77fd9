#include "core/lcm_schema.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <set>

namespace sweepmap {
namespace {

const std::set<std::string> kPrimitive = {"int8_t", "int16_t", "int32_t", "int64_t", "byte",
                                          "float",  "double",  "string",  "boolean"};
bool isIntegerType(const std::string& t) {
  return t == "int8_t" || t == "int16_t" || t == "int32_t" || t == "int64_t" || t == "byte";
}

struct Token {
  std::string text;
  int line;
  std::string comment;  // a // comment ending the token's line
};

// Identifiers, numbers (incl. signs, dots, exponents, hex), single punctuation; comments
// dropped but a line's trailing // comment kept on the line's tokens.
std::vector<Token> tokenize(const std::string& file, const std::string& text) {
  std::vector<Token> out;
  int line = 1;
  size_t i = 0;
  while (i < text.size()) {
    const char c = text[i];
    if (c == '\n') {
      ++line;
      ++i;
    } else if (std::isspace(static_cast<unsigned char>(c))) {
      ++i;
    } else if (text.compare(i, 2, "//") == 0) {
      const size_t end = text.find('\n', i);
      std::string comment =
          text.substr(i + 2, end == std::string::npos ? std::string::npos : end - i - 2);
      while (!comment.empty() && std::isspace(static_cast<unsigned char>(comment.front())))
        comment.erase(0, 1);
      for (auto it = out.rbegin(); it != out.rend() && it->line == line; ++it)
        it->comment = comment;
      i = end == std::string::npos ? text.size() : end;
    } else if (text.compare(i, 2, "/*") == 0) {
      const size_t end = text.find("*/", i + 2);
      if (end == std::string::npos)
        throw LcmSchemaError(file + ":" + std::to_string(line) + ": unterminated comment");
      for (size_t k = i; k < end; ++k) line += text[k] == '\n';
      i = end + 2;
    } else if (std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.') {
      size_t j = i + 1;
      while (j < text.size() &&
             (std::isalnum(static_cast<unsigned char>(text[j])) || text[j] == '_' ||
              text[j] == '.' ||
              ((text[j] == '-' || text[j] == '+') && (text[j - 1] == 'e' || text[j - 1] == 'E')))) {
        ++j;
      }
      out.push_back({text.substr(i, j - i), line, ""});
      i = j;
    } else {
      out.push_back({std::string(1, c), line, ""});
      ++i;
    }
  }
  return out;
}

// lcm-gen's hash (lcmgen.c): signed 64-bit arithmetic, the shift right arithmetic.
int64_t hashUpdate(int64_t v, char c) {
  const auto u = static_cast<uint64_t>(v);
  return static_cast<int64_t>((u << 8) ^ static_cast<uint64_t>(v >> 55)) + c;
}
int64_t hashString(int64_t v, const std::string& s) {
  v = hashUpdate(v, static_cast<char>(s.size()));
  for (char c : s) v = hashUpdate(v, c);
  return v;
}

bool isNumber(const std::string& s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) {
    return std::isdigit(static_cast<unsigned char>(c));
  });
}

class Reader {
 public:
  Reader(const uint8_t* data, size_t size) : data_(data), size_(size) {}
  size_t at() const { return at_; }
  const uint8_t* take(size_t n, const std::string& what) {
    if (n > size_ - at_) {
      throw LcmSchemaError(what + " at byte " + std::to_string(at_) + ": needs " +
                           std::to_string(n) + " bytes, " + std::to_string(size_ - at_) + " left");
    }
    const uint8_t* p = data_ + at_;
    at_ += n;
    return p;
  }
  uint64_t be(size_t n, const std::string& what) {
    const uint8_t* p = take(n, what);
    uint64_t v = 0;
    for (size_t k = 0; k < n; ++k) v = (v << 8) | p[k];
    return v;
  }
  size_t left() const { return size_ - at_; }

 private:
  const uint8_t* data_;
  size_t size_;
  size_t at_ = 0;
};

// The smallest encoded size of one element of `type` (for count checks).
size_t minSize(const LcmSchema& schema, const std::string& type) {
  if (type == "int8_t" || type == "byte" || type == "boolean") return 1;
  if (type == "int16_t") return 2;
  if (type == "int32_t" || type == "float" || type == "string") return 4;
  if (type == "int64_t" || type == "double") return 8;
  return 0;  // a struct: may be empty
}

}  // namespace

namespace {

// One .lcm file's tokens to structs: `package NAME;` then `struct NAME { members and
// constants }`, each error naming the file and line.
class Parser {
 public:
  Parser(std::string file, std::vector<Token> tokens)
      : file_(std::move(file)), t_(std::move(tokens)) {}

  void parse(std::vector<LcmStruct>* out) {
    std::string package;
    while (i_ < t_.size()) {
      if (t_[i_].text == "package") {
        ++i_;
        package = take("package name");
        expect(";");
        continue;
      }
      out->push_back(parseStruct(package));
    }
  }

 private:
  std::string where() const {
    const int line = i_ < t_.size() ? t_[i_].line : (t_.empty() ? 1 : t_.back().line);
    return file_ + ":" + std::to_string(line);
  }
  void expect(const std::string& s) {
    if (i_ >= t_.size() || t_[i_].text != s) {
      throw LcmSchemaError(where() + ": expected '" + s + "'" +
                           (i_ < t_.size() ? ", found '" + t_[i_].text + "'" : ""));
    }
    ++i_;
  }
  std::string take(const std::string& what) {
    if (i_ >= t_.size()) throw LcmSchemaError(where() + ": " + what + " missing");
    return t_[i_++].text;
  }

  LcmStruct parseStruct(const std::string& package) {
    expect("struct");
    LcmStruct s;
    s.package = package;
    s.name = take("struct name");
    expect("{");
    int groups = 0;
    while (i_ < t_.size() && t_[i_].text != "}") {
      if (t_[i_].text == "const") {
        parseConstants(&s, groups++);
      } else {
        parseMember(&s);
      }
    }
    expect("}");
    return s;
  }

  // TYPE NAME [DIM]... ; with its line's comment.
  void parseMember(LcmStruct* s) {
    LcmMember m;
    m.type = t_[i_++].text;
    if (m.type.find('.') != std::string::npos) m.type = m.type.substr(m.type.rfind('.') + 1);
    if (i_ >= t_.size()) throw LcmSchemaError(where() + ": member name missing");
    m.comment = t_[i_].comment;
    m.name = t_[i_++].text;
    while (i_ < t_.size() && t_[i_].text == "[") {
      ++i_;
      m.dims.push_back(take("array size"));
      expect("]");
    }
    if (i_ < t_.size() && t_[i_].text == ";" && m.comment.empty()) m.comment = t_[i_].comment;
    expect(";");
    for (const std::string& d : m.dims) {
      if (isNumber(d)) continue;
      const auto it = std::find_if(s->members.begin(), s->members.end(),
                                   [&](const LcmMember& o) { return o.name == d; });
      if (it == s->members.end() || !it->dims.empty() || !isIntegerType(it->type)) {
        throw LcmSchemaError(where() + ": " + m.name + "[" + d +
                             "]: the size must be a number or an earlier integer member");
      }
    }
    s->members.push_back(std::move(m));
  }

  // const TYPE NAME = VALUE [, NAME = VALUE]... ;
  void parseConstants(LcmStruct* s, int group) {
    expect("const");
    const std::string type = take("constant type");
    for (;;) {
      LcmConst c;
      c.type = type;
      c.group = group;
      c.name = take("constant name");
      expect("=");
      c.value = take("constant value");
      if (isIntegerType(type)) {
        try {
          std::stoll(c.value, nullptr, 0);
        } catch (const std::exception&) {
          throw LcmSchemaError(where() + ": " + c.name + " = " + c.value + ": not an integer");
        }
      }
      s->constants.push_back(std::move(c));
      if (i_ < t_.size() && t_[i_].text == ",") {
        ++i_;
        continue;
      }
      expect(";");
      return;
    }
  }

  std::string file_;
  std::vector<Token> t_;
  size_t i_ = 0;
};

bool mentionsWord(const std::string& text, const std::string& word) {
  for (size_t at = text.find(word); at != std::string::npos; at = text.find(word, at + 1)) {
    const auto isWordChar = [](char c) {
      return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
    };
    const bool starts = at == 0 || !isWordChar(text[at - 1]);
    const bool ends = at + word.size() == text.size() || !isWordChar(text[at + word.size()]);
    if (starts && ends) return true;
  }
  return false;
}

// An integer member takes a group of constants of its type as its enum when its comment names
// one of them or says "constants" (see LcmConst).
void linkEnums(LcmStruct* s) {
  for (LcmMember& m : s->members) {
    if (!m.dims.empty() || !isIntegerType(m.type)) continue;
    for (const LcmConst& c : s->constants) {
      if (c.type != m.type) continue;
      if (!mentionsWord(m.comment, c.name) && m.comment.find("constants") == std::string::npos) {
        continue;
      }
      for (const LcmConst& e : s->constants) {
        if (e.group == c.group) m.enum_names.emplace(std::stoll(e.value, nullptr, 0), e.name);
      }
      break;
    }
  }
}

// lcm-gen: member names, primitive type names, dimensions (mode: 0 const, 1 variable).
int64_t baseHash(const LcmStruct& s) {
  int64_t v = 0x12345678;
  for (const LcmMember& m : s.members) {
    v = hashString(v, m.name);
    if (kPrimitive.count(m.type)) v = hashString(v, m.type);
    v = hashUpdate(v, static_cast<char>(m.dims.size()));
    for (const std::string& d : m.dims) {
      v = hashUpdate(v, isNumber(d) ? 0 : 1);
      v = hashString(v, d);
    }
  }
  return v;
}

}  // namespace

LcmSchema::LcmSchema(const std::vector<std::pair<std::string, std::string>>& sources) {
  for (const auto& [file, text] : sources) {
    const size_t first = structs_.size();
    Parser(file, tokenize(file, text)).parse(&structs_);
    for (size_t k = first; k < structs_.size(); ++k) {
      linkEnums(&structs_[k]);
      structs_[k].base_hash = baseHash(structs_[k]);
    }
  }
  computeFingerprints();
}

// Fingerprints: the base hash plus those of the member structs, rotated left by one
// (lcm-gen's _computeHash; a type met again on the way in counts 0).
void LcmSchema::computeFingerprints() {
  std::function<int64_t(const LcmStruct&, std::vector<const LcmStruct*>&)> compute =
      [&](const LcmStruct& s, std::vector<const LcmStruct*>& parents) -> int64_t {
    if (std::find(parents.begin(), parents.end(), &s) != parents.end()) return 0;
    parents.push_back(&s);
    uint64_t h = static_cast<uint64_t>(s.base_hash);
    for (const LcmMember& m : s.members) {
      if (kPrimitive.count(m.type)) continue;
      const LcmStruct* inner = find(m.type);
      if (!inner) throw LcmSchemaError(s.name + "." + m.name + ": unknown type " + m.type);
      h += static_cast<uint64_t>(compute(*inner, parents));
    }
    parents.pop_back();
    return static_cast<int64_t>((h << 1) + ((h >> 63) & 1));
  };
  for (size_t k = 0; k < structs_.size(); ++k) {
    std::vector<const LcmStruct*> parents;
    structs_[k].fingerprint = compute(structs_[k], parents);
    by_fingerprint_[structs_[k].fingerprint] = k;
  }
}

const LcmSchema& LcmSchema::builtIn() {
  static const LcmSchema schema(lcmTypeSources());
  return schema;
}

const LcmStruct* LcmSchema::find(const std::string& name) const {
  const std::string bare =
      name.find('.') == std::string::npos ? name : name.substr(name.rfind('.') + 1);
  for (const LcmStruct& s : structs_) {
    if (s.name == bare) return &s;
  }
  return nullptr;
}

const LcmStruct* LcmSchema::byFingerprint(int64_t fingerprint) const {
  const auto it = by_fingerprint_.find(fingerprint);
  return it == by_fingerprint_.end() ? nullptr : &structs_[it->second];
}

const LcmStruct* LcmSchema::typeOf(const uint8_t* data, size_t size) const {
  if (size < 8) return nullptr;
  int64_t fingerprint = 0;
  for (int k = 0; k < 8; ++k) fingerprint = (fingerprint << 8) | data[k];
  return byFingerprint(fingerprint);
}

std::string lcmTypeSource(const LcmStruct& s) {
  for (const auto& [file, text] : lcmTypeSources()) {
    if (file == s.name + ".lcm") return text;
  }
  return "";
}

namespace {

void decodeStruct(const LcmSchema& schema, const LcmStruct& s, Reader& r, LcmValue* out, int depth);

LcmValue decodeOne(const LcmSchema& schema, const std::string& type, Reader& r,
                   const std::string& what, int depth) {
  LcmValue v;
  if (type == "int8_t" || type == "byte" || type == "boolean") {
    const uint64_t b = r.be(1, what);
    v.kind = type == "boolean" ? LcmValue::Kind::kBool : LcmValue::Kind::kInt;
    v.i = type == "int8_t" ? static_cast<int8_t>(b) : static_cast<int64_t>(b);
  } else if (type == "int16_t") {
    v.i = static_cast<int16_t>(r.be(2, what));
  } else if (type == "int32_t") {
    v.i = static_cast<int32_t>(r.be(4, what));
  } else if (type == "int64_t") {
    v.i = static_cast<int64_t>(r.be(8, what));
  } else if (type == "float") {
    const auto u = static_cast<uint32_t>(r.be(4, what));
    float f;
    std::memcpy(&f, &u, 4);
    v.kind = LcmValue::Kind::kDouble;
    v.d = f;
  } else if (type == "double") {
    const uint64_t u = r.be(8, what);
    std::memcpy(&v.d, &u, 8);
    v.kind = LcmValue::Kind::kDouble;
  } else if (type == "string") {
    const auto n = static_cast<int32_t>(r.be(4, what + " length"));
    if (n < 1 || static_cast<size_t>(n) > r.left()) {
      throw LcmSchemaError(what + " at byte " + std::to_string(r.at() - 4) + ": string length " +
                           std::to_string(n) + " with " + std::to_string(r.left()) + " bytes left");
    }
    const uint8_t* p = r.take(static_cast<size_t>(n), what);
    v.kind = LcmValue::Kind::kString;
    v.s.assign(reinterpret_cast<const char*>(p), static_cast<size_t>(n - 1));
  } else {
    const LcmStruct* inner = schema.find(type);
    if (!inner) throw LcmSchemaError(what + ": unknown type " + type);
    if (depth > 16) throw LcmSchemaError(what + ": structs nested too deeply");
    decodeStruct(schema, *inner, r, &v, depth + 1);
  }
  return v;
}

LcmValue decodeArray(const LcmSchema& schema, const LcmMember& m, const std::vector<int64_t>& dims,
                     size_t k, Reader& r, const std::string& what, int depth) {
  LcmValue v;
  v.kind = LcmValue::Kind::kArray;
  const int64_t n = dims[k];
  // Never reserve more than the remaining bytes could hold.
  size_t elem = minSize(schema, m.type);
  for (size_t j = k + 1; j < dims.size(); ++j)
    elem *= static_cast<size_t>(std::max<int64_t>(dims[j], 0));
  if (n < 0 || (elem > 0 && static_cast<uint64_t>(n) > r.left() / elem)) {
    throw LcmSchemaError(what + " at byte " + std::to_string(r.at()) + ": " + std::to_string(n) +
                         " elements do not fit in the " + std::to_string(r.left()) + " bytes left");
  }
  v.items.reserve(static_cast<size_t>(n));
  for (int64_t e = 0; e < n; ++e) {
    v.items.push_back(k + 1 < dims.size() ? decodeArray(schema, m, dims, k + 1, r, what, depth)
                                          : decodeOne(schema, m.type, r, what, depth));
  }
  return v;
}

void decodeStruct(const LcmSchema& schema, const LcmStruct& s, Reader& r, LcmValue* out,
                  int depth) {
  out->kind = LcmValue::Kind::kStruct;
  for (const LcmMember& m : s.members) {
    const std::string what = s.name + "." + m.name;
    if (m.dims.empty()) {
      LcmValue v = decodeOne(schema, m.type, r, what, depth);
      if (!m.enum_names.empty()) {
        const auto it = m.enum_names.find(v.i);
        v.enum_name = it == m.enum_names.end() ? "?" : it->second;
      }
      out->fields.emplace_back(m.name, std::move(v));
      continue;
    }
    std::vector<int64_t> dims;
    for (const std::string& d : m.dims) {
      if (isNumber(d)) {
        dims.push_back(std::stoll(d));
      } else {
        const auto it = std::find_if(out->fields.begin(), out->fields.end(),
                                     [&](const auto& f) { return f.first == d; });
        dims.push_back(it == out->fields.end() ? 0 : it->second.i);
      }
    }
    out->fields.emplace_back(m.name, decodeArray(schema, m, dims, 0, r, what, depth));
  }
}

}  // namespace

const LcmStruct* LcmSchema::decode(const uint8_t* data, size_t size, LcmValue* out) const {
  Reader r(data, size);
  const auto fingerprint = static_cast<int64_t>(r.be(8, "fingerprint"));
  const LcmStruct* s = byFingerprint(fingerprint);
  if (!s) return nullptr;
  *out = LcmValue{};
  decodeStruct(*this, *s, r, out, 0);
  if (r.left() != 0) {
    throw LcmSchemaError(s->name + ": " + std::to_string(r.left()) +
                         " bytes left over after byte " + std::to_string(r.at()));
  }
  return s;
}

namespace {

bool validUtf8(const uint8_t* p, size_t n) {
  for (size_t i = 0; i < n;) {
    const uint8_t c = p[i];
    size_t len = 0;
    uint32_t cp = 0;
    if (c < 0x80) {
      ++i;
      continue;
    } else if ((c & 0xE0) == 0xC0) {
      len = 2, cp = c & 0x1F;
    } else if ((c & 0xF0) == 0xE0) {
      len = 3, cp = c & 0x0F;
    } else if ((c & 0xF8) == 0xF0) {
      len = 4, cp = c & 0x07;
    } else {
      return false;
    }
    if (i + len > n) return false;
    for (size_t k = 1; k < len; ++k) {
      if ((p[i + k] & 0xC0) != 0x80) return false;
      cp = (cp << 6) | (p[i + k] & 0x3F);
    }
    // Overlong forms, surrogates and code points past U+10FFFF are not UTF-8.
    if ((len == 2 && cp < 0x80) || (len == 3 && cp < 0x800) || (len == 4 && cp < 0x10000) ||
        (cp >= 0xD800 && cp <= 0xDFFF) || cp > 0x10FFFF) {
      return false;
    }
    i += len;
  }
  return true;
}

// The walk behind LcmSchema::validate: the bytes against one struct after another, with no
// allocation unless a message fails (then the reason).
class Validator {
 public:
  // Walks data from `start` (past the fingerprint); offsets are the message's own.
  Validator(const LcmSchema& schema, const uint8_t* data, size_t size, size_t start)
      : schema_(schema), data_(data), size_(size), at_(start) {}
  size_t at() const { return at_; }
  const std::string& error() const { return error_; }

  bool structAt(const LcmStruct& s, int depth) {
    if (depth > 16) return fail(s, nullptr, "structs nested too deeply");
    int64_t ints[64];  // the struct's integer members so far (array sizes), by member index
    if (s.members.size() > 64) return fail(s, nullptr, "more than 64 members");
    for (size_t k = 0; k < s.members.size(); ++k) {
      const LcmMember& m = s.members[k];
      uint64_t count = 1;
      for (const std::string& d : m.dims) {
        const int64_t n = isNumber(d) ? std::stoll(d) : dimValue(s, ints, k, d);
        if (n < 0) return fail(s, &m, "negative count " + std::to_string(n));
        const uint64_t unit = std::max<size_t>(minSize(schema_, m.type), 1) * count;
        if (count > 0 && static_cast<uint64_t>(n) > (size_ - at_) / unit) {
          return fail(s, &m,
                      std::to_string(n) + " elements do not fit in the " +
                          std::to_string(size_ - at_) + " bytes left");
        }
        count *= static_cast<uint64_t>(n);
      }
      ints[k] = 0;
      for (uint64_t e = 0; e < count; ++e) {
        if (!element(s, m, depth, m.dims.empty() ? &ints[k] : nullptr)) return false;
      }
    }
    return true;
  }

 private:
  static int64_t dimValue(const LcmStruct& s, const int64_t* ints, size_t k,
                          const std::string& name) {
    for (size_t j = 0; j < k; ++j) {
      if (s.members[j].name == name) return ints[j];
    }
    return 0;
  }

  bool fail(const LcmStruct& s, const LcmMember* m, const std::string& why) {
    if (error_.empty()) {
      error_ = s.name + (m ? "." + m->name : std::string()) + " at byte " + std::to_string(at_) +
               ": " + why;
    }
    return false;
  }

  const uint8_t* take(size_t n) {
    if (n > size_ - at_) return nullptr;
    const uint8_t* p = data_ + at_;
    at_ += n;
    return p;
  }

  static uint64_t be(const uint8_t* p, size_t n) {
    uint64_t v = 0;
    for (size_t k = 0; k < n; ++k) v = (v << 8) | p[k];
    return v;
  }

  bool number(const LcmStruct& s, const LcmMember& m, size_t n, int64_t* value) {
    const uint8_t* p = take(n);
    if (!p) return fail(s, &m, "needs " + std::to_string(n) + " bytes");
    const uint64_t u = be(p, n);
    const bool nan_allowed = m.comment.find("NaN") != std::string::npos;
    if (m.type == "float" || m.type == "double") {
      double d;
      if (n == 4) {
        float f;
        const auto u32 = static_cast<uint32_t>(u);
        std::memcpy(&f, &u32, 4);
        d = f;
      } else {
        std::memcpy(&d, &u, 8);
      }
      if (!std::isfinite(d) && !(nan_allowed && std::isnan(d))) {
        return fail(s, &m, "not a finite number");
      }
      return true;
    }
    int64_t v = static_cast<int64_t>(u);
    if (n == 1 && m.type == "int8_t") v = static_cast<int8_t>(u);
    if (n == 2) v = static_cast<int16_t>(u);
    if (n == 4) v = static_cast<int32_t>(u);
    if (m.type == "boolean" && u > 1) return fail(s, &m, "boolean " + std::to_string(u));
    if (!m.enum_names.empty() && !m.enum_names.count(v)) {
      return fail(s, &m, "value " + std::to_string(v) + " is none of its constants");
    }
    if (value) *value = v;
    return true;
  }

  bool string(const LcmStruct& s, const LcmMember& m) {
    const size_t start = at_;  // a bad length is reported where the length is
    const uint8_t* p = take(4);
    if (!p) return fail(s, &m, "needs a string length");
    const auto n = static_cast<int32_t>(be(p, 4));
    if (n < 1 || static_cast<size_t>(n) > size_ - at_) {
      const std::string why = "string length " + std::to_string(n) + " with " +
                              std::to_string(size_ - at_) + " bytes left";
      at_ = start;
      return fail(s, &m, why);
    }
    if (static_cast<size_t>(n) > LcmSchema::kMaxStringBytes) {
      return fail(s, &m,
                  "string of " + std::to_string(n) + " bytes (at most " +
                      std::to_string(LcmSchema::kMaxStringBytes) + ")");
    }
    const uint8_t* text = take(static_cast<size_t>(n));
    if (text[n - 1] != 0) return fail(s, &m, "string not NUL-terminated");
    if (std::memchr(text, 0, static_cast<size_t>(n - 1))) return fail(s, &m, "NUL inside a string");
    if (!validUtf8(text, static_cast<size_t>(n - 1))) return fail(s, &m, "string not UTF-8");
    return true;
  }

  bool element(const LcmStruct& s, const LcmMember& m, int depth, int64_t* value) {
    const std::string& t = m.type;
    if (t == "int8_t" || t == "byte" || t == "boolean") return number(s, m, 1, value);
    if (t == "int16_t") return number(s, m, 2, value);
    if (t == "int32_t" || t == "float") return number(s, m, 4, value);
    if (t == "int64_t" || t == "double") return number(s, m, 8, value);
    if (t == "string") return string(s, m);
    const LcmStruct* inner = schema_.find(t);
    if (!inner) return fail(s, &m, "unknown type " + t);
    return structAt(*inner, depth + 1) || fail(s, &m, "in " + t);
  }

  const LcmSchema& schema_;
  const uint8_t* data_;
  size_t size_;
  size_t at_;
  std::string error_;
};

}  // namespace

std::string LcmSchema::validate(const uint8_t* data, size_t size) const {
  if (size < 8) return "shorter than a type fingerprint (" + std::to_string(size) + " bytes)";
  int64_t fingerprint = 0;
  for (int k = 0; k < 8; ++k) fingerprint = (fingerprint << 8) | data[k];
  const LcmStruct* s = byFingerprint(fingerprint);
  if (!s) {
    char hex[32];
    std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(fingerprint));
    return std::string("unknown type (fingerprint ") + hex + ")";
  }
  Validator v(*this, data, size, 8);
  if (!v.structAt(*s, 0)) return v.error();
  if (v.at() != size) {
    return s->name + ": " + std::to_string(size - v.at()) + " bytes left over after byte " +
           std::to_string(v.at());
  }
  return {};
}

}  // namespace sweepmap
