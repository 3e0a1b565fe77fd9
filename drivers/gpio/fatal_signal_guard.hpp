// Last-resort safety for outputs that must not stay active when the process dies: on a fatal
// signal (SIGSEGV, SIGABRT, SIGBUS, SIGFPE, SIGILL) an async-signal-safe handler writes every
// registered output's safe level (one write(2)/ioctl(2) each), puts back the handler that
// was there before and re-raises the signal, so the process still dies (and dumps core) as
// it would have. SIGINT/SIGTERM are not handled here: they stop the process normally
// (processes/live_runner.hpp) and the driver's destructor disables the motor.
#pragma once

#include "drivers/gpio/gpio_backend.hpp"

namespace sweepmap {

// Installs the handlers (once per process) and registers `w`. Returns a slot for
// unregisterFatalSignalWrite, or -1 when all kMaxFatalSignalWrites slots are taken.
constexpr int kMaxFatalSignalWrites = 8;
int registerFatalSignalWrite(const SignalSafeWrite& w);
void unregisterFatalSignalWrite(int slot);

}  // namespace sweepmap
