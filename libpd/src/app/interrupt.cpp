// Stop requests from signals: a flag set by the handler, polled by the run.
#include "libpd/app/interrupt.hpp"

#include <atomic>

namespace pd {

namespace {

std::atomic<int> stop_signal{0}; // lock-free: the one thing a handler may touch

extern "C" void on_stop_signal(int sig) {
  int none = 0;
  stop_signal.compare_exchange_strong(none, sig); // the first signal names the stop
}

} // namespace

InterruptGuard::InterruptGuard(bool active) : active_(active) {
  stop_signal.store(0);
  if (!active_) {
    return;
  }
  struct sigaction sa {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART; // a write interrupted by the signal carries on
  for (int k = 0; k < 3; ++k) {
    sigaction(signals_[k], &sa, &previous_[k]);
  }
}

InterruptGuard::~InterruptGuard() {
  if (active_) {
    for (int k = 0; k < 3; ++k) {
      sigaction(signals_[k], &previous_[k], nullptr);
    }
  }
}

bool InterruptGuard::requested() const {
  return stop_signal.load() != 0;
}

int InterruptGuard::signal() const {
  return stop_signal.load();
}

} // namespace pd
