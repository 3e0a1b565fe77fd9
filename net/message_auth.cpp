#include "net/message_auth.hpp"

#include <sodium.h>
#include <sys/stat.h>

#include <cctype>
#include <cstring>
#include <fstream>
#include <iterator>
#include <stdexcept>

namespace sweepmap::net {
namespace {

constexpr char kTrailerMagic[4] = {'S', 'W', 'A', '1'};

std::invalid_argument keyError(const std::string& path, const std::string& what) {
  return std::invalid_argument(
      "key file " + path + ": " + what +
      " (make one with: head -c 32 /dev/urandom > FILE && chmod 600 FILE)");
}

std::array<uint8_t, kAuthKeyBytes> parseKey(const std::string& path, std::string text) {
  std::array<uint8_t, kAuthKeyBytes> key{};
  if (text.size() == kAuthKeyBytes) {
    std::memcpy(key.data(), text.data(), kAuthKeyBytes);
    return key;
  }
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back()))) text.pop_back();
  size_t bin_len = 0;
  if (text.size() == 2 * kAuthKeyBytes &&
      sodium_hex2bin(key.data(), key.size(), text.data(), text.size(), nullptr, &bin_len,
                     nullptr) == 0 &&
      bin_len == kAuthKeyBytes) {
    return key;
  }
  throw keyError(
      path, "holds " + std::to_string(text.size()) + " bytes; a key is 32 bytes or 64 hex digits");
}

}  // namespace

MessageAuth MessageAuth::fromKeyFile(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) throw keyError(path, std::strerror(errno));
  if (!S_ISREG(st.st_mode)) throw keyError(path, "is not a regular file");
  if (st.st_mode & (S_IRWXG | S_IRWXO)) {
    throw keyError(path, "may be read or written by others than its owner (chmod 600 it)");
  }
  std::ifstream in(path, std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (!in.good() && !in.eof()) throw keyError(path, "cannot be read");
  return MessageAuth(parseKey(path, text));
}

MessageAuth::MessageAuth(const std::array<uint8_t, kAuthKeyBytes>& key) : key_(key) {
  if (sodium_init() < 0) throw std::runtime_error("libsodium failed to initialise");
}

std::array<uint8_t, 32> MessageAuth::mac(const std::string& channel, const uint8_t* data,
                                         size_t size) const {
  crypto_auth_hmacsha256_state state;
  crypto_auth_hmacsha256_init(&state, key_.data(), key_.size());
  const uint8_t nul = 0;
  crypto_auth_hmacsha256_update(&state, reinterpret_cast<const uint8_t*>(channel.data()),
                                channel.size());
  crypto_auth_hmacsha256_update(&state, &nul, 1);
  crypto_auth_hmacsha256_update(&state, data, size);
  crypto_auth_hmacsha256_update(&state, reinterpret_cast<const uint8_t*>(kTrailerMagic), 4);
  std::array<uint8_t, 32> tag{};
  crypto_auth_hmacsha256_final(&state, tag.data());
  return tag;
}

std::vector<uint8_t> MessageAuth::sign(const std::string& channel, const uint8_t* data,
                                       size_t size) const {
  std::vector<uint8_t> out;
  out.reserve(size + kAuthTrailerBytes);
  out.insert(out.end(), data, data + size);
  out.insert(out.end(), kTrailerMagic, kTrailerMagic + 4);
  const std::array<uint8_t, 32> tag = mac(channel, data, size);
  out.insert(out.end(), tag.begin(), tag.end());
  return out;
}

std::optional<size_t> MessageAuth::verify(const std::string& channel, const uint8_t* data,
                                          size_t size) const {
  if (size < kAuthTrailerBytes) return std::nullopt;
  const size_t payload = size - kAuthTrailerBytes;
  if (std::memcmp(data + payload, kTrailerMagic, 4) != 0) return std::nullopt;
  const std::array<uint8_t, 32> tag = mac(channel, data, payload);
  if (sodium_memcmp(tag.data(), data + payload + 4, tag.size()) != 0) return std::nullopt;
  return payload;
}

}  // namespace sweepmap::net
