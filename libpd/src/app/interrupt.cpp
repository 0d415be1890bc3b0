// Stop requests from signals: a flag set by the handler, polled by the run; a watchdog for the
// phases that cannot poll it.
#include "libpd/app/interrupt.hpp"

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <mutex>
#include <optional>
#include <thread>
#include <unistd.h>
#include <vector>

namespace pd {

namespace {

std::atomic<int> stop_signal{0};  // lock-free: the one thing a handler may touch
std::atomic<int> guard_depth{0};  // guards alive; only the main thread makes them
std::atomic<bool> holding{false}; // hold_stop_requests() is in force: requests are kept
constexpr int stop_signals[] = {SIGINT, SIGTERM, SIGHUP};
struct sigaction before_holding[3]{};

extern "C" void on_stop_signal(int sig) {
  int none = 0;
  stop_signal.compare_exchange_strong(none, sig); // the first signal names the stop
}

/// The watchdog of AbandonOnInterrupt: one thread while any is alive. A handler may not wake a
/// condition variable, so the thread looks at the flag every `poll`; that delay is part of the
/// grace.
class Watchdog {
public:
  static Watchdog& instance() {
    static Watchdog w;
    return w;
  }

  void push(const std::function<void(int)>* write) {
    std::unique_lock lock(mutex_);
    writers_.push_back(write);
    if (!thread_.joinable()) {
      quit_ = false;
      thread_ = std::thread([this] { watch(); });
    }
  }

  void pop(const std::function<void(int)>* write) {
    std::thread finished;
    {
      // Blocks while the watchdog writes: the process then ends inside watch().
      std::unique_lock lock(mutex_);
      std::erase(writers_, write);
      if (writers_.empty() && thread_.joinable()) {
        quit_ = true;
        finished = std::move(thread_);
      }
    }
    if (finished.joinable()) {
      wake_.notify_all();
      finished.join();
    }
  }

private:
  void watch() {
    using clock = std::chrono::steady_clock;
    constexpr auto poll = std::chrono::milliseconds(20);
    std::optional<clock::time_point> seen;
    std::unique_lock lock(mutex_);
    while (!quit_) {
      wake_.wait_for(lock, poll);
      if (quit_ || stop_signal.load() == 0) {
        continue;
      }
      const auto now = clock::now();
      if (!seen) {
        seen = now;
      }
      if (std::chrono::duration<double>(now - *seen).count() < abandon_grace_seconds) {
        continue;
      }
      const int sig = stop_signal.load();
      for (auto w = writers_.rbegin(); w != writers_.rend(); ++w) {
        try {
          (**w)(sig);
        } catch (...) { // what could not be written is lost; the exit must still come
        }
      }
      std::fflush(stdout);
      std::fflush(stderr);
      // Not exit(): destructors and atexit handlers would run beside the abandoned thread,
      // which still uses what they free.
      ::_exit(exit_status_interrupted);
    }
  }

  std::mutex mutex_;
  std::condition_variable wake_;
  std::vector<const std::function<void(int)>*> writers_;
  std::thread thread_;
  bool quit_ = false;
};

} // namespace

InterruptGuard::InterruptGuard(bool active) : active_(active) {
  if (!active_) {
    return;
  }
  outermost_ = guard_depth.fetch_add(1) == 0;
  if (!outermost_) {
    return;
  }
  if (!holding.load()) {
    stop_signal.store(0);
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
  if (!active_) {
    return;
  }
  guard_depth.fetch_sub(1);
  if (outermost_) {
    for (int k = 0; k < 3; ++k) {
      sigaction(signals_[k], &previous_[k], nullptr);
    }
  }
}

bool InterruptGuard::requested() const {
  return active_ && stop_signal.load() != 0;
}

int InterruptGuard::signal() const {
  return active_ ? stop_signal.load() : 0;
}

void hold_stop_requests() {
  struct sigaction sa {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;
  sigset_t held;
  sigemptyset(&held);
  for (int k = 0; k < 3; ++k) {
    sigaction(stop_signals[k], &sa, &before_holding[k]);
    sigaddset(&held, stop_signals[k]);
  }
  holding.store(true);
  // Only now: a signal pending since the restart reaches the handler, not the default action.
  sigprocmask(SIG_UNBLOCK, &held, nullptr);
}

void release_stop_requests() {
  if (!holding.exchange(false)) {
    return;
  }
  for (int k = 0; k < 3; ++k) {
    sigaction(stop_signals[k], &before_holding[k], nullptr);
  }
  if (const int sig = stop_signal.exchange(0); sig != 0) {
    ::raise(sig);
  }
}

AbandonOnInterrupt::AbandonOnInterrupt(std::function<void(int signal)> write)
    : write_(std::move(write)) {
  Watchdog::instance().push(&write_);
}

AbandonOnInterrupt::~AbandonOnInterrupt() {
  Watchdog::instance().pop(&write_);
}

} // namespace pd
