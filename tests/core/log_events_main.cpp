// What sweepmap's event log reader (core/event_log.hpp) finds in a log, one line each, for
// tests/python/test_log_readers_agree.py to hold python/sweepmap_log.py to the same results:
//   event OFFSET EVENTNUM UTIME CHANNEL DATA_BYTES FNV1A64(data, hex)
//   skipped BEGIN END
// Reads with resync (as replay and dump do). Test-only; exit 0, or 2 when it cannot open the log.
#include <cinttypes>
#include <cstdio>

#include "core/event_log.hpp"

namespace {

uint64_t fnv1a64(const std::vector<uint8_t>& data) {
  uint64_t h = 0xcbf29ce484222325ull;
  for (uint8_t b : data) h = (h ^ b) * 0x100000001b3ull;
  return h;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: log_events LOG\n");
    return 2;
  }
  try {
    sweepmap::EventLogReader reader(argv[1]);
    reader.setResync(true);
    sweepmap::LogEvent e;
    while (reader.next(&e)) {
      const uint64_t offset = reader.offset() - 28 - e.channel.size() - e.data.size();
      std::printf("event %" PRIu64 " %" PRId64 " %" PRId64 " %s %zu %016" PRIx64 "\n", offset,
                  e.eventnum, e.utime, e.channel.c_str(), e.data.size(), fnv1a64(e.data));
    }
    for (const sweepmap::SkippedRange& r : reader.skipped()) {
      std::printf("skipped %" PRIu64 " %" PRIu64 "\n", r.begin, r.end);
    }
  } catch (const sweepmap::LogError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  }
  return 0;
}
