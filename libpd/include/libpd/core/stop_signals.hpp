// The signals that ask pd to stop cleanly (app/interrupt.hpp) rather than end it: Ctrl-C
// (SIGINT), a scheduler's SIGTERM before its SIGKILL, a closed terminal's SIGHUP, and SIGUSR1,
// which OpenMPI's mpirun forwards to every rank (its own SIGTERM and SIGINT abort the job with
// exit 1 and SIGKILL the ranks a second later, whatever they return). In core because the
// process restart (core/blas.hpp) must keep them blocked across exec.
#pragma once

#include <array>
#include <csignal>

namespace pd {

inline constexpr std::array<int, 4> stop_signals{SIGINT, SIGTERM, SIGHUP, SIGUSR1};

/// stop_signals as a set, for sigprocmask, sigtimedwait and posix_spawn.
inline sigset_t stop_signal_set() {
  sigset_t set;
  sigemptyset(&set);
  for (const int sig : stop_signals) {
    sigaddset(&set, sig);
  }
  return set;
}

} // namespace pd
