// The one generic codec of the lcm-gen message types, for any `T`: encodeMessage() through
// T::getEncodedSize/encode, decodeMessage() through T::decode, accepting exactly one whole
// valid message. Part of convert.hpp's API (kept in this small header so that node.hpp's
// Outbox can use it without the library structs).
//
// lcm-gen's decoders size arrays and strings from the counts in the message before checking
// that the bytes are there: a few malformed bytes could ask for gigabytes, or overflow. So
// every message is first validated against its type's schema (core/lcm_schema.hpp: every
// count and length against the bytes present, finite numbers, enums, UTF-8), which covers
// every type from its .lcm file: a new type cannot be forgotten.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/lcm_schema.hpp"

namespace sweepmap {

template <class T>
std::vector<uint8_t> encodeMessage(const T& msg) {
  std::vector<uint8_t> data(static_cast<size_t>(msg.getEncodedSize()));
  msg.encode(data.data(), 0, static_cast<int>(data.size()));
  return data;
}

// False when the bytes are not exactly one valid message of T (short, trailing bytes, over
// 64 MiB, or invalid for LcmSchema::validate); the caller reports it, naming the channel.
template <class T>
bool decodeMessage(const uint8_t* data, size_t size, T* out) {
  if (size > (1u << 26) || !LcmSchema::builtIn().validate(data, size).empty()) return false;
  const int n = out->decode(data, 0, static_cast<int>(size));
  return n == static_cast<int>(size);
}

}  // namespace sweepmap
