// What the subcommands of `pd` share.
#include "common.hpp"

#include "libpd/core/text.hpp"
#include "libpd/core/threads.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fmt/format.h>
#include <fstream>
#include <sys/resource.h>
#include <unistd.h>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace pd::cli {

void set_threads(int threads) {
#ifdef _OPENMP
  if (threads > 0) {
    const int processors = omp_get_num_procs();
    if (threads > processors) {
      fmt::print(stderr, "warning: --threads {} is more than the {} processors here; using {}\n",
                 threads, processors, processors);
      threads = processors;
    }
    omp_set_num_threads(threads);
  } else if (std::getenv("OMP_NUM_THREADS") == nullptr) {
    follow_idle_processors(true); // core/threads.hpp: the processors other programs leave idle
  }
#else
  (void)threads;
#endif
}

void add_threads_option(CLI::App& command, int& threads) {
  command
      .add_option("--threads", threads,
                  "OpenMP threads, at least 1 (default: the processors other programs leave idle)")
      ->check(CLI::Range(1, 1 << 20));
}

CLI::Validator finite_in(double low, double high) {
  return CLI::Validator(
      [low, high](std::string& text) -> std::string {
        double v = 0;
        if (!CLI::detail::lexical_cast(text, v) || !std::isfinite(v) || !(v > low) ||
            !(v <= high)) {
          return fmt::format("expected a finite number in ({}, {}]", low, high);
        }
        return {};
      },
      fmt::format("in ({}, {}]", low, high));
}

std::string load_average() {
  std::ifstream in("/proc/loadavg");
  std::string a, b, c;
  if (!(in >> a >> b >> c)) {
    return "unknown";
  }
  return a + " " + b + " " + c;
}

namespace {

/// Busy seconds of all CPUs since boot (user, nice, system, irq, softirq, steal), -1 if unknown.
double busy_cpu_seconds() {
  std::ifstream in("/proc/stat");
  std::string cpu;
  double user = 0, nice = 0, system = 0, idle = 0, iowait = 0, irq = 0, softirq = 0, steal = 0;
  if (!(in >> cpu >> user >> nice >> system >> idle >> iowait >> irq >> softirq >> steal) ||
      cpu != "cpu") {
    return -1;
  }
  return (user + nice + system + irq + softirq + steal) /
         static_cast<double>(::sysconf(_SC_CLK_TCK));
}

double own_cpu_seconds() {
  rusage u{};
  ::getrusage(RUSAGE_SELF, &u);
  const auto s = [](const timeval& t) {
    return static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_usec);
  };
  return s(u.ru_utime) + s(u.ru_stime);
}

double wall_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

} // namespace

void OtherCpuMeter::start() {
  busy0_ = busy_cpu_seconds();
  self0_ = own_cpu_seconds();
  wall0_ = wall_seconds();
}

void OtherCpuMeter::stop() {
  const double busy = busy_cpu_seconds();
  if (busy < 0 || busy0_ < 0) {
    return;
  }
  other_seconds_ += std::max(0.0, (busy - busy0_) - (own_cpu_seconds() - self0_));
  wall_seconds_ += wall_seconds() - wall0_;
}

double OtherCpuMeter::cores() const {
  return wall_seconds_ > 0 ? other_seconds_ / wall_seconds_ : 0.0;
}

StopOnInterrupt::StopOnInterrupt(std::string command)
    : abandon_([command = std::move(command)](int sig) {
        fmt::print(stderr, "pd {}: interrupted by signal {} ({})\n", command, sig,
                   ::strsignal(sig));
      }) {}

Scene load_or_explain(const std::string& path) {
  Scene scene = load_scene(path);
  for (const auto& w : scene.warnings) {
    fmt::print(stderr, "{}\n", w);
  }
  return scene;
}

} // namespace pd::cli
