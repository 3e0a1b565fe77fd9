#include "tools/offline/dump.hpp"

#include <cmath>
#include <iomanip>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/event_log.hpp"
#include "core/exit_codes.hpp"
#include "core/lcm_schema.hpp"

namespace sweepmap {
namespace {

using Json = nlohmann::ordered_json;

// NaN and infinities have no JSON form: null.
Json toJson(const LcmValue& v) {
  switch (v.kind) {
    case LcmValue::Kind::kInt:
      return v.i;
    case LcmValue::Kind::kDouble:
      return std::isfinite(v.d) ? Json(v.d) : Json(nullptr);
    case LcmValue::Kind::kString:
      return v.s;
    case LcmValue::Kind::kBool:
      return v.i != 0;
    case LcmValue::Kind::kArray: {
      Json a = Json::array();
      for (const LcmValue& e : v.items) a.push_back(toJson(e));
      return a;
    }
    case LcmValue::Kind::kStruct: {
      Json o = Json::object();
      for (const auto& [k, f] : v.fields) o[k] = toJson(f);
      return o;
    }
  }
  return nullptr;
}

std::string scalar(const LcmValue& v) {
  std::ostringstream s;
  switch (v.kind) {
    case LcmValue::Kind::kInt:
      s << v.i;
      break;
    case LcmValue::Kind::kDouble:
      s << std::setprecision(9) << v.d;
      break;
    case LcmValue::Kind::kString:
      s << Json(v.s).dump(-1, ' ', false, Json::error_handler_t::replace);  // not UTF-8: U+FFFD
      break;
    case LcmValue::Kind::kBool:
      s << (v.i ? "true" : "false");
      break;
    default:
      s << "?";
  }
  return s.str();
}

void human(const std::string& name, const LcmValue& v, const std::string& indent, bool full,
           std::ostream& out) {
  if (v.kind == LcmValue::Kind::kStruct) {
    out << indent << name << ":\n";
    for (const auto& [k, f] : v.fields) human(k, f, indent + "  ", full, out);
    return;
  }
  if (v.kind != LcmValue::Kind::kArray) {
    out << indent << name << " = " << scalar(v);
    if (!v.enum_name.empty()) out << " (" << v.enum_name << ")";
    out << "\n";
    return;
  }
  out << indent << name << "[" << v.items.size() << "] =";
  const size_t shown = full ? v.items.size() : std::min<size_t>(v.items.size(), 8);
  for (size_t i = 0; i < shown; ++i) {
    const LcmValue& e = v.items[i];
    if (e.kind == LcmValue::Kind::kArray || e.kind == LcmValue::Kind::kStruct) {
      out << "\n";
      human(name + "[" + std::to_string(i) + "]", e, indent + "  ", full, out);
    } else {
      out << " " << scalar(e);
    }
  }
  if (shown < v.items.size()) out << " … (" << v.items.size() << " values; --full shows all)";
  out << "\n";
}

std::string hexHead(const std::vector<uint8_t>& data, size_t n) {
  std::ostringstream s;
  for (size_t i = 0; i < std::min(n, data.size()); ++i) {
    s << std::hex << std::setw(2) << std::setfill('0') << int(data[i]);
  }
  return s.str();
}

// One event, decoded when its type is known.
void printEvent(const LcmSchema& schema, const LogEvent& ev, const DumpOptions& o,
                std::ostream& out) {
  LcmValue value;
  const LcmStruct* type = nullptr;
  std::string problem;
  try {
    type = schema.decode(ev.data.data(), ev.data.size(), &value);
    if (!type) problem = "unknown type";
  } catch (const LcmSchemaError& e) {
    problem = e.what();
  }
  if (o.json) {
    Json j = Json::object();
    j["channel"] = ev.channel;
    j["log_utime"] = ev.utime;
    if (type && problem.empty()) {
      j["type"] = type->package + "." + type->name;
      for (const auto& [k, f] : value.fields) j[k] = toJson(f);
    } else {
      j["type"] = "unknown";
      j["size"] = ev.data.size();
      j["error"] = problem;
      j["head_hex"] = hexHead(ev.data, 32);
    }
    out << j.dump(-1, ' ', false, Json::error_handler_t::replace) << "\n";
    return;
  }
  out << ev.utime << " " << ev.channel;
  if (type && problem.empty()) {
    out << " (" << type->package << "." << type->name << ", " << ev.data.size() << " bytes)\n";
    for (const auto& [k, f] : value.fields) human(k, f, "  ", o.full, out);
  } else {
    out << " (" << problem << ", " << ev.data.size() << " bytes: " << hexHead(ev.data, 32)
        << (ev.data.size() > 32 ? "…" : "") << ")\n";
  }
}

// After the log: a log without a message, or a --channel it does not have, is an error that
// says what there is.
int checkWhatWasFound(const DumpOptions& o, const std::map<std::string, int64_t>& channels,
                      std::ostream& err) {
  if (channels.empty()) {
    err << "sweepmap dump: " << o.log << " holds no message\n";
    return kExitBadInput;
  }
  if (o.channel.empty() || channels.count(o.channel)) return kExitOk;
  err << "sweepmap dump: --channel " << o.channel << ": no such channel in " << o.log
      << "; its channels (messages):";
  for (const auto& [name, n] : channels) err << " " << name << " (" << n << ")";
  err << "\n";
  return kExitUsage;
}

}  // namespace

int runDump(const DumpOptions& o, std::ostream& out, std::ostream& err) {
  const LcmSchema& schema = LcmSchema::builtIn();
  EventLogReader reader(o.log);
  reader.setResync(true);
  LogEvent ev;
  int status = kExitOk;
  size_t reported = 0;                      // skipped ranges reported so far
  std::map<std::string, int64_t> channels;  // every channel of the log, with its messages
  for (;;) {
    bool more = false;
    try {
      more = reader.next(&ev);
    } catch (const LogError& e) {
      err << "sweepmap dump: " << e.what() << "\n";
      status = kExitBadInput;
      break;
    }
    for (; reported < reader.skipped().size(); ++reported) {
      const SkippedRange& r = reader.skipped()[reported];
      err << "sweepmap dump: " << o.log << ": byte " << r.begin << " to " << r.end
          << " skipped: " << r.why << "\n";
      status = kExitBadInput;
    }
    if (!more) break;
    ++channels[ev.channel];
    if (!o.channel.empty() && ev.channel != o.channel) continue;
    printEvent(schema, ev, o, out);
  }
  const int found = checkWhatWasFound(o, channels, err);
  return found != kExitOk ? found : status;
}

}  // namespace sweepmap
