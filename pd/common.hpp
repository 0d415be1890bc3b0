// What the subcommands of `pd` share: thread count, scene loading with its warnings, and the
// shape of a subcommand (its CLI11 app and the action main runs when it was chosen).
#pragma once

#include "libpd/app/interrupt.hpp"
#include "libpd/io/scene.hpp"

#include <CLI/CLI.hpp>
#include <functional>
#include <string>
#include <string_view>

namespace pd::cli {

/// A subcommand: `run` is called after parsing if `app` was chosen and returns the exit code
/// (0 success, 1 bad input or usage, 2 a verification gate failed, 3 the run became unstable,
/// 4 a stability gate failed, 5 the run was interrupted).
/// Exit code of a run stopped by Ctrl-C, SIGTERM, SIGHUP or SIGUSR1 (its results so far are
/// written): not 0, so that a script or scheduler never takes a partial run for a finished one.
inline constexpr int exit_interrupted = pd::exit_status_interrupted;

/// For a command with nothing to save on a stop request (pd bench, pd compare: what they print
/// or write is complete row by row): Ctrl-C, SIGTERM, SIGHUP or SIGUSR1 end it within a second,
/// with exit status 5 and a line on stderr that says so (app/interrupt.hpp).
class StopOnInterrupt {
public:
  explicit StopOnInterrupt(std::string command);

private:
  InterruptGuard guard_{true};
  AbandonOnInterrupt abandon_;
};

struct Command {
  CLI::App* app = nullptr;
  std::function<int()> run;
  /// Whether a stop request ends it cleanly (exit 5): then one during its set-up is held for it
  /// (hold_stop_requests), else the signal acts as usual.
  bool stops_cleanly = false;
};

/// OpenMP threads for this process; 0: the processors other programs leave idle, followed during
/// the run (core/threads.hpp), unless OMP_NUM_THREADS says otherwise. More threads than the
/// machine has processors are capped to that number, with a warning (oversubscribed threads only
/// wait for each other: 10,000 threads ran 230× slower).
void set_threads(int threads);
/// --threads N, N ≥ 1 (not given: set_threads(0)).
void add_threads_option(CLI::App& command, int& threads);

/// Largest count (steps, repeats, evaluations) any option takes: beyond it a run would not end in
/// a lifetime, and it is far below where an integer type wraps.
inline constexpr double max_count = 1e12;

/// A count option (steps, repeats, every N steps): an integer in [min, max_count]. The range is
/// checked on the text, before CLI11 converts it: it would turn "-1" into 2^64 − 1 for an
/// unsigned target.
template <class T>
CLI::Option* add_count_option(CLI::App& command, const std::string& name, T& value,
                              const std::string& doc, double min = 1) {
  return command.add_option(name, value, doc)
      ->check(CLI::Range(min, max_count))
      ->capture_default_str();
}

/// A validator for a real option that must be finite and lie in (low, high]: CLI::Range lets NaN
/// through, since every comparison with NaN is false.
CLI::Validator finite_in(double low, double high);

/// The first three fields of /proc/loadavg ("unknown" elsewhere), printed beside timings.
std::string load_average();

/// How much CPU other processes (and the hypervisor: steal time) took while a section ran, in
/// cores: the busy time of all CPUs from /proc/stat minus this process's own CPU time, over the
/// wall time. A load average cannot say this: it lags by a minute and counts the benchmark
/// itself. Sections add up (start/stop around each timed part); 0 where /proc/stat is missing.
class OtherCpuMeter {
public:
  void start();
  void stop();
  /// Mean cores used by others over all sections so far.
  double cores() const;

private:
  double busy0_ = 0, self0_ = 0, wall0_ = 0;
  double other_seconds_ = 0, wall_seconds_ = 0;
};

/// Load a scene and print its warnings on stderr.
Scene load_or_explain(const std::string& path);

} // namespace pd::cli
