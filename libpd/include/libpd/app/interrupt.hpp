// Stopping a run from outside: Ctrl-C (SIGINT), a scheduler's SIGTERM before its SIGKILL, and a
// closed terminal's SIGHUP only set a flag, which the run polls after each step and then stops
// cleanly (status `interrupted`, outputs and a checkpoint written) instead of dying with
// half-written files.
#pragma once

#include <csignal>

namespace pd {

/// While alive (and `active`), SIGINT, SIGTERM and SIGHUP request a stop instead of ending the
/// process; later signals only repeat the request, so a second Ctrl-C while the final files are
/// written cannot cut them short. The previous handlers are put back on destruction. Requests
/// from before construction are forgotten.
class InterruptGuard {
public:
  explicit InterruptGuard(bool active);
  ~InterruptGuard();
  InterruptGuard(const InterruptGuard&) = delete;
  InterruptGuard& operator=(const InterruptGuard&) = delete;

  bool requested() const;
  /// The signal that asked for the stop (SIGINT, SIGTERM or SIGHUP), 0 if none did.
  int signal() const;

private:
  static constexpr int signals_[] = {SIGINT, SIGTERM, SIGHUP};
  bool active_;
  struct sigaction previous_[3]{};
};

} // namespace pd
