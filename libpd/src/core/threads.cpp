#include "libpd/core/threads.hpp"

#include <algorithm>
#include <atomic>
#include <charconv>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <string>
#include <system_error>
#include <thread>
#include <vector>
#ifdef _OPENMP
#include <omp.h>
#endif

namespace pd {

int runnable_threads_in_loadavg(std::string_view line) {
  // The fourth field: "running/total".
  std::size_t field_start = 0;
  for (int field = 0; field < 3; ++field) {
    field_start = line.find(' ', field_start);
    if (field_start == std::string_view::npos) {
      return -1;
    }
    field_start = line.find_first_not_of(' ', field_start);
    if (field_start == std::string_view::npos) {
      return -1;
    }
  }
  int running = -1;
  const char* first = line.data() + field_start;
  const auto [end, error] = std::from_chars(first, line.data() + line.size(), running);
  if (error != std::errc() || end == line.data() + line.size() || *end != '/') {
    return -1;
  }
  return running;
}

namespace {

int own_running_threads() {
  std::error_code ec;
  int running = 0;
  for (const auto& task : std::filesystem::directory_iterator("/proc/self/task", ec)) {
    std::ifstream in(task.path() / "stat");
    std::string stat;
    std::getline(in, stat);
    // "pid (comm) S ...": the state follows the last ')' (comm may hold spaces and parentheses).
    const std::size_t close = stat.rfind(')');
    if (close != std::string::npos && close + 2 < stat.size() && stat[close + 2] == 'R') {
      ++running;
    }
  }
  return ec ? -1 : running;
}

/// Samples other_runnable_threads in the background while following_idle_processors is on, and
/// keeps the fewest seen over the last `window` readings: a program that keeps cores busy shows
/// in every reading, a short one (a shell, the Python that reads pd's output from a pipe, a
/// compile step) in a few. Until `first_decision` readings exist, nothing is decided.
class LoadSampler {
public:
  static constexpr auto interval = std::chrono::milliseconds(25);
  static constexpr std::size_t window = 10;
  static constexpr std::size_t first_decision = 4;

  void start() {
    const std::lock_guard lock(mutex_);
    if (!thread_.joinable()) {
      thread_ = std::jthread([this](const std::stop_token& stop) { sample(stop); });
    }
  }

  /// The fewest other runnable threads over the window, or -1 while undecided.
  int fewest_others() const { return fewest_.load(); }

private:
  void sample(const std::stop_token& stop) {
    std::vector<int> readings;
    std::size_t next = 0;
    while (!stop.stop_requested()) {
      const int others = other_runnable_threads();
      if (others >= 0) {
        if (readings.size() < window) {
          readings.push_back(others);
        } else {
          readings[next] = others;
          next = (next + 1) % window;
        }
        if (readings.size() >= first_decision) {
          fewest_ = *std::min_element(readings.begin(), readings.end());
        }
      }
      std::this_thread::sleep_for(interval);
    }
  }

  std::mutex mutex_;
  std::atomic<int> fewest_{-1};
  std::jthread thread_;
};

LoadSampler& sampler() {
  static LoadSampler s;
  return s;
}

std::atomic<bool> following{false};

} // namespace

int other_runnable_threads() {
  std::ifstream in("/proc/loadavg");
  std::string line;
  if (!std::getline(in, line)) {
    return -1;
  }
  const int running = runnable_threads_in_loadavg(line);
  const int own = own_running_threads();
  if (running < 0 || own < 0) {
    return -1;
  }
  // The reading thread is running, and counted in both, while it reads.
  return std::max(0, running - std::max(own, 1));
}

int idle_processors(int processors, int others) {
  return std::max(1, processors - std::max(0, others));
}

void follow_idle_processors(bool on) {
  following = on;
  if (on) {
    sampler().start();
    refresh_thread_count();
  }
}

bool following_idle_processors() {
  return following;
}

int current_thread_count() {
#ifdef _OPENMP
  return omp_get_max_threads();
#else
  return 1;
#endif
}

void refresh_thread_count() {
#ifdef _OPENMP
  if (!following) {
    return;
  }
  const int processors = omp_get_num_procs();
  const int others = sampler().fewest_others();
  // Undecided (the program's first 0.1 s): every processor, as OpenMP would.
  const int threads = others < 0 ? processors : idle_processors(processors, others);
  if (threads != omp_get_max_threads()) {
    omp_set_num_threads(threads);
  }
#endif
}

} // namespace pd
