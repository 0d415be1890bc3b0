// Ctrl-C during a run: a flag set by the SIGINT handler, polled by the run.
#include "libpd/app/interrupt.hpp"

#include <atomic>
#include <csignal>

namespace pd {

namespace {

std::atomic<bool> interrupt_requested{false};

extern "C" void on_interrupt(int) {
  interrupt_requested.store(true);
}

} // namespace

InterruptGuard::InterruptGuard(bool active) : active_(active), previous_(SIG_DFL) {
  interrupt_requested.store(false);
  if (active_) {
    previous_ = std::signal(SIGINT, on_interrupt);
  }
}

InterruptGuard::~InterruptGuard() {
  if (active_) {
    std::signal(SIGINT, previous_);
  }
}

bool InterruptGuard::requested() const {
  return interrupt_requested.load();
}

} // namespace pd
