#include "tools/bench/hostile_traffic.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <random>
#include <stdexcept>
#include <thread>

#include "core/event_log.hpp"
#include "net/lcm_datagram.hpp"
#include "sweepmap/map_save_t.hpp"
#include "sweepmap/process_status_t.hpp"
#include "sweepmap/sweep_status_t.hpp"

namespace sweepmap::hostile {

namespace {

void putU32(Bytes& b, uint32_t v) {
  for (int s = 24; s >= 0; s -= 8) b.push_back(static_cast<uint8_t>(v >> s));
}

void setU32(Bytes& b, size_t at, uint32_t v) {
  for (int i = 0; i < 4; ++i) b[at + i] = static_cast<uint8_t>(v >> (24 - 8 * i));
}

void putU64(Bytes& b, uint64_t v) {
  for (int s = 56; s >= 0; s -= 8) b.push_back(static_cast<uint8_t>(v >> s));
}

void putString(Bytes& b, const std::string& s) {
  putU32(b, static_cast<uint32_t>(s.size() + 1));
  b.insert(b.end(), s.begin(), s.end());
  b.push_back(0);
}

// An LC03 header: magic, sequence number, message size, offset, fragment number and count.
Bytes fragmentHeader(uint32_t seqno, uint32_t size, uint32_t offset, uint16_t count) {
  Bytes b;
  putU32(b, net::kLcmMagicLong);
  putU32(b, seqno);
  putU32(b, size);
  putU32(b, offset);
  b.insert(b.end(), {0, 0, static_cast<uint8_t>(count >> 8), static_cast<uint8_t>(count)});
  return b;
}

template <class T>
Bytes encode(const T& m) {
  Bytes b(static_cast<size_t>(m.getEncodedSize()));
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}

}  // namespace

Bytes offsetWrap(const std::string& channel, uint32_t seqno) {
  Bytes b = fragmentHeader(seqno, 100000, 0xFFFFFFFFu, 2);
  b.insert(b.end(), channel.begin(), channel.end());
  b.push_back(0);
  b.resize(std::max<size_t>(b.size(), 131), 0x41);
  return b;
}

Bytes unterminatedChannel(const std::string& channel, uint32_t seqno) {
  Bytes b;
  putU32(b, net::kLcmMagicShort);
  putU32(b, seqno);
  b.insert(b.end(), channel.begin(), channel.end());
  return b;
}

Bytes openFragment(const std::string& channel, uint32_t seqno) {
  Bytes b = fragmentHeader(seqno, 100000, 0, 2);
  b.insert(b.end(), channel.begin(), channel.end());
  b.push_back(0);
  b.resize(std::max<size_t>(b.size(), 1400), 0x42);
  return b;
}

std::vector<Bytes> malformedDatagrams(const std::vector<std::string>& channels, int mutated,
                                      uint32_t seed) {
  std::vector<Bytes> d;
  uint32_t seqno = seed;
  for (const std::string& channel : channels) {
    d.push_back(offsetWrap(channel, seqno++));
    d.push_back(unterminatedChannel(channel, seqno++));
    d.push_back(openFragment(channel, seqno++));
  }
  std::mt19937 rng(seed);
  for (int i = 0; i < mutated && !channels.empty(); ++i) {
    const std::string& channel = channels[static_cast<size_t>(i) % channels.size()];
    Bytes b = i % 2 ? offsetWrap(channel, seqno++) : unterminatedChannel(channel, seqno++);
    for (int e = 0; e < 3; ++e) {
      b[rng() % std::min<size_t>(b.size(), 24)] = static_cast<uint8_t>(rng());
    }
    d.push_back(std::move(b));
  }
  return d;
}

Bytes mapSaveWithMinLength() {
  Bytes b;
  putU64(b, static_cast<uint64_t>(map_save_t::getHash()));
  putU64(b, 1);
  putU32(b, 0x80000000u);  // INT32_MIN
  b.insert(b.end(), {'x', 0});
  return b;
}

Bytes statusWithHugeCount(const std::string& process, uint32_t count) {
  Bytes b;
  putU64(b, static_cast<uint64_t>(process_status_t::getHash()));
  putU64(b, 1);
  putString(b, process);
  b.push_back(process_status_t::OK);
  putString(b, "");
  putU32(b, count);  // ncounters, and no counter follows
  return b;
}

Bytes statusWithMinLength() {
  process_status_t s{};
  s.utime = 1;
  Bytes b = encode(s);
  setU32(b, 16, 0x80000000u);  // after the fingerprint and utime: the process's length
  return b;
}

Bytes sweepStatusWithMinLength() {
  Bytes b = encode(sweep_status_t{});
  setU32(b, b.size() - 9, 0x80000000u);  // the reason (""): length, NUL, then chunk_count
  return b;
}

Bytes statusWithBadUtf8(const std::string& process) {
  process_status_t s{};
  s.utime = 1;
  s.process = process;
  s.health = process_status_t::OK;
  s.detail = "\xff\xfe not UTF-8 \xc3";
  s.ncounters = 0;
  return encode(s);
}

Bytes mapSave(const std::string& path, int64_t utime) {
  map_save_t m{};
  m.utime = utime;
  m.path = path;
  return encode(m);
}

std::vector<Forged> messagesOfLog(const std::string& log,
                                  const std::vector<std::string>& channels) {
  std::vector<Forged> out;
  EventLogReader reader(log);
  LogEvent e;
  while (reader.next(&e)) {
    if (channels.empty() ||
        std::find(channels.begin(), channels.end(), e.channel) != channels.end())
      out.push_back({e.channel, e.data});
  }
  return out;
}

std::vector<Forged> decoderBreakers() {
  return {{"MAP_SAVE", mapSaveWithMinLength()},
          {"STATUS_ASSEMBLER", statusWithHugeCount("assembler")},
          {"STATUS_MAPPER", statusWithHugeCount("mapper")},
          {"STATUS_LIDAR", statusWithBadUtf8("lidar")},
          {"MAP_SAVE", mapSave("intruder.bt", 1)},
          {"MAP_SAVE", mapSave("../intruder.bt", 2)}};
}

Forged wronglySigned(const Forged& m, uint8_t key_byte) {
  std::array<uint8_t, net::kAuthKeyBytes> key{};
  key.fill(key_byte);
  return {m.channel, net::MessageAuth(key).sign(m.channel, m.payload.data(), m.payload.size())};
}

std::vector<Bytes> datagramsOf(const std::vector<Forged>& messages, uint32_t first_seqno) {
  std::vector<Bytes> out;
  uint32_t seqno = first_seqno;
  for (const Forged& m : messages) {
    for (Bytes& d :
         net::encodeLcmDatagrams(m.channel, m.payload.data(), m.payload.size(), seqno++)) {
      out.push_back(std::move(d));
    }
  }
  return out;
}

MulticastSender::MulticastSender(const std::string& group, uint16_t port) {
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(port);
  if (inet_pton(AF_INET, group.c_str(), &to.sin_addr) != 1) {
    throw std::runtime_error("MulticastSender: bad group address '" + group + "'");
  }
  static_assert(sizeof to <= sizeof to_);
  std::memcpy(to_.data(), &to, sizeof to);
  fd_ = ::socket(AF_INET, SOCK_DGRAM, 0);
  if (fd_ < 0) throw std::runtime_error(std::string("socket: ") + std::strerror(errno));
  const int ttl = 1;
  ::setsockopt(fd_, IPPROTO_IP, IP_MULTICAST_TTL, &ttl, sizeof ttl);
}

MulticastSender::~MulticastSender() {
  if (fd_ >= 0) ::close(fd_);
}

size_t MulticastSender::send(const std::vector<Bytes>& datagrams, int burst, int pause_us) {
  size_t sent = 0;
  for (size_t i = 0; i < datagrams.size(); ++i) {
    const Bytes& d = datagrams[i];
    sent += ::sendto(fd_, d.data(), d.size(), 0, reinterpret_cast<const sockaddr*>(to_.data()),
                     sizeof(sockaddr_in)) == static_cast<ssize_t>(d.size());
    if (burst > 0 && i % static_cast<size_t>(burst) == static_cast<size_t>(burst) - 1) {
      std::this_thread::sleep_for(std::chrono::microseconds(pause_us));
    }
  }
  return sent;
}

}  // namespace sweepmap::hostile
