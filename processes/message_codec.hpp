// The one generic codec of the lcm-gen message types, for any `T`: encodeMessage() through
// T::getEncodedSize/encode, decodeMessage() through T::decode, accepting exactly one whole
// message. Part of convert.hpp's API (kept in this small header so that node.hpp's Outbox can
// use it without the library structs); its per-type part is in convert.cpp.
//
// lcm-gen's decoders size arrays from the count in the message before checking that the
// bytes are there: a few malformed bytes could ask for gigabytes. A type with variable arrays
// therefore adds one line here, a plausibleCounts<T> declaration, and its count check in
// convert.cpp; a type without them adds nothing.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace sweepmap {

template <class T>
std::vector<uint8_t> encodeMessage(const T& msg) {
  std::vector<uint8_t> data(static_cast<size_t>(msg.getEncodedSize()));
  msg.encode(data.data(), 0, static_cast<int>(data.size()));
  return data;
}

// Whether the array counts in `size` bytes of a `T` fit in those bytes.
template <class T>
bool plausibleCounts(const uint8_t*, size_t) {
  return true;
}
class lidar_scan_t;
class cloud_chunk_t;
class profile_t;
template <>
bool plausibleCounts<lidar_scan_t>(const uint8_t* data, size_t size);
template <>
bool plausibleCounts<cloud_chunk_t>(const uint8_t* data, size_t size);
template <>
bool plausibleCounts<profile_t>(const uint8_t* data, size_t size);

// False when the bytes are not exactly one valid message (short, trailing bytes, over 64 MiB,
// or array counts beyond the bytes); the caller reports it, naming the channel.
template <class T>
bool decodeMessage(const uint8_t* data, size_t size, T* out) {
  if (size > (1u << 26) || !plausibleCounts<T>(data, size)) return false;
  const int n = out->decode(data, 0, static_cast<int>(size));
  return n == static_cast<int>(size);
}

}  // namespace sweepmap
