#include "tools/view/view.hpp"

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <lcm/lcm-cpp.hpp>
#include <mutex>
#include <nlohmann/json.hpp>
#include <thread>

#include "core/event_log.hpp"
#include "core/exit_codes.hpp"
#include "core/lcm_schema.hpp"
#include "net/udpm_receiver.hpp"
#include "processes/live_runner.hpp"
#include "rigs/rig_file.hpp"
#include "tools/view/receive_queue.hpp"
#include "viz/foxglove_messages.hpp"

namespace sweepmap {
namespace {

namespace fs = std::filesystem;

int64_t nowUtime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// A log's messages in memory, in log order, with the event times.
struct LoadedLog {
  std::vector<Message> messages;
  int64_t start = 0, end = 0;
  std::string skipped;  // what the reader skipped, "" when nothing
};

LoadedLog loadLog(const std::string& path, double max_mb) {
  EventLogReader reader(path);
  reader.setResync(true);
  LoadedLog log;
  LogEvent e;
  size_t bytes = 0;
  while (reader.next(&e)) {
    bytes += e.data.size() + e.channel.size();
    if (bytes > max_mb * 1e6) {
      throw LogError(path, reader.offset(),
                     "more than " + std::to_string(max_mb) + " MB of messages (--max-log-mb)");
    }
    log.messages.push_back(Message{e.utime, std::move(e.channel), std::move(e.data)});
  }
  log.skipped = describeSkipped(path, reader.skipped());
  if (!log.messages.empty()) {
    log.start = log.messages.front().utime;
    log.end = log.messages.back().utime;
  }
  return log;
}

// The shared playback of a log: what pages ask (play, pause, speed, seek) and where it is.
struct Playback {
  std::mutex mutex;
  bool playing = true;
  double speed = 1.0;
  int64_t t = 0;
  std::optional<int64_t> seek;
};

constexpr size_t kReceiveQueueBytes = 512u << 20;  // live messages not yet fed to the view

class ViewApp {
 public:
  ViewApp(const ViewOptions& o, std::optional<Rig> rig) : options_(o), rig_(std::move(rig)) {}
  int run();

 private:
  void startServer();
  void startFoxglove();
  void resetModel();
  void onViewOpen(const std::function<void(const std::vector<ViewFrame>&)>& attach);
  void onCommand(const std::string& text);
  std::string boardJson();
  void add(const Message& m, int64_t now_utime);
  void feed(const Message& m, int64_t now_utime);
  void forwardRaw(const Message& m, int64_t now_utime);
  void receiveLive();
  void receiveInto(ReceiveQueue& queue);
  void playLog();
  void feedUntil(int64_t t, size_t* next);
  ViewFrame timeFrame();

  ViewOptions options_;
  std::optional<Rig> rig_;  // Foxglove's frames; none: only the raw LCM channels
  std::mutex model_mutex_;
  std::unique_ptr<viz::FoxgloveConverter> foxglove_;
  std::map<std::string, uint32_t> foxglove_ids_;  // topic -> channel id
  struct RawChannel {
    uint32_t id;
    const LcmStruct* type;
  };
  std::map<std::string, RawChannel> raw_channels_;  // LCM channel -> its Foxglove channel
  uint32_t next_channel_id_ = 1;
  int64_t raw_refused_ = 0;  // messages not forwarded raw: unknown, invalid or of another type
  int64_t last_map_utime_ = 0;
  std::unique_ptr<ViewModel> model_;
  std::unique_ptr<ViewServer> server_;
  std::atomic<bool> stop_{false};
  ReceiveQueue received_{kReceiveQueueBytes};
  LoadedLog log_;
  Playback playback_;
};

void ViewApp::onViewOpen(const std::function<void(const std::vector<ViewFrame>&)>& attach) {
  std::lock_guard<std::mutex> lock(model_mutex_);
  nlohmann::json hello = {{"type", "hello"},
                          {"mode", options_.log.empty() ? "live" : "log"},
                          {"source", options_.log.empty() ? options_.lcm_url : options_.log},
                          {"voxel_m", options_.model.voxel_m},
                          {"point_budget", options_.model.point_budget}};
  if (!options_.log.empty()) hello["log"] = {{"start", log_.start}, {"end", log_.end}};
  ViewFrame h;
  h.data = std::make_shared<const std::string>(hello.dump());
  std::vector<ViewFrame> frames = {h};
  for (ViewFrame& f : model_->snapshot()) frames.push_back(std::move(f));
  if (!options_.log.empty()) frames.push_back(timeFrame());
  attach(frames);
}

// Log playback only; everything else a page may send is refused (counted by the server).
void ViewApp::onCommand(const std::string& text) {
  const auto j = nlohmann::json::parse(text, nullptr, false);
  if (options_.log.empty() || !j.is_object() || !j.contains("type") || !j["type"].is_string()) {
    return;
  }
  const std::string type = j["type"];
  std::lock_guard<std::mutex> lock(playback_.mutex);
  if (type == "play") playback_.playing = true;
  if (type == "pause") playback_.playing = false;
  if (type == "speed" && j.value("value", nlohmann::json()).is_number()) {
    playback_.speed = std::clamp(j["value"].get<double>(), 0.05, 100.0);
  }
  if (type == "seek" && j.value("utime", nlohmann::json()).is_number_integer()) {
    playback_.seek = std::clamp(j["utime"].get<int64_t>(), log_.start, log_.end);
  }
}

std::string ViewApp::boardJson() {
  std::lock_guard<std::mutex> lock(model_mutex_);
  int64_t now = nowUtime();
  if (!options_.log.empty()) {
    std::lock_guard<std::mutex> p(playback_.mutex);
    now = playback_.t;
  }
  auto j = nlohmann::json::parse(model_->boardJson(now));
  const ViewModelCounters& c = model_->counters();
  j["view_model"] = {{"messages", c.messages},
                     {"malformed", c.malformed},
                     {"chunks", c.chunks},
                     {"points_received", c.points_received},
                     {"points_on_screen", model_->pointsOnScreen()},
                     {"voxels", model_->voxels()},
                     {"voxels_refused", c.voxels_refused},
                     {"voxel_source", model_->voxelsFromMapper() ? "mapper" : "points"},
                     {"map_updates", c.map_updates},
                     {"map_updates_invalid", c.map_updates_invalid},
                     {"map_update_gaps", c.map_update_gaps},
                     {"mapper_occupied_voxels", c.mapper_occupied_voxels},
                     {"thinned", c.thinned},
                     {"removed_sweeps", c.removed_sweeps},
                     {"receive_dropped", received_.dropped()},
                     {"raw_refused", raw_refused_},
                     {"receive_queue_peak_mb", static_cast<double>(received_.peakBytes()) / 1e6}};
  return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

void ViewApp::add(const Message& m, int64_t now_utime) {
  std::lock_guard<std::mutex> lock(model_mutex_);
  feed(m, now_utime);
}

// One message into the view and, raw and converted, to the Foxglove clients (the model's lock
// held).
void ViewApp::feed(const Message& m, int64_t now_utime) {
  model_->add(m, now_utime);
  forwardRaw(m, now_utime);
  if (!foxglove_) return;
  std::vector<viz::FoxgloveMessage> out =
      foxglove_->convert(m.channel, m.data.data(), m.data.size(), now_utime * 1000);
  // The map, when it changed, once a second (finish() gives it whatever its own schedule).
  if (now_utime - last_map_utime_ >= 1'000'000) {
    for (auto& f : foxglove_->finish(now_utime * 1000)) out.push_back(std::move(f));
    last_map_utime_ = now_utime;
  }
  for (const viz::FoxgloveMessage& f : out) {
    const auto id = foxglove_ids_.find(f.topic);
    if (id != foxglove_ids_.end()) server_->broadcastFoxglove(id->second, f.log_time_ns, f.json);
  }
}

// Every LCM channel as it is, on /lcm/CHANNEL (encoding "lcm"; the schema is its type's .lcm
// text), advertised with its first valid message. A message that is not valid for the channel's
// type (damaged, or of another type) is not forwarded: a client decodes the bytes it gets by
// the advertised schema.
void ViewApp::forwardRaw(const Message& m, int64_t now_utime) {
  const LcmSchema& schema = LcmSchema::builtIn();
  const LcmStruct* type = schema.typeOf(m.data.data(), m.data.size());
  if (!type || !schema.validate(m.data.data(), m.data.size()).empty()) {
    ++raw_refused_;
    return;
  }
  auto it = raw_channels_.find(m.channel);
  if (it == raw_channels_.end()) {
    FoxgloveChannel c;
    c.id = next_channel_id_++;
    c.topic = "/lcm/" + m.channel;
    c.encoding = "lcm";
    c.schema_name = type->package + "." + type->name;
    c.schema = lcmTypeSource(*type);
    c.schema_encoding = "lcm";
    server_->addFoxgloveChannels({c});
    it = raw_channels_.emplace(m.channel, RawChannel{c.id, type}).first;
  }
  if (it->second.type != type) {  // the channel advertised another type: not decodable by it
    ++raw_refused_;
    return;
  }
  server_->broadcastFoxglove(it->second.id, static_cast<uint64_t>(now_utime) * 1000,
                             std::string(m.data.begin(), m.data.end()));
}

// A seek back: the view and the Foxglove conversion start again (with the model's lock held).
void ViewApp::resetModel() {
  model_->reset();
  if (foxglove_) foxglove_ = std::make_unique<viz::FoxgloveConverter>(*rig_);
  last_map_utime_ = 0;
}

// The converted topics (viz/foxglove_messages.hpp), each with its published JSON schema.
void ViewApp::startFoxglove() {
  if (!rig_) {
    std::cout << "sweepmap view: no --rig: only the raw LCM channels for Foxglove (the "
                 "converted topics need the rig's frames)\n";
    return;
  }
  foxglove_ = std::make_unique<viz::FoxgloveConverter>(*rig_);
  std::vector<FoxgloveChannel> channels;
  for (const auto& [topic, schema_name] : viz::foxgloveTopics()) {
    const viz::FoxgloveSchema* schema = viz::foxgloveSchema(schema_name);
    if (!schema) continue;
    FoxgloveChannel c;
    c.id = next_channel_id_++;
    c.topic = topic;
    c.encoding = "json";
    c.schema_name = schema_name;
    c.schema = schema->data;
    c.schema_encoding = schema->encoding;
    foxglove_ids_[topic] = c.id;
    channels.push_back(c);
  }
  server_->addFoxgloveChannels(channels);
}

// The receiver only queues (tools/view/receive_queue.hpp); this thread's worker feeds the view
// each message with the time it was received.
void ViewApp::receiveLive() {
  std::atomic<bool> receiving{true};
  std::thread worker([this, &receiving] {
    Message m;
    while (receiving) {
      if (received_.pop(&m, std::chrono::milliseconds(100))) add(m, m.utime);
    }
  });
  try {
    receiveInto(received_);
  } catch (...) {
    receiving = false;
    worker.join();
    throw;
  }
  receiving = false;
  worker.join();
}

// udpm:// through sweepmap's own receiver (one malformed datagram must not end the view);
// other providers (memq://, file://) through liblcm.
void ViewApp::receiveInto(ReceiveQueue& queue) {
  const std::string url = net::effectiveLcmUrl(options_.lcm_url);
  if (net::isUdpmUrl(url)) {
    net::UdpmReceiver rx(url);
    rx.subscribe(".*", [&queue](const std::string& c, const uint8_t* d, size_t n) {
      queue.push(Message{nowUtime(), c, std::vector<uint8_t>(d, d + n)});
    });
    while (!stop_) rx.handleTimeout(100);
    return;
  }
  lcm::LCM lcm(url);
  if (!lcm.good()) throw std::runtime_error("cannot open LCM at '" + url + "'");
  lcm.subscribeFunction<ReceiveQueue*>(
      ".*",
      [](const lcm::ReceiveBuffer* rb, const std::string& c, ReceiveQueue* q) {
        const auto* p = static_cast<const uint8_t*>(rb->data);
        q->push(Message{nowUtime(), c, std::vector<uint8_t>(p, p + rb->data_size)});
      },
      &queue);
  while (!stop_) lcm.handleTimeout(100);
}

void ViewApp::feedUntil(int64_t t, size_t* next) {
  std::lock_guard<std::mutex> lock(model_mutex_);
  while (*next < log_.messages.size() && log_.messages[*next].utime <= t) {
    feed(log_.messages[*next], log_.messages[*next].utime);
    ++*next;
  }
}

ViewFrame ViewApp::timeFrame() {
  std::lock_guard<std::mutex> lock(playback_.mutex);
  ViewFrame f;
  f.kind = ViewFrame::kLatest;
  f.key = "time";
  f.data = std::make_shared<const std::string>(nlohmann::json({{"type", "time"},
                                                               {"utime", playback_.t},
                                                               {"start", log_.start},
                                                               {"end", log_.end},
                                                               {"playing", playback_.playing},
                                                               {"speed", playback_.speed}})
                                                   .dump());
  return f;
}

// Moves the shared playhead by the wall time passed times the speed (or to a seek), feeding
// the messages it passes; a seek back starts again from the log's start.
void ViewApp::playLog() {
  size_t next = 0;
  auto last = std::chrono::steady_clock::now();
  int step = 0;
  while (!stop_) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    const auto now = std::chrono::steady_clock::now();
    const double dt_s = std::chrono::duration<double>(now - last).count();
    last = now;
    int64_t target;
    bool back = false;
    {
      std::lock_guard<std::mutex> lock(playback_.mutex);
      if (playback_.seek) {
        target = *playback_.seek;
        back = target < playback_.t;
        playback_.seek.reset();
      } else {
        target = playback_.t + (playback_.playing ? int64_t(dt_s * playback_.speed * 1e6) : 0);
      }
      target = std::min(target, log_.end);
      if (target >= log_.end) playback_.playing = false;
      playback_.t = target;
    }
    if (back) {
      std::lock_guard<std::mutex> lock(model_mutex_);
      resetModel();
      next = 0;
    }
    feedUntil(target, &next);
    if (++step % 5 == 0 || back) server_->broadcast(timeFrame());
  }
}

void ViewApp::startServer() {
  ViewServer::Callbacks cb;
  cb.on_view_open = [this](const auto& attach) { onViewOpen(attach); };
  cb.on_view_command = [this](const std::string& t) { onCommand(t); };
  cb.board_json = [this] { return boardJson(); };
  cb.on_voxels_stale = [this](const auto& attach) {
    std::lock_guard<std::mutex> lock(model_mutex_);
    attach(model_->voxelSnapshot());
  };
  server_ = std::make_unique<ViewServer>(options_.server, cb);
  model_ = std::make_unique<ViewModel>(options_.model,
                                       [this](const ViewFrame& f) { server_->broadcast(f); });
  startFoxglove();
}

int ViewApp::run() {
  try {
    if (!options_.log.empty()) {
      log_ = loadLog(options_.log, options_.max_log_mb);
      playback_.t = log_.start;
      if (!log_.skipped.empty()) std::cerr << "sweepmap view: " << log_.skipped << "\n";
    }
    startServer();
  } catch (const LogError& e) {
    std::cerr << "sweepmap view: " << e.what() << "\n";
    return kExitBadInput;
  } catch (const std::exception& e) {
    std::cerr << "sweepmap view: " << e.what() << "\n";
    return kExitUsage;
  }
  std::cout << "sweepmap view: http://" << options_.server.listen << ":" << server_->port() << "/ ("
            << (options_.log.empty()
                    ? "live on " + options_.lcm_url
                    : options_.log + ", " + std::to_string(log_.messages.size()) + " messages")
            << ")" << std::endl;
  installStopSignals();
  std::thread http([this] { server_->run(); });
  int rc = kExitOk;
  std::thread source([this, &rc] {
    try {
      options_.log.empty() ? receiveLive() : playLog();
    } catch (const std::exception& e) {
      std::cerr << "sweepmap view: " << e.what() << "\n";
      rc = kExitUsage;
      stop_ = true;
    }
  });
  while (!stopRequested() && !stop_) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  stop_ = true;
  source.join();
  server_->stop();
  http.join();
  // What the view took in, for the person or script that stopped it (the pages' status frames
  // can lag behind a page's backlog).
  std::cout << "sweepmap view: stopped: " << nlohmann::json::parse(boardJson())["view_model"].dump()
            << std::endl;
  return rc;
}

}  // namespace

std::string webDir() {
  if (const char* env = std::getenv("SWEEPMAP_WEB_DIR")) return env;
  return (fs::read_symlink("/proc/self/exe").parent_path() / ".." / "share" / "sweepmap" / "web")
      .lexically_normal()
      .string();
}

int runView(const ViewOptions& options) {
  ViewOptions o = options;
  if (!o.log.empty() && !fs::exists(o.log)) {
    std::cerr << "sweepmap view: " << o.log << ": no such file\n";
    return kExitUsage;
  }
  std::optional<Rig> rig;
  if (!o.rig.empty()) {
    rig = loadRig(o.rig, o.rig_sets);  // ConfigError: exit 2 in main
    std::visit([&](const auto& c) { o.model.voxel_m = c.mapper.resolution_m; }, rig->config);
  }
  if (o.server.web_dir.empty()) o.server.web_dir = webDir();
  if (!fs::exists(fs::path(o.server.web_dir) / "index.html")) {
    std::cerr << "sweepmap view: the page's files are not in " << o.server.web_dir
              << " (SWEEPMAP_WEB_DIR)\n";
    return kExitUsage;
  }
  return ViewApp(o, std::move(rig)).run();
}

}  // namespace sweepmap
