#include "core/device_uri.hpp"

#include <stdexcept>

namespace sweepmap {
namespace {

int parsePositive(const std::string& uri, const std::string& what, const std::string& s, int max) {
  size_t used = 0;
  long v = 0;
  try {
    v = std::stol(s, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (s.empty() || used != s.size() || v <= 0 || v > max) {
    throw std::invalid_argument("device '" + uri + "': bad " + what + " '" + s + "'");
  }
  return static_cast<int>(v);
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
  }
  return "?";
}

DeviceUri parseDeviceUri(const std::string& text) {
  DeviceUri uri;
  uri.text = text;
  if (text == "sim") return uri;
  const size_t colon = text.find("://");
  if (colon == std::string::npos) {
    throw std::invalid_argument("device '" + text +
                                "': expected sim, scip://HOST[:PORT], ydlidar:///dev/PORT, "
                                "rplidar:///dev/PORT, hi219:///dev/PORT or "
                                "wheelboard:///dev/PORT (serial ones with [?baud=N])");
  }
  const std::string scheme = text.substr(0, colon);
  std::string rest = text.substr(colon + 3);
  std::string query;
  if (const size_t q = rest.find('?'); q != std::string::npos) {
    query = rest.substr(q + 1);
    rest = rest.substr(0, q);
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
    size_t at = 0;
    while (at < query.size()) {
      size_t amp = query.find('&', at);
      if (amp == std::string::npos) amp = query.size();
      const std::string kv = query.substr(at, amp - at);
      const size_t eq = kv.find('=');
      const std::string key = kv.substr(0, eq);
      if (key != "baud" || eq == std::string::npos) {
        throw std::invalid_argument("device '" + text + "': unknown option '" + kv +
                                    "' (known: baud=N)");
      }
      uri.baud = parsePositive(text, "baud rate", kv.substr(eq + 1), 4000000);
      at = amp + 1;
    }
    return uri;
  }
  throw std::invalid_argument("device '" + text + "': unknown scheme '" + scheme +
                              "' (sim, scip, ydlidar, rplidar, hi219, wheelboard)");
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
