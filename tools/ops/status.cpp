#include "tools/ops/status.hpp"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <iomanip>
#include <iostream>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "core/angles.hpp"
#include "core/exit_codes.hpp"
#include "core/lcm_schema.hpp"
#include "net/udpm_receiver.hpp"
#include "processes/live_runner.hpp"
#include "sweepmap/map_stats_t.hpp"
#include "sweepmap/process_status_t.hpp"
#include "sweepmap/sweep_status_t.hpp"

namespace sweepmap {
namespace {

constexpr const char* kStatusPrefix = "STATUS_";

const char* healthName(int health) {
  switch (health) {
    case process_status_t::OK:
      return "OK";
    case process_status_t::DEGRADED:
      return "DEGRADED";
    case process_status_t::FAILED:
      return "FAILED";
  }
  return "?";
}

double seconds(int64_t us) { return 1e-6 * static_cast<double>(us); }

}  // namespace

StatusBoard::StatusBoard(const StatusBoardOptions& options) : options_(options) {}

void StatusBoard::add(const Message& msg, int64_t now_utime) {
  if (first_rx_ < 0) first_rx_ = now_utime;
  Channel& c = channels_[msg.channel];
  c.rx.push_back(now_utime);
  ++c.total;
  c.last_size = msg.data.size();
  const int64_t window = static_cast<int64_t>(options_.rate_window_s * 1e6);
  while (!c.rx.empty() && c.rx.front() <= now_utime - window) c.rx.pop_front();

  const bool read = msg.channel.rfind(kStatusPrefix, 0) == 0 || msg.channel == "MAP_STATS" ||
                    msg.channel == "SWEEP_STATUS";
  // Nothing from the network is decoded before its type's schema says it is whole and sane
  // (lcm-gen's decoders overflow on a string length of INT32_MIN and allocate whatever count a
  // message claims: 2^26 status counters took 2.2 GB); text must be UTF-8.
  if (read && !LcmSchema::builtIn().validate(msg.data.data(), msg.data.size()).empty()) {
    ++malformed_;
    return;
  }
  if (msg.channel.rfind(kStatusPrefix, 0) == 0) {
    addStatus(msg, now_utime);
  } else if (msg.channel == "MAP_STATS") {
    map_stats_t m;
    if (!decodeMessage(msg, &m)) {
      ++malformed_;
      return;
    }
    map_ = Map{m.sweeps_inserted, m.points_inserted,   m.occupied_voxels, m.free_voxels,
               m.memory_bytes,    m.incomplete_sweeps, m.resolution_m};
  } else if (msg.channel == "SWEEP_STATUS") {
    sweep_status_t m;
    if (!decodeMessage(msg, &m)) {
      ++malformed_;
      return;
    }
    sweep_ = Sweep{m.sweep_id, m.corrected != 0, m.phi_offset_rad * kRadToDeg, m.reason};
  }
}

// One node's status: the node is the channel's suffix, the process the message names (a
// status of an older build names none: the node is its own process).
void StatusBoard::addStatus(const Message& msg, int64_t now_utime) {
  process_status_t s;
  if (!decodeMessage(msg, &s)) {
    ++malformed_;
    return;
  }
  std::string node = msg.channel.substr(std::string(kStatusPrefix).size());
  std::transform(node.begin(), node.end(), node.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  NodeStatus& n = processes_[s.process.empty() ? node : s.process].nodes[node];
  n.last_rx = now_utime;
  n.health = s.health;
  n.detail = s.detail;
  n.counters.clear();
  for (int i = 0; i < s.ncounters; ++i)
    n.counters.emplace_back(s.counter_names[i], s.counter_values[i]);
}

bool StatusBoard::stale(int64_t last_rx, int64_t now) const {
  return seconds(now - last_rx) > options_.stale_s;
}

std::string StatusBoard::nodeState(const NodeStatus& n, int64_t now) const {
  return stale(n.last_rx, now) ? "STALE" : healthName(n.health);
}

StatusBoard::Row StatusBoard::row(const std::string& name, const Process& p, int64_t now) const {
  int64_t newest = 0;
  for (const auto& [node, n] : p.nodes) newest = std::max(newest, n.last_rx);
  Row r;
  r.age_s = seconds(now - newest);
  if (stale(newest, now)) {
    r.state = "STALE";
    const auto own = p.nodes.find(name);
    r.detail = (own != p.nodes.end() ? own : p.nodes.begin())->second.detail;
    return r;
  }
  // The worst of the live nodes; on a tie the node named after the process, else the first.
  const NodeStatus* worst = nullptr;
  for (const auto& [node, n] : p.nodes) {
    if (stale(n.last_rx, now)) continue;
    if (!worst || n.health > worst->health || (n.health == worst->health && node == name)) {
      worst = &n;
    }
  }
  r.state = healthName(worst->health);
  r.detail = worst->detail;
  return r;
}

double StatusBoard::rateHz(const Channel& c, int64_t now) const {
  // Over the window, or over the time listened when that is shorter.
  const double span = std::min(options_.rate_window_s, seconds(now - first_rx_));
  size_t n = 0;
  for (const int64_t t : c.rx) n += t > now - static_cast<int64_t>(options_.rate_window_s * 1e6);
  return span > 0.0 ? static_cast<double>(n) / span : 0.0;
}

int StatusBoard::unhealthy(int64_t now_utime) const {
  int n = 0;
  for (const auto& [name, p] : processes_) {
    const std::string state = row(name, p, now_utime).state;
    n += state == "STALE" || state == "FAILED";
  }
  return n;
}

namespace {

// `counters` as name=value items, wrapped at 100 columns, each line indented by `indent`.
void countersText(std::ostream& o, const std::vector<std::pair<std::string, int64_t>>& counters,
                  const std::string& indent) {
  std::string line = indent;
  for (const auto& [k, v] : counters) {
    const std::string item = k + "=" + std::to_string(v) + "  ";
    if (line.size() + item.size() > 100 && line.size() > indent.size()) {
      o << line << "\n";
      line = indent;
    }
    line += item;
  }
  if (line.size() > indent.size()) o << line << "\n";
}

std::string ageText(double age_s) {
  std::ostringstream age;
  age << std::fixed << std::setprecision(1) << age_s << " s";
  return age.str();
}

}  // namespace

// One row per process; beneath it its nodes (a process of one node named after it: just the
// counters).
void StatusBoard::processesText(std::ostream& o, int64_t now) const {
  o << std::left << std::setw(20) << "PROCESS" << std::setw(10) << "STATUS" << std::setw(9) << "AGE"
    << "DETAIL\n";
  for (const auto& [name, p] : processes_) {
    const Row r = row(name, p, now);
    o << std::setw(20) << name << std::setw(10) << r.state << std::setw(9) << ageText(r.age_s)
      << r.detail << "\n";
    if (p.nodes.size() == 1 && p.nodes.begin()->first == name) {
      countersText(o, p.nodes.begin()->second.counters, "    ");
      continue;
    }
    for (const auto& [node, n] : p.nodes) {
      o << "    node " << node << " " << nodeState(n, now) << ", "
        << ageText(seconds(now - n.last_rx)) << (n.detail.empty() ? "" : ": " + n.detail) << "\n";
      countersText(o, n.counters, "      ");
    }
  }
}

void StatusBoard::channelsText(std::ostream& o, int64_t now) const {
  o << std::setw(28) << "CHANNEL" << std::right << std::setw(10) << "RATE Hz" << std::setw(12)
    << "MESSAGES" << std::setw(12) << "LAST BYTES" << std::left << "\n";
  for (const auto& [name, c] : channels_) {
    o << std::setw(28) << name << std::right << std::setw(10) << std::setprecision(1)
      << rateHz(c, now) << std::setw(12) << c.total << std::setw(12) << c.last_size << std::left
      << "\n";
  }
}

std::string StatusBoard::text(int64_t now) const {
  std::ostringstream o;
  o << std::fixed;
  o << "sweepmap status: " << processes_.size() << " processes, " << channels_.size()
    << " channels, listening for " << std::setprecision(1)
    << (first_rx_ < 0 ? 0.0 : seconds(now - first_rx_)) << " s\n\n";
  processesText(o, now);
  o << "\n";
  channelsText(o, now);
  if (map_) {
    o << "\nmapper: " << map_->sweeps << " sweeps, " << map_->points << " points, "
      << map_->occupied << " occupied / " << map_->free << " free voxels at "
      << std::setprecision(2) << map_->resolution_m << " m, " << std::setprecision(1)
      << static_cast<double>(map_->memory_bytes) / (1 << 20) << " MiB, " << map_->incomplete
      << " incomplete sweeps\n";
  }
  if (sweep_) {
    o << "last sweep: #" << sweep_->id << " "
      << (sweep_->corrected ? "corrected" : "not corrected (" + sweep_->reason + ")")
      << ", phi_offset " << std::setprecision(3) << sweep_->phi_offset_deg << " deg\n";
  }
  if (malformed_ > 0) o << "\n" << malformed_ << " malformed status messages ignored\n";
  if (datagrams_refused_ > 0) {
    o << datagrams_refused_ << " datagrams refused by this monitor's receive path\n";
  }
  if (processes_.empty()) o << "\nno STATUS_* message seen: is anything running on this URL?\n";
  return o.str();
}

std::string StatusBoard::json(int64_t now) const {
  nlohmann::json j;
  j["listened_s"] = first_rx_ < 0 ? 0.0 : seconds(now - first_rx_);
  j["processes"] = nlohmann::json::object();
  for (const auto& [name, p] : processes_) {
    const Row r = row(name, p, now);
    nlohmann::json nodes = nlohmann::json::object();
    for (const auto& [node, n] : p.nodes) {
      nlohmann::json c = nlohmann::json::object();
      for (const auto& [k, v] : n.counters) c[k] = v;
      nodes[node] = {{"status", nodeState(n, now)},
                     {"age_s", seconds(now - n.last_rx)},
                     {"detail", n.detail},
                     {"counters", c}};
    }
    j["processes"][name] = {
        {"status", r.state}, {"age_s", r.age_s}, {"detail", r.detail}, {"nodes", nodes}};
  }
  j["channels"] = nlohmann::json::object();
  for (const auto& [name, c] : channels_) {
    j["channels"][name] = {
        {"rate_hz", rateHz(c, now)}, {"messages", c.total}, {"last_bytes", c.last_size}};
  }
  if (map_) {
    j["mapper"] = {{"sweeps", map_->sweeps},
                   {"points", map_->points},
                   {"occupied_voxels", map_->occupied},
                   {"free_voxels", map_->free},
                   {"resolution_m", map_->resolution_m},
                   {"memory_bytes", map_->memory_bytes},
                   {"incomplete_sweeps", map_->incomplete}};
  }
  if (sweep_) {
    j["last_sweep"] = {{"id", sweep_->id},
                       {"corrected", sweep_->corrected},
                       {"phi_offset_deg", sweep_->phi_offset_deg},
                       {"reason", sweep_->reason}};
  }
  j["malformed"] = malformed_;
  j["datagrams_refused"] = datagrams_refused_;
  j["unhealthy"] = unhealthy(now);
  // A detail of bytes that are not UTF-8 (the network is not trusted) is escaped, not fatal.
  return j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
}

namespace {

int64_t nowUtime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

class Listener {
 public:
  explicit Listener(StatusBoard* board) : board_(board) {}
  void onMessage(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    const auto* p = static_cast<const uint8_t*>(rbuf->data);
    board_->add(Message{rbuf->recv_utime, channel, std::vector<uint8_t>(p, p + rbuf->data_size)},
                nowUtime());
  }

 private:
  StatusBoard* board_;
};

// --once's exit status: a health check fails while nothing runs, or while a process is
// stale or FAILED (DEGRADED still runs: 0).
int onceStatus(const StatusBoard& board, int64_t now, const StatusOptions& o) {
  if (board.processes() == 0) {
    std::cerr << "sweepmap status: no process seen on " << o.lcm_url << " in " << o.window_s
              << " s\n";
    return kExitBadInput;
  }
  if (const int n = board.unhealthy(now); n > 0) {
    std::cerr << "sweepmap status: " << n << " of " << board.processes()
              << " processes stale or FAILED\n";
    return kExitBadInput;
  }
  return kExitOk;
}

// The bus to listen on: an udpm:// URL through sweepmap's validating receive path (a monitor
// that one malformed datagram kills is no monitor), any other provider through liblcm.
class StatusSource {
 public:
  explicit StatusSource(const StatusOptions& o, StatusBoard* board) : board_(board) {
    const std::string& url = o.lcm_url;
    if (net::isUdpmUrl(url)) {
      udpm_ = std::make_unique<net::UdpmReceiver>(
          url, net::securityOptions(url, o.allow_senders, o.key_file));
      udpm_->subscribe(".*", [this](const std::string& c, const uint8_t* d, size_t n) {
        board_->add(Message{nowUtime(), c, std::vector<uint8_t>(d, d + n)}, nowUtime());
      });
      return;
    }
    lcm_ = std::make_unique<lcm::LCM>(url);
    if (!lcm_->good()) throw std::runtime_error("cannot open LCM at '" + url + "'");
    listener_ = std::make_unique<Listener>(board);
    lcm_->subscribe(".*", &Listener::onMessage, listener_.get());
  }
  void wait(int ms) {
    if (udpm_) {
      udpm_->handleTimeout(ms);
      const net::ReceiverCounters& c = udpm_->counters();
      board_->setDatagramsRefused(static_cast<int64_t>(c.reassembly.refusedTotal() + c.truncated +
                                                       c.not_allowed + c.not_signed));
    } else {
      lcm_->handleTimeout(ms);
    }
  }

 private:
  StatusBoard* board_;
  std::unique_ptr<net::UdpmReceiver> udpm_;
  std::unique_ptr<lcm::LCM> lcm_;
  std::unique_ptr<Listener> listener_;
};

}  // namespace

int runStatus(const StatusOptions& o) {
  StatusBoard board(o.board);
  std::unique_ptr<StatusSource> source;
  try {
    source = std::make_unique<StatusSource>(o, &board);
  } catch (const std::exception& e) {
    std::cerr << "sweepmap status: " << e.what() << "\n";
    return kExitUsage;
  }
  installStopSignals();
  const int64_t start = nowUtime();
  int64_t next_draw = start + 1'000'000;
  while (!stopRequested()) {
    source->wait(100);
    const int64_t now = nowUtime();
    if (o.once) {
      if (seconds(now - start) < o.window_s) continue;
      std::cout << (o.json ? board.json(now) : board.text(now)) << std::flush;
      return onceStatus(board, now, o);
    }
    if (now >= next_draw) {
      std::cout << "\033[H\033[2J" << board.text(now) << std::flush;
      next_draw += 1'000'000;
    }
  }
  return kExitOk;
}

}  // namespace sweepmap
