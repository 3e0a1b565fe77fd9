#include "mapping/las_io.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <ctime>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

#include "core/atomic_file.hpp"

namespace sweepmap {
namespace {

constexpr size_t kHeaderSize = 375;  // LAS 1.4 public header block
constexpr size_t kRecordSize = 30;   // point data record format 6

template <class T>
void put(std::string* out, size_t at, T v) {
  static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "LAS is little-endian");
  std::memcpy(&(*out)[at], &v, sizeof v);
}

void putText(std::string* out, size_t at, size_t size, const std::string& text) {
  std::memcpy(&(*out)[at], text.data(), std::min(size, text.size()));  // rest stays NUL
}

LasSummary bounds(const std::string& path, const std::vector<LasPoint>& points) {
  LasSummary s;
  s.points = points.size();
  for (size_t i = 0; i < points.size(); ++i) {
    const double v[3] = {points[i].x, points[i].y, points[i].z};
    for (int k = 0; k < 3; ++k) {
      if (!std::isfinite(v[k])) {
        throw std::runtime_error(path + ": point " + std::to_string(i) + " is not finite");
      }
      s.min[k] = i == 0 ? v[k] : std::min(s.min[k], v[k]);
      s.max[k] = i == 0 ? v[k] : std::max(s.max[k], v[k]);
    }
  }
  // Offsets: the middle of the bounds, to the metre, so the int32 counts reach +-214 km.
  for (int k = 0; k < 3; ++k) s.offset[k] = std::round(0.5 * (s.min[k] + s.max[k]));
  return s;
}

void writeHeader(std::string* out, const LasSummary& s, const LasOptions& o) {
  putText(out, 0, 4, "LASF");
  put<uint16_t>(out, 6, (1u << 0) | (1u << 4));  // adjusted standard GPS time; WKT (R15: 6-10)
  put<uint8_t>(out, 24, 1);                      // version 1.4
  put<uint8_t>(out, 25, 4);
  putText(out, 26, 32, "OTHER");
  putText(out, 58, 32, o.software);
  if (o.creation_unix_s > 0) {
    const std::time_t t = static_cast<std::time_t>(o.creation_unix_s);
    std::tm tm{};
    gmtime_r(&t, &tm);
    put<uint16_t>(out, 90, static_cast<uint16_t>(tm.tm_yday + 1));
    put<uint16_t>(out, 92, static_cast<uint16_t>(tm.tm_year + 1900));
  }
  put<uint16_t>(out, 94, kHeaderSize);
  put<uint32_t>(out, 96, kHeaderSize);  // offset to point data: no VLRs
  put<uint32_t>(out, 100, 0);
  put<uint8_t>(out, 104, 6);
  put<uint16_t>(out, 105, kRecordSize);
  // 107: legacy point count and 111: legacy counts by return stay 0 (format 6).
  for (int k = 0; k < 3; ++k) {
    put<double>(out, 131 + 8 * k, o.scale_m);
    put<double>(out, 155 + 8 * k, s.offset[k]);
    put<double>(out, 179 + 16 * k, s.max[k]);
    put<double>(out, 187 + 16 * k, s.min[k]);
  }
  // 227: waveform data start, 235: first EVLR, 243: EVLR count: all 0.
  put<uint64_t>(out, 247, s.points);
  put<uint64_t>(out, 255, s.points);  // every point is return 1 of 1
}

int32_t scaled(const std::string& path, double v, double offset, double scale) {
  const double counts = std::round((v - offset) / scale);
  if (counts < INT32_MIN || counts > INT32_MAX) {
    throw std::runtime_error(path + ": a coordinate is beyond the int32 range at scale " +
                             std::to_string(scale) + " m");
  }
  return static_cast<int32_t>(counts);
}

}  // namespace

double adjustedGpsTime(double unix_s) { return unix_s - 315964800.0 + 18.0 - 1e9; }

LasSummary writeLas14(const std::string& path, const std::vector<LasPoint>& points,
                      const LasOptions& options) {
  LasSummary s = bounds(path, points);
  std::string bytes(kHeaderSize + points.size() * kRecordSize, '\0');
  writeHeader(&bytes, s, options);
  for (size_t i = 0; i < points.size(); ++i) {
    const LasPoint& p = points[i];
    const size_t at = kHeaderSize + i * kRecordSize;
    put<int32_t>(&bytes, at + 0, scaled(path, p.x, s.offset[0], options.scale_m));
    put<int32_t>(&bytes, at + 4, scaled(path, p.y, s.offset[1], options.scale_m));
    put<int32_t>(&bytes, at + 8, scaled(path, p.z, s.offset[2], options.scale_m));
    put<uint16_t>(&bytes, at + 12, p.intensity);
    put<uint8_t>(&bytes, at + 14, 0x11);  // return 1 of 1
    // 15: flags, 16: classification 0 (never classified), 17: user data, 18: scan angle,
    // 20: point source id: 0.
    put<double>(&bytes, at + 22, p.gps_time);
  }
  writeFileAtomic(path, bytes);
  s.bytes = bytes.size();
  return s;
}

namespace {

struct PlyProperty {
  std::string name, type;
  size_t offset = 0, size = 0;
};

size_t plyTypeSize(const std::string& t) {
  static const std::map<std::string, size_t> sizes = {
      {"char", 1},  {"uchar", 1},   {"int8", 1},   {"uint8", 1},  {"short", 2}, {"ushort", 2},
      {"int16", 2}, {"uint16", 2},  {"int", 4},    {"uint", 4},   {"int32", 4}, {"uint32", 4},
      {"float", 4}, {"float32", 4}, {"double", 8}, {"float64", 8}};
  const auto it = sizes.find(t);
  return it == sizes.end() ? 0 : it->second;
}

double plyValue(const uint8_t* p, const std::string& t) {
  auto get = [p](auto v) {
    std::memcpy(&v, p, sizeof v);
    return static_cast<double>(v);
  };
  if (t == "float" || t == "float32") return get(float{});
  if (t == "double" || t == "float64") return get(double{});
  if (t == "uchar" || t == "uint8") return get(uint8_t{});
  if (t == "char" || t == "int8") return get(int8_t{});
  if (t == "ushort" || t == "uint16") return get(uint16_t{});
  if (t == "short" || t == "int16") return get(int16_t{});
  if (t == "uint" || t == "uint32") return get(uint32_t{});
  return get(int32_t{});
}

// The vertex element's properties and count from the header; throws for what is not read.
std::vector<PlyProperty> readPlyHeader(const std::string& path, std::istream& in, uint64_t* count,
                                       size_t* stride) {
  std::string line;
  std::vector<PlyProperty> props;
  bool in_vertex = false, first_element = true, binary_le = false;
  if (!std::getline(in, line) || line != "ply") throw std::runtime_error(path + ": not a PLY file");
  while (std::getline(in, line) && line != "end_header") {
    std::istringstream words(line);
    std::string key, a, b;
    words >> key >> a >> b;
    if (key == "format") binary_le = a == "binary_little_endian";
    if (key == "element") {
      if (!first_element && a == "vertex") throw std::runtime_error(path + ": vertex not first");
      in_vertex = a == "vertex" && first_element;
      if (in_vertex) *count = std::stoull(b);
      first_element = false;
    }
    if (key == "property" && in_vertex) {
      if (a == "list") throw std::runtime_error(path + ": list property in the vertex element");
      const size_t size = plyTypeSize(a);
      if (size == 0) throw std::runtime_error(path + ": unknown PLY type '" + a + "'");
      props.push_back({b, a, *stride, size});
      *stride += size;
    }
  }
  if (line != "end_header") throw std::runtime_error(path + ": PLY header without end_header");
  if (!binary_le) throw std::runtime_error(path + ": only binary_little_endian PLY is read");
  return props;
}

const PlyProperty* findProperty(const std::vector<PlyProperty>& props,
                                std::initializer_list<const char*> names) {
  for (const char* n : names) {
    for (const auto& p : props) {
      if (p.name == n) return &p;
    }
  }
  return nullptr;
}

}  // namespace

uint16_t lasIntensity(double device_units) {
  if (!(device_units > 0.0)) return 0;  // also NaN
  return static_cast<uint16_t>(std::lround(std::min(device_units, 65535.0)));
}

std::vector<LasPoint> readPlyVertices(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open");
  uint64_t count = 0;
  size_t stride = 0;
  const auto props = readPlyHeader(path, in, &count, &stride);
  const PlyProperty* xyz[3] = {findProperty(props, {"x"}), findProperty(props, {"y"}),
                               findProperty(props, {"z"})};
  if (!xyz[0] || !xyz[1] || !xyz[2]) throw std::runtime_error(path + ": no x, y, z properties");
  const PlyProperty* intensity = findProperty(props, {"intensity", "scalar_intensity"});
  const PlyProperty* time = findProperty(props, {"gps_time", "scalar_gps_time"});
  std::vector<LasPoint> points;
  std::vector<uint8_t> record(stride);
  for (uint64_t i = 0; i < count; ++i) {
    if (!in.read(reinterpret_cast<char*>(record.data()), static_cast<std::streamsize>(stride))) {
      throw std::runtime_error(path + ": vertex " + std::to_string(i) + " of " +
                               std::to_string(count) + " is cut short");
    }
    LasPoint p;
    p.x = plyValue(&record[xyz[0]->offset], xyz[0]->type);
    p.y = plyValue(&record[xyz[1]->offset], xyz[1]->type);
    p.z = plyValue(&record[xyz[2]->offset], xyz[2]->type);
    if (intensity) {
      p.intensity = lasIntensity(plyValue(&record[intensity->offset], intensity->type));
    }
    if (time) p.gps_time = plyValue(&record[time->offset], time->type);
    points.push_back(p);
  }
  return points;
}

}  // namespace sweepmap
