#include "drivers/gpio/fatal_signal_guard.hpp"

#include <atomic>
#include <csignal>
#include <mutex>

namespace sweepmap {
namespace {

constexpr int kFatalSignals[] = {SIGSEGV, SIGABRT, SIGBUS, SIGFPE, SIGILL};

struct Slot {
  std::atomic<void (*)(int, int)> write{nullptr};
  std::atomic<int> fd{-1};
  std::atomic<int> value{0};
};
Slot g_slots[kMaxFatalSignalWrites];
struct sigaction g_previous[NSIG];

void onFatalSignal(int sig) {
  for (Slot& s : g_slots) {
    void (*write)(int, int) = s.write.load();
    if (write != nullptr) write(s.fd.load(), s.value.load());
  }
  sigaction(sig, &g_previous[sig], nullptr);
  // Blocked until this handler returns; then the previous action (by default: terminate
  // with a core dump) runs. A hardware fault would also simply recur on return.
  raise(sig);
}

void installOnce() {
  static std::once_flag once;
  std::call_once(once, [] {
    struct sigaction action {};
    action.sa_handler = onFatalSignal;
    sigemptyset(&action.sa_mask);
    action.sa_flags = SA_ONSTACK;
    for (int sig : kFatalSignals) sigaction(sig, &action, &g_previous[sig]);
  });
}

}  // namespace

int registerFatalSignalWrite(const SignalSafeWrite& w) {
  installOnce();
  static std::mutex mutex;
  std::lock_guard<std::mutex> lock(mutex);
  for (int i = 0; i < kMaxFatalSignalWrites; ++i) {
    Slot& s = g_slots[i];
    if (s.write.load() != nullptr) continue;
    s.fd = w.fd;
    s.value = w.value;
    s.write = w.write;  // last: the handler reads a complete slot
    return i;
  }
  return -1;
}

void unregisterFatalSignalWrite(int slot) {
  if (slot >= 0 && slot < kMaxFatalSignalWrites) g_slots[slot].write = nullptr;
}

}  // namespace sweepmap
