#include "core/device_uri.hpp"

#include <cctype>
#include <iterator>
#include <stdexcept>
#include <utility>

namespace sweepmap {
namespace {

int parseInRange(const std::string& uri, const std::string& what, const std::string& s, int min,
                 int max) {
  size_t used = 0;
  long v = 0;
  try {
    v = std::stol(s, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (s.empty() || !std::isdigit(static_cast<unsigned char>(s[0])) || used != s.size() || v < min ||
      v > max) {
    throw std::invalid_argument("device '" + uri + "': bad " + what + " '" + s + "' (" +
                                std::to_string(min) + ".." + std::to_string(max) + ")");
  }
  return static_cast<int>(v);
}

int parsePositive(const std::string& uri, const std::string& what, const std::string& s, int max) {
  return parseInRange(uri, what, s, 1, max);
}

// Calls on_option(key, value, kv) for each `key=value` of `query`; a pair without '=' is
// passed with an empty value and has_value false.
template <class F>
void forEachOption(const std::string& query, F on_option) {
  size_t at = 0;
  while (at < query.size()) {
    size_t amp = query.find('&', at);
    if (amp == std::string::npos) amp = query.size();
    const std::string kv = query.substr(at, amp - at);
    const size_t eq = kv.find('=');
    on_option(kv.substr(0, eq), eq == std::string::npos ? std::string() : kv.substr(eq + 1),
              eq != std::string::npos, kv);
    at = amp + 1;
  }
}

// One of two words for a boolean option (`first` -> true).
bool parseChoice(const std::string& uri, const std::string& key, const std::string& value,
                 const char* first, const char* second) {
  if (value == first) return true;
  if (value == second) return false;
  throw std::invalid_argument("device '" + uri + "': option " + key + "='" + value + "' must be " +
                              first + " or " + second);
}

void parseGpiod(const std::string& text, const std::string& rest, const std::string& query,
                DeviceUri& uri) {
  GpioLines& g = uri.gpio;
  g.chip = rest;
  if (!g.chip.empty() && g.chip.front() != '/' && g.chip.back() == '/') g.chip.pop_back();
  if (g.chip.empty()) {
    throw std::invalid_argument("device '" + text +
                                "': expected gpiod://CHIP?step=N&dir=N&enable=N&home=N "
                                "(CHIP: gpiochip0, a number, a label or /dev/gpiochipN)");
  }
  const std::pair<const char*, int*> lines[] = {
      {"step", &g.step}, {"dir", &g.dir}, {"enable", &g.enable}, {"home", &g.home}};
  forEachOption(query, [&](const std::string& key, const std::string& value, bool has_value,
                           const std::string& kv) {
    for (const auto& [name, offset] : lines) {
      if (key != name || !has_value) continue;
      *offset =
          parseInRange(text, std::string("line offset ") + name, value, 0, kGpioMaxLineOffset);
      return;
    }
    if (key == "enable_active" && has_value) {
      g.enable_active_low = parseChoice(text, key, value, "low", "high");
    } else if (key == "dir_positive" && has_value) {
      g.dir_positive_high = parseChoice(text, key, value, "high", "low");
    } else if (key == "home_blocked" && has_value) {
      g.home_blocked_high = parseChoice(text, key, value, "high", "low");
    } else if (key == "home_pull" && has_value) {
      if (value == "up") {
        g.home_pull = GpioPull::kUp;
      } else if (value == "down") {
        g.home_pull = GpioPull::kDown;
      } else if (value == "none") {
        g.home_pull = GpioPull::kNone;
      } else {
        throw std::invalid_argument("device '" + text + "': option home_pull='" + value +
                                    "' must be up, down or none");
      }
    } else {
      throw std::invalid_argument("device '" + text + "': unknown option '" + kv +
                                  "' (known: step, dir, enable, home, enable_active, "
                                  "dir_positive, home_blocked, home_pull)");
    }
  });
  for (size_t i = 0; i < std::size(lines); ++i) {
    if (*lines[i].second < 0) {
      throw std::invalid_argument("device '" + text + "': missing line " + lines[i].first +
                                  "=N (step, dir, enable and home are required)");
    }
    for (size_t j = 0; j < i; ++j) {
      if (*lines[i].second == *lines[j].second) {
        throw std::invalid_argument("device '" + text + "': lines " + lines[j].first + " and " +
                                    lines[i].first + " are both " +
                                    std::to_string(*lines[i].second));
      }
    }
  }
}

}  // namespace

const char* protocolName(DeviceProtocol protocol) {
  switch (protocol) {
    case DeviceProtocol::kSim:
      return "sim";
    case DeviceProtocol::kScip:
      return "scip";
    case DeviceProtocol::kYdlidarX4:
      return "ydlidar";
    case DeviceProtocol::kRplidar:
      return "rplidar";
    case DeviceProtocol::kHi219:
      return "hi219";
    case DeviceProtocol::kWheelBoard:
      return "wheelboard";
    case DeviceProtocol::kGpiod:
      return "gpiod";
  }
  return "?";
}

// A serial device's options: baud=N.
static void parseBaudOption(const std::string& text, const std::string& query, DeviceUri* uri) {
  forEachOption(query, [&](const std::string& key, const std::string& value, bool has_value,
                           const std::string& kv) {
    if (key != "baud" || !has_value) {
      throw std::invalid_argument("device '" + text + "': unknown option '" + kv +
                                  "' (known: baud=N)");
    }
    uri->baud = parsePositive(text, "baud rate", value, 4000000);
  });
}

DeviceUri parseDeviceUri(const std::string& text) {
  DeviceUri uri;
  uri.text = text;
  if (text == "sim") return uri;
  const size_t colon = text.find("://");
  if (colon == std::string::npos) {
    throw std::invalid_argument("device '" + text +
                                "': expected sim, scip://HOST[:PORT], ydlidar:///dev/PORT, "
                                "rplidar:///dev/PORT, hi219:///dev/PORT, "
                                "wheelboard:///dev/PORT (serial ones with [?baud=N]) or "
                                "gpiod://CHIP?step=N&dir=N&enable=N&home=N");
  }
  const std::string scheme = text.substr(0, colon);
  std::string rest = text.substr(colon + 3);
  std::string query;
  if (const size_t q = rest.find('?'); q != std::string::npos) {
    query = rest.substr(q + 1);
    rest = rest.substr(0, q);
  }
  if (scheme == "scip" && !rest.empty() && rest.front() == '/') {
    // A Hokuyo on a serial line or its USB port (URG-04LX: /dev/ttyACM0): the same SCIP lines.
    uri.protocol = DeviceProtocol::kScip;
    uri.path = rest;
    uri.baud = 19200;  // the URG-04LX's factory rate (its USB port ignores it)
    parseBaudOption(text, query, &uri);
    return uri;
  }
  if (scheme == "scip") {
    uri.protocol = DeviceProtocol::kScip;
    if (!query.empty()) throw std::invalid_argument("device '" + text + "': scip takes no options");
    if (!rest.empty() && rest.back() == '/') rest.pop_back();
    uri.port = kScipDefaultPort;
    std::string host = rest;
    if (!rest.empty() && rest.front() == '[') {  // [IPv6]:port
      const size_t close = rest.find(']');
      if (close == std::string::npos)
        throw std::invalid_argument("device '" + text + "': bad host");
      host = rest.substr(1, close - 1);
      if (close + 1 < rest.size()) {
        if (rest[close + 1] != ':') throw std::invalid_argument("device '" + text + "': bad host");
        uri.port = parsePositive(text, "port", rest.substr(close + 2), 65535);
      }
    } else if (const size_t c = rest.rfind(':'); c != std::string::npos) {
      host = rest.substr(0, c);
      uri.port = parsePositive(text, "port", rest.substr(c + 1), 65535);
    }
    if (host.empty()) throw std::invalid_argument("device '" + text + "': no host");
    uri.host = host;
    return uri;
  }
  if (scheme == "ydlidar" || scheme == "rplidar" || scheme == "hi219" || scheme == "wheelboard") {
    if (scheme == "ydlidar") {
      uri.protocol = DeviceProtocol::kYdlidarX4;
      uri.baud = kX4DefaultBaud;
    } else if (scheme == "rplidar") {
      uri.protocol = DeviceProtocol::kRplidar;
      uri.baud = kRplidarDefaultBaud;
    } else if (scheme == "hi219") {
      uri.protocol = DeviceProtocol::kHi219;
      uri.baud = kHi219DefaultBaud;
    } else {
      uri.protocol = DeviceProtocol::kWheelBoard;
      uri.baud = kWheelBoardDefaultBaud;
    }
    if (rest.empty() || rest.front() != '/') {
      throw std::invalid_argument("device '" + text + "': expected " + scheme +
                                  ":///dev/PORT (an absolute path)");
    }
    uri.path = rest;
    parseBaudOption(text, query, &uri);
    return uri;
  }
  if (scheme == "gpiod") {
    uri.protocol = DeviceProtocol::kGpiod;
    parseGpiod(text, rest, query, uri);
    return uri;
  }
  throw std::invalid_argument("device '" + text + "': unknown scheme '" + scheme +
                              "' (sim, scip, ydlidar, rplidar, hi219, wheelboard, gpiod)");
}

DeviceUri parseDeviceUriFor(const std::string& text, const std::vector<DeviceProtocol>& allowed) {
  DeviceUri uri = parseDeviceUri(text);
  if (uri.protocol == DeviceProtocol::kSim) return uri;
  std::string names = "sim";
  for (DeviceProtocol p : allowed) {
    if (p == uri.protocol) return uri;
    names += std::string(", ") + protocolName(p);
  }
  throw std::invalid_argument("device '" + text + "': a " + protocolName(uri.protocol) +
                              " device does not belong here (this key takes " + names + ")");
}

}  // namespace sweepmap
