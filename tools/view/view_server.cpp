#include "tools/view/view_server.hpp"

#define ASIO_STANDALONE
#define _WEBSOCKETPP_CPP11_STL_
#include <atomic>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <sstream>
#include <websocketpp/config/asio_no_tls.hpp>
#include <websocketpp/server.hpp>

namespace sweepmap {
namespace {

namespace fs = std::filesystem;
using Server = websocketpp::server<websocketpp::config::asio>;
using Handle = websocketpp::connection_hdl;

constexpr const char* kFoxgloveSubprotocol = "foxglove.websocket.v1";
constexpr size_t kMaxIncomingMessage = 64 * 1024;
constexpr int kSocketSendBuffer = 256 * 1024;

std::string contentType(const fs::path& p) {
  static const std::map<std::string, std::string> types = {
      {".html", "text/html; charset=utf-8"},
      {".js", "text/javascript; charset=utf-8"},
      {".css", "text/css; charset=utf-8"},
      {".json", "application/json"},
      {".png", "image/png"},
      {".svg", "image/svg+xml"}};
  const auto it = types.find(p.extension().string());
  return it == types.end() ? "application/octet-stream" : it->second;
}

// The file a GET names inside `root`, or "" when it names none (a path that leaves the
// folder, a character outside [A-Za-z0-9._/-], a file that is not there).
std::string fileUnder(const fs::path& root, const std::string& rel) {
  static const std::regex safe("[A-Za-z0-9_][A-Za-z0-9._/-]*");
  if (!std::regex_match(rel, safe) || rel.find("..") != std::string::npos ||
      rel.find("//") != std::string::npos) {
    return "";
  }
  std::error_code ec;
  const fs::path p = fs::weakly_canonical(root / rel, ec);
  const fs::path r = fs::weakly_canonical(root, ec);
  if (ec || p.string().rfind(r.string() + "/", 0) != 0 || !fs::is_regular_file(p, ec)) return "";
  return p.string();
}

std::string readAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string messageData(uint32_t subscription, uint64_t log_time_ns, const std::string& payload) {
  std::string out(13, '\0');
  out[0] = 0x01;  // messageData
  for (int i = 0; i < 4; ++i) out[1 + i] = static_cast<char>((subscription >> (8 * i)) & 0xff);
  for (int i = 0; i < 8; ++i) out[5 + i] = static_cast<char>((log_time_ns >> (8 * i)) & 0xff);
  return out + payload;
}

// The protocol's advertise message for `channels`.
ViewFrame advertise(const std::vector<FoxgloveChannel>& channels) {
  nlohmann::json list = nlohmann::json::array();
  for (const FoxgloveChannel& c : channels) {
    list.push_back({{"id", c.id},
                    {"topic", c.topic},
                    {"encoding", c.encoding},
                    {"schemaName", c.schema_name},
                    {"schema", c.schema},
                    {"schemaEncoding", c.schema_encoding}});
  }
  ViewFrame f;  // kControl: never dropped
  f.data = std::make_shared<const std::string>(
      nlohmann::json({{"op", "advertise"}, {"channels", list}}).dump());
  return f;
}

}  // namespace

struct ViewServer::Impl {
  struct Session {
    bool foxglove = false;
    std::unique_ptr<ClientQueue> queue;
    std::map<uint32_t, uint32_t> subscriptions;  // Foxglove: subscription id -> channel id
  };

  ViewServerOptions options;
  Callbacks callbacks;
  Server server;
  std::unique_ptr<asio::steady_timer> timer;
  mutable std::mutex mutex;  // sessions, channels, counters
  std::map<Handle, Session, std::owner_less<Handle>> sessions;
  std::vector<FoxgloveChannel> channels;
  ViewServerCounters counters;
  std::atomic<bool> pump_scheduled{false};
  int ticks = 0;

  void serveHttp(Handle h);
  bool validate(Handle h);
  void open(Handle h);
  void close(Handle h);
  void message(Handle h, Server::message_ptr m);
  void foxgloveCommand(Handle h, const std::string& text);
  void schedulePump();
  void pumpAll();
  void pump(Handle h, Session& s);
  void tick();
  void resyncVoxels();
  std::string statusFrame(const std::string& board, const ClientCounters& you) const;
};

void ViewServer::Impl::serveHttp(Handle h) {
  auto con = server.get_con_from_hdl(h);
  const std::string method = con->get_request().get_method();
  std::string path = con->get_resource();
  path = path.substr(0, path.find_first_of("?#"));
  std::string file;
  if (method == "GET" || method == "HEAD") {
    if (path == "/") path = "/index.html";
    file = path.rfind("/three/", 0) == 0 ? fileUnder(options.three_dir, path.substr(7))
                                         : fileUnder(options.web_dir, path.substr(1));
  }
  {
    std::lock_guard<std::mutex> lock(mutex);
    ++counters.http_requests;
    counters.http_refused += file.empty();
  }
  con->append_header("X-Content-Type-Options", "nosniff");
  con->append_header("Cache-Control", "no-cache");
  if (file.empty()) {
    con->set_status(method == "GET" || method == "HEAD"
                        ? websocketpp::http::status_code::not_found
                        : websocketpp::http::status_code::method_not_allowed);
    con->set_body("not found\n");
    return;
  }
  con->append_header("Content-Type", contentType(file));
  con->append_header("Content-Security-Policy",
                     "default-src 'self'; img-src 'self' data:; connect-src 'self'; "
                     "style-src 'self' 'unsafe-inline'");
  con->set_status(websocketpp::http::status_code::ok);
  con->set_body(readAll(file));
}

// /ws: the view's protocol; /: the Foxglove protocol, when the client asks for it.
bool ViewServer::Impl::validate(Handle h) {
  auto con = server.get_con_from_hdl(h);
  const std::string path = con->get_resource();
  if (path == "/ws" || path.rfind("/ws?", 0) == 0) return true;
  for (const std::string& p : con->get_requested_subprotocols()) {
    if (p == kFoxgloveSubprotocol && (path == "/" || path.rfind("/?", 0) == 0)) {
      con->select_subprotocol(p);
      return true;
    }
  }
  return false;
}

void ViewServer::Impl::open(Handle h) {
  auto con = server.get_con_from_hdl(h);
  const bool foxglove = con->get_subprotocol() == kFoxgloveSubprotocol;
  if (foxglove) {
    std::lock_guard<std::mutex> lock(mutex);
    Session& s = sessions[h];
    s.foxglove = true;
    s.queue = std::make_unique<ClientQueue>(options.queue_bytes);
    ++counters.connections;
    ViewFrame info;
    info.data = std::make_shared<const std::string>(
        nlohmann::json({{"op", "serverInfo"},
                        {"name", "sweepmap view"},
                        {"capabilities", nlohmann::json::array()},
                        {"supportedEncodings", nlohmann::json::array()},
                        {"metadata", nlohmann::json::object()},
                        {"sessionId", std::to_string(counters.connections)}})
            .dump());
    s.queue->push(info);
    s.queue->push(advertise(channels));
  } else {
    callbacks.on_view_open([&](const std::vector<ViewFrame>& frames) {
      std::lock_guard<std::mutex> lock(mutex);
      Session& s = sessions[h];
      s.queue = std::make_unique<ClientQueue>(options.queue_bytes);
      for (const ViewFrame& f : frames) s.queue->push(f);
      ++counters.connections;
    });
  }
  schedulePump();
}

void ViewServer::Impl::close(Handle h) {
  std::lock_guard<std::mutex> lock(mutex);
  sessions.erase(h);
}

void ViewServer::Impl::message(Handle h, Server::message_ptr m) {
  bool foxglove = false;
  {
    std::lock_guard<std::mutex> lock(mutex);
    const auto it = sessions.find(h);
    if (it == sessions.end()) return;
    foxglove = it->second.foxglove;
  }
  if (m->get_opcode() != websocketpp::frame::opcode::text) {
    std::lock_guard<std::mutex> lock(mutex);
    ++counters.commands_refused;
    return;
  }
  if (foxglove) {
    foxgloveCommand(h, m->get_payload());
  } else if (callbacks.on_view_command) {
    callbacks.on_view_command(m->get_payload());
  }
}

// subscribe / unsubscribe; anything else (publishing, parameters, services) is refused: the
// server advertises no capability that would let a client change anything.
void ViewServer::Impl::foxgloveCommand(Handle h, const std::string& text) {
  const auto j = nlohmann::json::parse(text, nullptr, false);
  std::lock_guard<std::mutex> lock(mutex);
  auto it = sessions.find(h);
  if (it == sessions.end()) return;
  const std::string op = j.is_object() && j.value("op", nlohmann::json()).is_string()
                             ? j["op"].get<std::string>()
                             : "";
  if (op == "subscribe" && j.contains("subscriptions") && j["subscriptions"].is_array()) {
    for (const auto& s : j["subscriptions"]) {
      if (!s.is_object() || !s.value("id", nlohmann::json()).is_number_unsigned() ||
          !s.value("channelId", nlohmann::json()).is_number_unsigned()) {
        ++counters.commands_refused;
        continue;
      }
      it->second.subscriptions[s["id"].get<uint32_t>()] = s["channelId"].get<uint32_t>();
    }
  } else if (op == "unsubscribe" && j.contains("subscriptionIds") &&
             j["subscriptionIds"].is_array()) {
    for (const auto& id : j["subscriptionIds"]) {
      if (id.is_number_unsigned()) it->second.subscriptions.erase(id.get<uint32_t>());
    }
  } else {
    ++counters.commands_refused;
  }
}

void ViewServer::Impl::schedulePump() {
  if (pump_scheduled.exchange(true)) return;
  asio::post(server.get_io_service(), [this] {
    pump_scheduled = false;
    pumpAll();
  });
}

void ViewServer::Impl::pumpAll() {
  std::lock_guard<std::mutex> lock(mutex);
  for (auto& [h, s] : sessions) pump(h, s);
}

// Hands the connection frames while its socket holds less than the send window; a status
// frame gets this connection's counters as they are once every frame before it was handed.
void ViewServer::Impl::pump(Handle h, Session& s) {
  std::error_code ec;
  auto con = server.get_con_from_hdl(h, ec);
  if (ec || con->get_state() != websocketpp::session::state::open) return;
  const size_t window = std::min(options.send_window_bytes, options.queue_bytes / 4);
  while (con->get_buffered_amount() < window) {
    std::optional<ViewFrame> f = s.queue->pop();
    if (!f) break;
    const std::string& data = *f->data;
    const std::string text = f->key == "status" ? statusFrame(data, s.queue->counters()) : "";
    con->send(text.empty() ? data : text,
              f->binary ? websocketpp::frame::opcode::binary : websocketpp::frame::opcode::text);
  }
}

std::string ViewServer::Impl::statusFrame(const std::string& board, const ClientCounters& c) const {
  int64_t dropped_all = 0;
  for (const auto& [h, s] : sessions) dropped_all += s.queue->counters().frames_dropped;
  nlohmann::json view = {{"connections", sessions.size()},
                         {"frames_dropped_all", dropped_all},
                         {"http_requests", counters.http_requests},
                         {"http_refused", counters.http_refused},
                         {"commands_refused", counters.commands_refused}};
  nlohmann::json you = {{"frames_sent", c.frames_sent},       {"bytes_sent", c.bytes_sent},
                        {"frames_dropped", c.frames_dropped}, {"bytes_dropped", c.bytes_dropped},
                        {"points_dropped", c.points_dropped}, {"replaced", c.replaced},
                        {"points", c.points_drawn},           {"queued_bytes", c.queued_bytes},
                        {"queued_frames", c.queued_frames},   {"voxel_resyncs", c.voxel_resyncs}};
  std::string out = nlohmann::json({{"type", "status"}, {"view", view}, {"you", you}}).dump();
  out.pop_back();  // the board, already JSON, goes in as it is
  return out + ",\"board\":" + (board.empty() ? "null" : board) + "}";
}

// The pages that lost a voxel frame get the view's whole voxel set again (newest wins: a
// lost update is never replayed, the current state replaces it).
void ViewServer::Impl::resyncVoxels() {
  if (!callbacks.on_voxels_stale) return;
  {
    std::lock_guard<std::mutex> lock(mutex);
    bool any = false;
    for (const auto& [h, s] : sessions) any = any || (!s.foxglove && s.queue->voxelsStale());
    if (!any) return;
  }
  callbacks.on_voxels_stale([&](const std::vector<ViewFrame>& frames) {
    std::lock_guard<std::mutex> lock(mutex);
    for (auto& [h, s] : sessions) {
      if (s.foxglove || !s.queue->takeVoxelsStale()) continue;
      for (const ViewFrame& f : frames) s.queue->push(f);
    }
  });
}

// Every 20 ms: the connections whose sockets took what they had get more; once a second: a
// status frame for every page.
void ViewServer::Impl::tick() {
  if (++ticks % 50 == 1 && callbacks.board_json) {
    ViewFrame f;
    f.kind = ViewFrame::kLatest;
    f.key = "status";
    f.data = std::make_shared<const std::string>(callbacks.board_json());
    std::lock_guard<std::mutex> lock(mutex);
    for (auto& [h, s] : sessions) {
      if (!s.foxglove) s.queue->push(f);
    }
  }
  resyncVoxels();
  pumpAll();
  timer->expires_after(std::chrono::milliseconds(20));
  timer->async_wait([this](const std::error_code& ec) {
    if (!ec) tick();
  });
}

ViewServer::ViewServer(const ViewServerOptions& options, Callbacks callbacks)
    : impl_(std::make_unique<Impl>()) {
  Impl& i = *impl_;
  i.options = options;
  i.callbacks = std::move(callbacks);
  i.server.clear_access_channels(websocketpp::log::alevel::all);
  i.server.clear_error_channels(websocketpp::log::elevel::all);
  i.server.init_asio();
  i.server.set_reuse_addr(true);
  i.server.set_max_message_size(kMaxIncomingMessage);
  i.server.set_max_http_body_size(kMaxIncomingMessage);
  // A fixed kernel send buffer per connection: what a stalled client holds in the kernel is
  // bounded too (the queue and the send window bound the rest).
  i.server.set_socket_init_handler([](Handle, asio::ip::tcp::socket& s) {
    std::error_code ec;
    s.set_option(asio::socket_base::send_buffer_size(kSocketSendBuffer), ec);
  });
  i.server.set_http_handler([this](Handle h) { impl_->serveHttp(h); });
  i.server.set_validate_handler([this](Handle h) { return impl_->validate(h); });
  i.server.set_open_handler([this](Handle h) { impl_->open(h); });
  i.server.set_close_handler([this](Handle h) { impl_->close(h); });
  i.server.set_fail_handler([this](Handle h) { impl_->close(h); });
  i.server.set_message_handler([this](Handle h, Server::message_ptr m) { impl_->message(h, m); });
  std::error_code ec;
  const auto address = asio::ip::make_address(options.listen, ec);
  if (!ec) i.server.listen(asio::ip::tcp::endpoint(address, options.port), ec);
  if (!ec) i.server.start_accept(ec);
  if (ec) {
    throw std::runtime_error("cannot listen on " + options.listen + ":" +
                             std::to_string(options.port) + ": " + ec.message());
  }
  i.timer = std::make_unique<asio::steady_timer>(i.server.get_io_service());
}

ViewServer::~ViewServer() = default;

uint16_t ViewServer::port() const {
  std::error_code ec;
  const auto ep = impl_->server.get_local_endpoint(ec);
  return ec ? 0 : ep.port();
}

void ViewServer::run() {
  impl_->tick();
  impl_->server.run();
}

void ViewServer::stop() {
  asio::post(impl_->server.get_io_service(), [this] {
    std::error_code ec;
    impl_->timer->cancel();
    impl_->server.stop_listening(ec);
    std::lock_guard<std::mutex> lock(impl_->mutex);
    for (auto& [h, s] : impl_->sessions) {
      impl_->server.close(h, websocketpp::close::status::going_away, "server stops", ec);
    }
    impl_->server.stop();
  });
}

void ViewServer::broadcast(const ViewFrame& frame) {
  {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    for (auto& [h, s] : impl_->sessions) {
      if (!s.foxglove) s.queue->push(frame);
    }
  }
  impl_->schedulePump();
}

void ViewServer::addFoxgloveChannels(const std::vector<FoxgloveChannel>& channels) {
  {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    impl_->channels.insert(impl_->channels.end(), channels.begin(), channels.end());
    const ViewFrame adv = advertise(channels);
    for (auto& [h, s] : impl_->sessions) {
      if (s.foxglove) s.queue->push(adv);
    }
  }
  impl_->schedulePump();
}

void ViewServer::broadcastFoxglove(uint32_t channel_id, uint64_t log_time_ns,
                                   const std::string& payload) {
  {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    for (auto& [h, s] : impl_->sessions) {
      if (!s.foxglove) continue;
      for (const auto& [sub, channel] : s.subscriptions) {
        if (channel != channel_id) continue;
        ViewFrame f;
        f.kind = ViewFrame::kBulk;
        f.binary = true;
        f.data = std::make_shared<const std::string>(messageData(sub, log_time_ns, payload));
        s.queue->push(f);
      }
    }
  }
  impl_->schedulePump();
}

ViewServerCounters ViewServer::counters() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  ViewServerCounters c = impl_->counters;
  for (const auto& [h, s] : impl_->sessions) {
    const ClientCounters q = s.queue->counters();
    (s.foxglove ? c.foxglove_clients : c.view_clients) += 1;
    c.all.frames_sent += q.frames_sent;
    c.all.bytes_sent += q.bytes_sent;
    c.all.frames_dropped += q.frames_dropped;
    c.all.bytes_dropped += q.bytes_dropped;
    c.all.points_dropped += q.points_dropped;
    c.all.replaced += q.replaced;
    c.all.voxel_resyncs += q.voxel_resyncs;
    c.all.queued_bytes += q.queued_bytes;
  }
  return c;
}

}  // namespace sweepmap
