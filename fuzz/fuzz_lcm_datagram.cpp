// libFuzzer target: sweepmap's LCM datagram receive path (net/lcm_datagram.hpp) on arbitrary
// datagram sequences. The input is cut into datagrams by 2-byte length prefixes; each takes its
// sender from one byte and its arrival time from the sequence, so fragments of several
// senders interleave, repeat and expire. Checked after every datagram: memory held stays
// within the limits, and every message handed out is valid (channel, size). abort() on a
// violation, so libFuzzer (and the corpus replay) report it.
#include <cstdlib>

#include "net/lcm_datagram.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace sweepmap::net;
  ReassemblyLimits limits;
  limits.max_message_bytes = 1 << 20;
  limits.max_pending_bytes_per_sender = 1 << 18;
  limits.max_pending_bytes = 1 << 19;
  limits.max_senders = 4;
  limits.fragment_timeout_us = 50;
  LcmReassembler r(limits);
  size_t at = 0;
  int64_t now = 0;
  while (at + 3 <= size) {
    const size_t n = std::min<size_t>((data[at] << 8 | data[at + 1]) % 4096, size - at - 3);
    const SenderId sender{data[at + 2] & 7u, 1};
    const auto m = r.feed(data + at + 3, n, sender, now);
    at += 3 + n;
    now += 7;
    if (r.pendingBytes() > limits.max_pending_bytes) std::abort();
    if (!m) continue;
    if (m->channel.empty() || m->channel.size() > kLcmMaxChannelLength) std::abort();
    if (m->data.size() > std::max<size_t>(limits.max_message_bytes, kLcmShortMessageMaxBytes)) {
      std::abort();
    }
  }
  if (r.counters().messages + r.counters().refusedTotal() > 2 * r.counters().datagrams) {
    std::abort();
  }
  return 0;
}
