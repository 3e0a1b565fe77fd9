// What every decoder fuzz target checks: the input split in two at a position taken from
// its first byte, fed to a fresh decoder, then the end of the input (finish(), where the
// decoder has it); afterwards the counters must be consistent with
// the bytes fed and every error offset must lie inside them. abort() on a violation, so
// libFuzzer (and the corpus replay) report it.
#pragma once

#include <cstdint>
#include <cstdlib>
#include <type_traits>
#include <utility>
#include <vector>

#include "drivers/protocols/decoder.hpp"

namespace sweepmap {

// Whether the decoder has finish() (the end of the input: held bytes searched again).
template <class Decoder, class Event, class = void>
struct HasFinish : std::false_type {};
template <class Decoder, class Event>
struct HasFinish<
    Decoder, Event,
    std::void_t<decltype(std::declval<Decoder&>().finish(std::declval<std::vector<Event>*>()))>>
    : std::true_type {};

template <class Decoder, class Event>
void fuzzDecoder(const uint8_t* data, size_t size) {
  if (size == 0) return;
  const size_t cut = 1 + data[0] % size;
  Decoder d;
  std::vector<Event> out;
  d.feed(data + 1, cut - 1, &out);
  d.feed(data + cut, size - cut, &out);
  if constexpr (HasFinish<Decoder, Event>::value) d.finish(&out);
  const DecoderCounters& c = d.counters();
  const auto fed = static_cast<int64_t>(size - 1);
  if (c.bytes != fed || c.discarded_bytes < 0 || c.discarded_bytes > fed || c.scans > c.packets ||
      c.checksum_errors < 0 || c.resyncs < 0) {
    std::abort();
  }
  for (const Event& e : out) {
    if (const auto* err = std::get_if<DecodeError>(&e)) {
      if (err->offset < 0 || err->offset > fed || err->what.empty()) std::abort();
    }
  }
}

}  // namespace sweepmap
