// Stopping a run from outside: Ctrl-C (SIGINT), a scheduler's SIGTERM before its SIGKILL, a closed
// terminal's SIGHUP and SIGUSR1 (what mpirun forwards; core/stop_signals.hpp) only set a flag,
// which the run polls after each step and then stops cleanly (status `interrupted`, outputs and a
// checkpoint written) instead of dying with half-written files. Work that cannot poll (building a
// model, CHOLMOD's factorisation, a verification case) is abandoned instead: a watchdog thread
// writes what is known and ends the process, so that every phase answers within a second.
#pragma once

#include "libpd/core/stop_signals.hpp"

#include <csignal>
#include <functional>

namespace pd {

/// While alive (and `active`), the stop signals (SIGINT, SIGTERM, SIGHUP, SIGUSR1) request a stop
/// instead of ending the process; later signals only repeat the request, so a second Ctrl-C while
/// the final files are written cannot cut them short. The previous handlers are put back on
/// destruction. Guards nest (a run inside `pd verify`): only the outermost installs the handlers
/// and forgets requests from before its construction, so an inner one never loses a request the
/// outer one has seen.
class InterruptGuard {
public:
  explicit InterruptGuard(bool active);
  ~InterruptGuard();
  InterruptGuard(const InterruptGuard&) = delete;
  InterruptGuard& operator=(const InterruptGuard&) = delete;

  bool requested() const;
  /// The signal that asked for the stop (one of stop_signals), 0 if none did.
  int signal() const;

private:
  bool active_;
  bool outermost_ = false;
  struct sigaction previous_[stop_signals.size()]{};
};

/// From the first instruction of a command that stops cleanly to its InterruptGuard (reading the
/// scene, starting MPI): the stop signals are held as a request, which the outermost
/// guard then takes over instead of forgetting, so that a stop during set-up still ends the run
/// with status 5 and a summary rather than killing it. Also takes delivery of the signals that
/// arrived while they were blocked across the restart of pd (core/blas.hpp).
/// The calling thread must be the program's only one or every other thread must block the stop
/// signals (pd's main blocks them before any library starts a thread): from here on they stay
/// blocked in every thread and one thread of this file waits for them, so no handler a library
/// installs for a while (METIS does, for SIGTERM) can take one. Programs started meanwhile get
/// them unblocked through core/child_process.hpp, not std::system or popen.
void hold_stop_requests();
/// For a command that does not stop cleanly (pd info): the signals act as they did before
/// hold_stop_requests, and one held meanwhile ends the process now, as it would have.
void release_stop_requests();

/// While alive, a stop request that the code has not acted on within `abandon_grace_seconds`
/// (acting on it means destroying this object) ends the process with exit status 5: `write` is
/// called on a watchdog thread with the signal, to record the interrupted state, and then
/// _exit. It runs beside the busy thread, so it may only read what it owns or what is guarded
/// against that thread. Several may be alive (a run inside a verification case inside `pd
/// verify`): the innermost writes first. Meant for phases that cannot poll the request; where
/// a phase polls, destroying this object before writing the final state keeps the files whole.
class AbandonOnInterrupt {
public:
  explicit AbandonOnInterrupt(std::function<void(int signal)> write);
  ~AbandonOnInterrupt();
  AbandonOnInterrupt(const AbandonOnInterrupt&) = delete;
  AbandonOnInterrupt& operator=(const AbandonOnInterrupt&) = delete;

private:
  std::function<void(int)> write_;
};

/// How long a stop request may go unanswered before the work is abandoned: half the second the
/// user is promised, the other half for writing the interrupted state.
inline constexpr double abandon_grace_seconds = 0.5;

/// The exit status of an interrupted command (pd's exit codes, cli/main.cpp).
inline constexpr int exit_status_interrupted = 5;

} // namespace pd
