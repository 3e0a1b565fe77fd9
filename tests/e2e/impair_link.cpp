// impair_link: packet loss and reordering on a link, for tests where the kernel has no
// `tc netem` (this one: CONFIG_NET_SCH_NETEM unset). An iptables NFQUEUE rule hands it the
// packets to impair, e.g. in the receiving namespace
//   iptables-legacy -A INPUT -i veth-laptop -s 10.77.0.1 -p udp -j NFQUEUE --queue-num 7
// It answers each with a verdict: it drops one packet chosen at random in every block of
// 1/loss packets (exactly `loss` of them, never a long run without a loss), and holds a
// packet now and then (probability `reorder`) until 1 to 4 later datagrams have begun to go
// through (a packet that is a datagram's first IP fragment, or whole), or until `hold_ms` has
// passed with no other packet: the held one then arrives after them. (Counting fragments
// instead, a held fragment of an 8 kB LIDAR_SCAN, six fragments on this link, was overtaken
// only by its own datagram's other fragments: no datagram ever arrived out of order.) The
// kernel matches verdicts by packet id, so they may come in any order.
// On SIGINT or SIGTERM it lets every held packet through and prints its counts.
// Test-only: it is built with the tests and never installed.
#include <arpa/inet.h>
#include <libnetfilter_queue/libnetfilter_queue.h>
#include <linux/netfilter.h>
#include <poll.h>
#include <signal.h>
#include <sys/socket.h>

#include <CLI/CLI.hpp>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <random>
#include <vector>

namespace {

volatile sig_atomic_t g_stop = 0;
void onSignal(int) { g_stop = 1; }

using Clock = std::chrono::steady_clock;

struct Impairer {
  double loss = 0.01;
  double reorder = 0.02;
  int hold_ms = 50;
  std::mt19937_64 rng{1};
  nfq_q_handle* queue = nullptr;

  // Loss: in each block of `block` packets, the one at `drop_at` is dropped.
  int64_t block = 0, in_block = 0, drop_at = -1;
  struct Held {
    uint32_t id;
    int initial;  // packets to let through before this one
    int after;    // of those, still to come
    Clock::time_point since;
  };
  std::vector<Held> held;
  int64_t packets = 0, dropped = 0, held_count = 0, reordered = 0;

  void setVerdict(uint32_t id, uint32_t verdict) {
    nfq_set_verdict(queue, id, verdict, 0, nullptr);
  }
  void newBlock() {
    in_block = 0;
    drop_at = block > 0 ? static_cast<int64_t>(rng() % static_cast<uint64_t>(block)) : -1;
  }
  // One packet from the queue; `starts_datagram`: it is a whole datagram or its first fragment.
  void onPacket(uint32_t id, bool starts_datagram) {
    ++packets;
    if (block > 0) {
      if (in_block == block) newBlock();
      if (in_block++ == drop_at) {
        ++dropped;
        setVerdict(id, NF_DROP);
        return;
      }
    }
    if (std::uniform_real_distribution<double>(0.0, 1.0)(rng) < reorder) {
      ++held_count;
      const int after = 1 + static_cast<int>(rng() % 4);
      held.push_back({id, after, after, Clock::now()});
      return;
    }
    setVerdict(id, NF_ACCEPT);
    if (!starts_datagram) return;
    // This one's datagram overtakes every packet held before it.
    for (size_t i = 0; i < held.size();) {
      if (--held[i].after == 0) {
        ++reordered;
        setVerdict(held[i].id, NF_ACCEPT);
        held.erase(held.begin() + static_cast<long>(i));
      } else {
        ++i;
      }
    }
  }
  // Held packets with nothing behind them for hold_ms go on (overtaken or not).
  void releaseStale(bool all) {
    const auto now = Clock::now();
    for (size_t i = 0; i < held.size();) {
      if (all || now - held[i].since >= std::chrono::milliseconds(hold_ms)) {
        reordered += held[i].after < held[i].initial;
        setVerdict(held[i].id, NF_ACCEPT);
        held.erase(held.begin() + static_cast<long>(i));
      } else {
        ++i;
      }
    }
  }
};

// Whether an IPv4 packet is a whole datagram or its first fragment (fragment offset 0).
bool startsDatagram(nfq_data* nfa) {
  unsigned char* ip = nullptr;
  const int n = nfq_get_payload(nfa, &ip);
  if (n < 20 || ip == nullptr) return true;
  return ((ip[6] & 0x1F) << 8 | ip[7]) == 0;
}

int onQueued(nfq_q_handle*, nfgenmsg*, nfq_data* nfa, void* data) {
  const nfqnl_msg_packet_hdr* ph = nfq_get_msg_packet_hdr(nfa);
  if (ph) static_cast<Impairer*>(data)->onPacket(ntohl(ph->packet_id), startsDatagram(nfa));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "impair_link (test-only): drops and reorders the packets an iptables NFQUEUE rule "
      "queues to it, as `tc netem loss ... reorder ...` would; prints its counts on "
      "SIGINT/SIGTERM"};
  int queue_num = 0;
  uint64_t seed = 1;
  Impairer imp;
  app.add_option("--queue", queue_num, "NFQUEUE number (iptables --queue-num)")->required();
  app.add_option("--loss", imp.loss, "fraction of packets dropped: one in each block of 1/loss")
      ->check(CLI::Range(0.0, 0.5));
  app.add_option("--reorder", imp.reorder, "probability that a packet is held back")
      ->check(CLI::Range(0.0, 0.5));
  app.add_option("--hold-ms", imp.hold_ms, "longest hold while no packet follows")
      ->check(CLI::Range(1, 10000));
  app.add_option("--seed", seed, "random seed");
  CLI11_PARSE(app, argc, argv);
  imp.rng.seed(seed);
  imp.block = imp.loss > 0 ? static_cast<int64_t>(std::lround(1.0 / imp.loss)) : 0;
  imp.newBlock();

  nfq_handle* h = nfq_open();
  if (!h) {
    std::cerr << "impair_link: nfq_open: " << std::strerror(errno) << "\n";
    return 1;
  }
  imp.queue = nfq_create_queue(h, static_cast<uint16_t>(queue_num), &onQueued, &imp);
  if (!imp.queue) {
    std::cerr << "impair_link: cannot bind NFQUEUE " << queue_num << ": " << std::strerror(errno)
              << "\n";
    nfq_close(h);
    return 1;
  }
  // The packet id and the IP header; a long queue so bursts (cloud chunks) are not refused.
  nfq_set_mode(imp.queue, NFQNL_COPY_PACKET, 20);  // the IP header: fragment offset
  nfq_set_queue_maxlen(imp.queue, 8192);
  const int fd = nfq_fd(h);
  int rcvbuf = 4 << 20;
  setsockopt(fd, SOL_SOCKET, SO_RCVBUFFORCE, &rcvbuf, sizeof rcvbuf);

  struct sigaction sa {};
  sa.sa_handler = onSignal;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  std::cout << "impair_link: queue " << queue_num << ", loss " << imp.loss << ", reorder "
            << imp.reorder << ", seed " << seed << std::endl;

  std::vector<char> buf(1 << 16);
  int64_t overruns = 0;
  while (!g_stop) {
    pollfd p{fd, POLLIN, 0};
    const int n = poll(&p, 1, 5);
    if (n > 0) {
      const ssize_t len = recv(fd, buf.data(), buf.size(), MSG_DONTWAIT);
      if (len > 0) {
        nfq_handle_packet(h, buf.data(), static_cast<int>(len));
      } else if (len < 0 && errno == ENOBUFS) {
        ++overruns;  // the kernel could not tell us of some packets: they are dropped
      }
    }
    imp.releaseStale(false);
  }
  imp.releaseStale(true);
  std::cout << "impair_link: packets " << imp.packets << " dropped " << imp.dropped << " held "
            << imp.held_count << " reordered " << imp.reordered << " overruns " << overruns
            << std::endl;
  nfq_destroy_queue(imp.queue);
  nfq_close(h);
  return 0;
}
