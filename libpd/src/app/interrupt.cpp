// Stop requests from signals: a flag set by the handler, polled by the run; a watchdog for the
// phases that cannot poll it.
#include "libpd/app/interrupt.hpp"

#include "libpd/core/child_process.hpp"

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <mutex>
#include <optional>
#include <pthread.h>
#include <thread>
#include <time.h>
#include <unistd.h>
#include <vector>

namespace pd {

namespace {

std::atomic<int> stop_signal{0};  // lock-free: the one thing a handler may touch
std::atomic<int> guard_depth{0};  // guards alive; only the main thread makes them
std::atomic<bool> holding{false}; // hold_stop_requests() is in force: requests are kept
struct sigaction before_holding[stop_signals.size()]{};

extern "C" void on_stop_signal(int sig) {
  int none = 0;
  stop_signal.compare_exchange_strong(none, sig); // the first signal names the stop
}

/// Takes the stop signals while hold_stop_requests is in force. Every thread of pd keeps them
/// blocked (main blocks them before any library starts a thread, and threads inherit the mask),
/// so they reach no handler: a library that installs its own for a while cannot take them.
/// METIS does (GKlib's gk_sigtrap, during CHOLMOD's ordering): its handler turned a SIGTERM into
/// an ordering error that CHOLMOD recovered from, and the request was lost.
class Listener {
public:
  static Listener& instance() {
    static Listener l;
    return l;
  }
  void start() {
    if (!thread_.joinable()) {
      quit_ = false;
      thread_ = std::thread([this] { listen(); });
    }
  }
  void stop() {
    if (thread_.joinable()) {
      quit_ = true;
      thread_.join();
    }
  }
  ~Listener() { stop(); }

private:
  void listen() {
    const sigset_t set = stop_signal_set();
    // Woken to look at quit_; a signal is taken at once.
    const timespec tick{0, 50'000'000};
    while (!quit_.load()) {
      if (const int sig = ::sigtimedwait(&set, nullptr, &tick); sig > 0) {
        on_stop_signal(sig);
      }
    }
  }
  std::thread thread_;
  std::atomic<bool> quit_{false};
};

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
      if (const int pid = running_child(); pid > 0) {
        ::kill(-pid, SIGTERM); // pd-fem of a verification: it would run on and write alone
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
  for (std::size_t k = 0; k < stop_signals.size(); ++k) {
    sigaction(stop_signals[k], &sa, &previous_[k]);
  }
}

InterruptGuard::~InterruptGuard() {
  if (!active_) {
    return;
  }
  guard_depth.fetch_sub(1);
  if (outermost_) {
    for (std::size_t k = 0; k < stop_signals.size(); ++k) {
      sigaction(stop_signals[k], &previous_[k], nullptr);
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
  // The handler only for a thread some library starts with the signals unblocked.
  for (std::size_t k = 0; k < stop_signals.size(); ++k) {
    sigaction(stop_signals[k], &sa, &before_holding[k]);
  }
  const sigset_t held = stop_signal_set();
  pthread_sigmask(SIG_BLOCK, &held, nullptr);
  holding.store(true);
  // Started with the signals blocked, as it must be to wait for them; a signal pending since the
  // restart is taken now.
  Listener::instance().start();
}

void release_stop_requests() {
  if (!holding.exchange(false)) {
    return;
  }
  Listener::instance().stop();
  for (std::size_t k = 0; k < stop_signals.size(); ++k) {
    sigaction(stop_signals[k], &before_holding[k], nullptr);
  }
  if (const int sig = stop_signal.exchange(0); sig != 0) {
    ::raise(sig); // pending until the signals are unblocked below, then their default action
  }
  const sigset_t held = stop_signal_set();
  pthread_sigmask(SIG_UNBLOCK, &held, nullptr);
}

AbandonOnInterrupt::AbandonOnInterrupt(std::function<void(int signal)> write)
    : write_(std::move(write)) {
  Watchdog::instance().push(&write_);
}

AbandonOnInterrupt::~AbandonOnInterrupt() {
  Watchdog::instance().pop(&write_);
}

} // namespace pd
