// The HTTP + WebSocket server of `sweepmap view` (Debian's websocketpp over standalone asio,
// kept out of this header). One port serves:
//  - GET of the page's files (the web folder) and of three.js (/three/..., Debian's libjs-three
//    folder); nothing else is readable, nothing is ever written;
//  - WebSocket /ws: the view's own protocol (view_model.hpp frames); what a page sends can only
//    move a log's playback (on_view_command), never the rig;
//  - WebSocket / with the subprotocol foxglove.websocket.v1: the Foxglove protocol (channels
//    advertised by addFoxgloveChannels, messages by broadcastFoxglove).
// Every connection has its own bounded queue (client_queue.hpp); the asio thread hands a
// connection at most send_window_bytes more whenever its socket has taken what it had, so a
// stalled client holds memory up to its bound and slows nothing else.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "tools/view/client_queue.hpp"

namespace sweepmap {

struct ViewServerOptions {
  std::string listen = "127.0.0.1";
  uint16_t port = 8080;  // 0: any free port (port() says which)
  std::string web_dir;   // index.html, view.js, view.css
  std::string three_dir = "/usr/share/javascript/three";
  size_t queue_bytes = 64u << 20;       // per connection
  size_t send_window_bytes = 1u << 20;  // handed to a socket ahead of what it has taken
                                        // (at most a quarter of the queue bound)
};

// A Foxglove channel as advertised (the protocol's advertise message): a converted topic
// ("json", a JSON schema) or a raw LCM channel ("lcm", the type's .lcm text).
struct FoxgloveChannel {
  uint32_t id = 0;
  std::string topic;
  std::string encoding;  // "json" or "lcm"
  std::string schema_name;
  std::string schema;
  std::string schema_encoding = "jsonschema";
};

struct ViewServerCounters {
  int64_t connections = 0;  // ever opened
  int64_t view_clients = 0;
  int64_t foxglove_clients = 0;
  int64_t http_requests = 0;
  int64_t http_refused = 0;      // not found, not GET, bad path
  int64_t commands_refused = 0;  // page messages that were not a known command
  ClientCounters all;            // summed over the connections open now
};

class ViewServer {
 public:
  struct Callbacks {
    // A page connected to /ws: call `attach` with its first frames, while holding whatever
    // lock the broadcasts hold, so the page misses no frame and gets none twice.
    std::function<void(const std::function<void(const std::vector<ViewFrame>&)>& attach)>
        on_view_open;
    // A text message from a page (already bounded in size).
    std::function<void(const std::string& text)> on_view_command;
    // The JSON of the status board, for the per-connection status frames (once a second).
    std::function<std::string()> board_json;
    // Pages lost a voxel frame (their queue was full): call `attach` with the frames that
    // replace a page's voxels (ViewModel::voxelSnapshot), holding the broadcasts' lock as
    // on_view_open does; they go to every page that lost one.
    std::function<void(const std::function<void(const std::vector<ViewFrame>&)>& attach)>
        on_voxels_stale;
  };

  // Binds; throws std::runtime_error naming the address when it cannot.
  ViewServer(const ViewServerOptions& options, Callbacks callbacks);
  ~ViewServer();
  uint16_t port() const;
  // Serves until stop() (from any thread).
  void run();
  void stop();
  // Thread-safe: a frame for every page.
  void broadcast(const ViewFrame& frame);
  // Thread-safe: more channels, advertised to the Foxglove clients connected now (and with
  // the others to every client that connects later).
  void addFoxgloveChannels(const std::vector<FoxgloveChannel>& channels);
  // Thread-safe: a message on a channel for every Foxglove client subscribed to it.
  void broadcastFoxglove(uint32_t channel_id, uint64_t log_time_ns, const std::string& payload);
  ViewServerCounters counters() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sweepmap
