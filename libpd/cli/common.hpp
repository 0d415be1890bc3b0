// What the subcommands of `pd` share: thread count, scene loading with its warnings, and the
// shape of a subcommand (its CLI11 app and the action main runs when it was chosen).
#pragma once

#include "libpd/io/scene.hpp"

#include <CLI/CLI.hpp>
#include <functional>
#include <string>

namespace pd::cli {

/// A subcommand: `run` is called after parsing if `app` was chosen and returns the exit code
/// (0 success, 1 bad input or usage, 2 a verification gate failed, 3 the run became unstable,
/// 4 a stability gate failed).
struct Command {
  CLI::App* app = nullptr;
  std::function<int()> run;
};

/// OpenMP threads for this process; 0 keeps the default (all).
void set_threads(int threads);
int thread_count();
void add_threads_option(CLI::App& command, int& threads);

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
