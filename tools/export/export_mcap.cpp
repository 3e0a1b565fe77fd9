#include "tools/export/export_mcap.hpp"

#include <memory>

#include "core/event_log.hpp"
#include "core/lcm_schema.hpp"
#include "viz/foxglove_messages.hpp"
#include "viz/mcap_writer.hpp"

namespace sweepmap {

namespace {

// Several logs read as one, in time order (ties: the earlier log first), skipping corrupt
// bytes as LCM's reader does.
class MergedLogs {
 public:
  explicit MergedLogs(const std::vector<std::string>& paths) {
    for (const auto& p : paths) {
      readers_.push_back(std::make_unique<EventLogReader>(p));
      readers_.back()->setResync(true);
      heads_.emplace_back();
      has_.push_back(readers_.back()->next(&heads_.back()));
    }
  }
  bool next(LogEvent* event) {
    int best = -1;
    for (size_t i = 0; i < readers_.size(); ++i) {
      if (has_[i] && (best < 0 || heads_[i].utime < heads_[best].utime)) best = i;
    }
    if (best < 0) return false;
    *event = std::move(heads_[best]);
    has_[best] = readers_[best]->next(&heads_[best]);
    return true;
  }
  std::string skipped() const {
    std::string out;
    for (const auto& r : readers_) {
      const std::string s = describeSkipped(r->path(), r->skipped());
      if (!s.empty()) out += (out.empty() ? "" : "; ") + s;
    }
    return out;
  }

 private:
  std::vector<std::unique_ptr<EventLogReader>> readers_;
  std::vector<LogEvent> heads_;
  std::vector<bool> has_;
};

// The MCAP schemas and channels, made as their first message comes.
class Channels {
 public:
  explicit Channels(viz::McapWriter* w) : w_(w) {}

  // A raw LCM channel: its type found by the message's fingerprint (schema id 0: unknown type).
  uint16_t raw(const std::string& channel, const std::vector<uint8_t>& data) {
    const auto it = raw_.find(channel);
    if (it != raw_.end()) return it->second;
    uint16_t schema = 0;
    if (const LcmStruct* s = LcmSchema::builtIn().typeOf(data.data(), data.size())) {
      schema = lcmSchema(*s);
    }
    return raw_[channel] = w_->addChannel(schema, channel, "lcm");
  }
  uint16_t foxglove(const std::string& topic, const std::string& schema_name) {
    const auto it = foxglove_.find(topic);
    if (it != foxglove_.end()) return it->second;
    uint16_t& schema = schemas_[schema_name];
    if (schema == 0) {
      const viz::FoxgloveSchema* s = viz::foxgloveSchema(schema_name);
      schema = w_->addSchema(s->name, s->encoding, s->data);
    }
    return foxglove_[topic] = w_->addChannel(schema, topic, "json");
  }

 private:
  uint16_t lcmSchema(const LcmStruct& s) {
    const std::string name = s.package + "." + s.name;
    uint16_t& id = schemas_[name];
    if (id != 0) return id;
    const std::string text = lcmTypeSource(s);
    if (!text.empty()) id = w_->addSchema(name, "lcm", text);
    return id;
  }

  viz::McapWriter* w_;
  std::map<std::string, uint16_t> raw_, foxglove_, schemas_;
};

void writeFoxglove(const std::vector<viz::FoxgloveMessage>& messages, Channels* channels,
                   viz::McapWriter* w, ExportMcapResult* r) {
  for (const auto& m : messages) {
    const uint16_t id = channels->foxglove(m.topic, m.schema_name);
    w->write(id, m.log_time_ns, m.log_time_ns, m.json.data(), m.json.size());
    ++r->topics[m.topic];
  }
}

}  // namespace

ExportMcapResult exportMcap(const Rig& rig, const ExportMcapOptions& options) {
  MergedLogs logs(options.logs);
  viz::McapWriterOptions wo;
  wo.zstd = options.zstd;
  viz::McapWriter writer(options.out, wo);
  Channels channels(&writer);
  viz::FoxgloveConverter converter(rig);
  ExportMcapResult r;
  LogEvent e;
  int64_t last_ns = 0;
  while (logs.next(&e)) {
    ++r.events;
    const int64_t t_ns = std::max<int64_t>(e.utime, 0) * 1000;
    last_ns = std::max(last_ns, t_ns);
    if (options.raw) {
      writer.write(channels.raw(e.channel, e.data), t_ns, t_ns, e.data.data(), e.data.size());
      ++r.topics[e.channel];
    }
    writeFoxglove(converter.convert(e.channel, e.data.data(), e.data.size(), t_ns), &channels,
                  &writer, &r);
  }
  writeFoxglove(converter.finish(last_ns), &channels, &writer, &r);
  r.error = logs.skipped();
  r.log_error = !r.error.empty();
  r.rejected = converter.rejected();
  r.messages = static_cast<int64_t>(writer.messageCount());
  writer.close();
  r.bytes = writer.bytesWritten();
  return r;
}

}  // namespace sweepmap
