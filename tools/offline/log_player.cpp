#include "tools/offline/log_player.hpp"

#include <algorithm>

#include "core/event_log.hpp"

namespace sweepmap {

LogPlayer::LogPlayer(const std::string& path) : reader_(std::make_unique<EventLogReader>(path)) {
  reader_->setResync(true);
}

LogPlayer::~LogPlayer() = default;

void LogPlayer::addInputs(const std::set<std::string>& channels) {
  inputs_.insert(channels.begin(), channels.end());
}

void LogPlayer::handle(const std::string& channel, Handler handler) {
  handlers_[channel] = std::move(handler);
}

void LogPlayer::setProgress(std::function<void(uint64_t, uint64_t)> progress) {
  progress_ = std::move(progress);
}

LogPlayResult LogPlayer::play() {
  LogPlayResult result;
  LogEvent ev;
  try {
    while (reader_->next(&ev)) {
      ++result.events;
      if (result.events == 1) result.first_utime = ev.utime;
      result.last_utime = ev.utime;
      now_ = std::max(now_, ev.utime);
      if (progress_) progress_(reader_->offset(), reader_->size());
      Message m{ev.utime, ev.channel, std::move(ev.data)};
      if (inputs_.count(m.channel)) {
        bus_.tick(now_);
        bus_.deliver(m);
      } else if (const auto h = handlers_.find(m.channel); h != handlers_.end()) {
        h->second(m);
      } else {
        ++result.skipped_channels[m.channel];
      }
    }
  } catch (const LogError& e) {  // an I/O error: what was read is kept
    result.log_error = true;
    result.error = e.what();
  }
  result.skipped_ranges = reader_->skipped();
  if (!result.skipped_ranges.empty()) {
    const std::string skipped = describeSkipped(reader_->path(), result.skipped_ranges);
    result.error = result.error.empty() ? skipped : result.error + "; " + skipped;
    result.log_error = true;
  }
  result.now_utime = now_;
  return result;
}

void LogPlayer::finish() { bus_.finish(now_); }

}  // namespace sweepmap
