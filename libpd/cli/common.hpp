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

/// Load a scene and print its warnings on stderr.
Scene load_or_explain(const std::string& path);

} // namespace pd::cli
