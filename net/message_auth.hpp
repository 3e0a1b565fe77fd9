// Signed LCM messages: a shared key (a file readable only by the service user) lets every
// process sign what it publishes and drop what is unsigned or wrongly signed.
//
// The signature travels after the message's own bytes, as a trailer:
//   payload | "SWA1" | HMAC-SHA-256(key, channel | NUL | payload | "SWA1")  (32 bytes)
// LCM's decoders (lcm-gen's C, C++, Java and Python) read the fields they know and ignore
// what follows, so lcm-spy, lcm-logger and Python readers still decode signed messages. The
// MAC is libsodium's crypto_auth_hmacsha256.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace sweepmap::net {

constexpr size_t kAuthKeyBytes = 32;
constexpr size_t kAuthTrailerBytes = 4 + 32;

class MessageAuth {
 public:
  // Reads a key file: exactly 32 bytes, or 64 hex digits (and an optional newline). Refuses a
  // file that its group or others may read or write (chmod 600). Throws std::invalid_argument
  // naming the file and what is wrong, and how to make one.
  static MessageAuth fromKeyFile(const std::string& path);
  explicit MessageAuth(const std::array<uint8_t, kAuthKeyBytes>& key);

  // `data` with the trailer appended.
  std::vector<uint8_t> sign(const std::string& channel, const uint8_t* data, size_t size) const;
  // The size of the payload without its trailer when the trailer is there and the MAC holds
  // (compared in constant time); nothing otherwise.
  std::optional<size_t> verify(const std::string& channel, const uint8_t* data, size_t size) const;

 private:
  std::array<uint8_t, 32> mac(const std::string& channel, const uint8_t* data, size_t size) const;
  std::array<uint8_t, kAuthKeyBytes> key_;
};

}  // namespace sweepmap::net
