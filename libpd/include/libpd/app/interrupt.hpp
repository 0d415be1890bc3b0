// Ctrl-C during a run: SIGINT only sets a flag, which the run polls after each step and then
// stops cleanly (status `interrupted`, outputs and a checkpoint written) instead of dying with
// half-written files.
#pragma once

namespace pd {

/// While alive (and `active`), SIGINT requests a stop instead of ending the process; the previous
/// handler is put back on destruction. Requests from before construction are forgotten.
class InterruptGuard {
public:
  explicit InterruptGuard(bool active);
  ~InterruptGuard();
  InterruptGuard(const InterruptGuard&) = delete;
  InterruptGuard& operator=(const InterruptGuard&) = delete;

  bool requested() const;

private:
  bool active_;
  void (*previous_)(int) = nullptr;
};

} // namespace pd
