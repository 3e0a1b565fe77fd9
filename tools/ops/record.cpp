#include "tools/ops/record.hpp"

#include <sys/statvfs.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <thread>

#include "core/event_log.hpp"
#include "core/exit_codes.hpp"
#include "net/udpm_receiver.hpp"
#include "processes/inbox.hpp"
#include "processes/live_runner.hpp"
#include "processes/node.hpp"
#include "processes/sd_notify.hpp"

namespace sweepmap {
std::string recordChannels(const std::string& preset) {
  if (preset == "all") return ".*";
  if (preset == "raw") {
    return "LIDAR_SCAN|MOTOR_STATE|MOTOR_SWITCH|SCAN_WINDOW|WHEEL_TICKS|IMU|WHEEL_CMD|PROFILE|"
           "STATUS_.*|"
           "TRUTH_.*";
  }
  throw std::invalid_argument("--preset must be raw or all, not '" + preset + "'");
}

double freeMb(const std::string& path) {
  struct statvfs s {};
  if (::statvfs(path.c_str(), &s) != 0) return -1.0;
  return static_cast<double>(s.f_bavail) * static_cast<double>(s.f_frsize) / 1e6;
}

namespace {

// The log files of one recording: NAME (replaced), or NAME.NN every split_mb, NN counting
// from the first number no file has yet, so that a restarted recorder continues the series
// (lcm-logger's -f and -i).
class RecordFiles {
 public:
  explicit RecordFiles(const RecordOptions& o)
      : base_((std::filesystem::path(o.out) / o.name).string()), split_mb_(o.split_mb) {
    open();
  }
  const std::string& path() const { return path_; }
  int64_t events() const { return events_ + (writer_ ? writer_->events() : 0); }
  // Bytes in this recording's files.
  int64_t bytes() const { return bytes_ + (writer_ ? static_cast<int64_t>(writer_->bytes()) : 0); }
  // Throws std::runtime_error when the disk refuses (the file then ends at an event).
  void write(const Message& m) {
    if (split_mb_ > 0 && static_cast<double>(writer_->bytes()) >= split_mb_ * 1e6) {
      writer_->close();
      events_ += writer_->events();
      bytes_ += static_cast<int64_t>(writer_->bytes());
      ++part_;
      open();
    }
    writer_->write(m.utime, m.channel, m.data);
  }
  void flush() { writer_->flush(); }
  void close() { writer_->close(); }

 private:
  void open() {
    for (;; ++part_) {
      char suffix[16] = "";
      if (split_mb_ > 0) std::snprintf(suffix, sizeof suffix, ".%02d", part_);
      path_ = base_ + suffix;
      if (split_mb_ <= 0 || !std::filesystem::exists(path_)) break;
    }
    writer_ = std::make_unique<EventLogWriter>(path_);
  }
  std::string base_;
  double split_mb_;
  int part_ = 0;
  int64_t events_ = 0;
  int64_t bytes_ = 0;
  std::string path_;
  std::unique_ptr<EventLogWriter> writer_;
};

// Writes `messages` unless that takes the files past --max-mb; false when it would (said once).
bool writeWithinBound(const RecordOptions& o, const std::deque<Message>& messages,
                      RecordFiles& files) {
  for (const Message& m : messages) {
    // An event costs its header (28 bytes), its channel and its data (core/event_log.hpp).
    const double after = static_cast<double>(files.bytes() + 28 + m.channel.size() + m.data.size());
    if (o.max_mb > 0 && after > o.max_mb * 1e6) {
      std::cerr << "record: stopped: the recording reached --max-mb " << o.max_mb
                << " (the log ends with its last complete event)\n";
      return false;
    }
    files.write(m);
  }
  return true;
}

// Writes what arrives until a stop, the duration or a low disk; returns the exit status.
int writeUntilStopped(const RecordOptions& o, Inbox& queue, RecordFiles& files) {
  const auto start = std::chrono::steady_clock::now();
  SdNotifier notifier;  // under systemd or `sweepmap launch`: ready now, alive from this loop
  notifier.ready();
  int status = kExitOk;
  bool full = false;  // --max-mb reached
  while (!stopRequested()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    notifier.alive();
    if (!writeWithinBound(o, queue.take(), files)) {
      full = true;
      break;
    }
    files.flush();
    const double free = freeMb(o.out);
    if (free >= 0 && free < o.min_free_mb) {
      std::cerr << "record: stopped: " << std::lround(free) << " MB free on " << o.out
                << ", below --min-free-mb " << o.min_free_mb
                << " (the log ends with its last complete event)\n";
      status = kExitDeviceIo;
      break;
    }
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (o.duration_s > 0 && elapsed >= o.duration_s) break;
  }
  notifier.stopping();
  if (status == kExitOk && !full) writeWithinBound(o, queue.take(), files);
  files.close();
  return status;
}

}  // namespace

int runRecord(const RecordOptions& o) {
  namespace fs = std::filesystem;
  std::string channels;
  try {
    channels = recordChannels(o.preset);
  } catch (const std::invalid_argument& e) {
    std::cerr << "record: " << e.what() << "\n";
    return kExitUsage;
  }
  if (!net::isUdpmUrl(o.lcm_url)) {
    std::cerr << "record: --lcm-url '" << o.lcm_url << "': record listens on udpm:// URLs\n";
    return kExitUsage;
  }
  std::error_code ec;
  fs::create_directories(o.out, ec);
  if (ec) {
    std::cerr << "record: cannot create " << o.out << ": " << ec.message() << "\n";
    return kExitDeviceIo;
  }
  const double free0 = freeMb(o.out);
  if (free0 >= 0 && free0 < o.min_free_mb) {
    std::cerr << "record: only " << std::lround(free0) << " MB free on " << o.out
              << ", below --min-free-mb " << o.min_free_mb << "; not starting\n";
    return kExitDeviceIo;
  }
  installStopSignals();
  // Messages from the receive thread to the writer (as lcm-logger's callback only enqueues and
  // its writer thread does the disk I/O).
  Inbox queue(o.queue_capacity, static_cast<size_t>(o.queue_mib * (1 << 20)));
  std::unique_ptr<net::UdpmReceiver> receiver;
  std::unique_ptr<RecordFiles> files;
  try {
    receiver = std::make_unique<net::UdpmReceiver>(
        o.lcm_url, net::securityOptions(o.lcm_url, o.allow_senders, o.key_file));
    files = std::make_unique<RecordFiles>(o);
  } catch (const std::invalid_argument& e) {
    std::cerr << "record: " << e.what() << "\n";
    return kExitUsage;
  } catch (const std::exception& e) {
    std::cerr << "record: " << e.what() << "\n";
    return kExitDeviceIo;
  }
  receiver->subscribe(channels, [&queue](const std::string& c, const uint8_t* d, size_t n) {
    queue.push(Message{wallUtime(), c, std::vector<uint8_t>(d, d + n)}, false);
  });
  std::cout << "record: " << o.preset << " channels to " << files->path()
            << (o.split_mb > 0 ? " (then .01, .02, ...)" : "") << " (stops below " << o.min_free_mb
            << " MB free)" << std::endl;
  std::atomic<bool> receiving{true};
  std::thread receive([&] {
    while (receiving) receiver->handleTimeout(50);
  });
  int status = kExitOk;
  try {
    status = writeUntilStopped(o, queue, *files);
  } catch (const std::exception& e) {
    std::cerr << "record: " << e.what() << "\n";
    status = kExitDeviceIo;
  }
  receiving = false;
  receive.join();
  const net::ReceiverCounters c = receiver->counters();
  std::cerr << "record: " << files->events() << " events; " << queue.droppedTotal()
            << " dropped (queue full), " << c.reassembly.refusedTotal() + c.truncated
            << " datagrams refused\n";
  return status;
}

}  // namespace sweepmap
