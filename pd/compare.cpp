// pd compare dynamic|quasistatic [-o FILE] [--scenes DIR] [--quick] [--threads N]
// Integrator comparison rows (JSON lines on stdout and, with -o, in FILE). The study itself is
// verification/studies/integrator_comparison.hpp; this file only parses and prints.
#include "case_folders.hpp"
#include "commands.hpp"
#include "integrator_comparison.hpp"
#include "verification.hpp"

#include <cstdio>
#include <fmt/format.h>
#include <fstream>
#include <memory>

namespace pd::cli {

namespace {

struct CompareArgs {
  std::string what, out_file, scenes_dir;
  bool quick = false;
  int threads = 0;
};

int compare(const CompareArgs& a) {
  const StopOnInterrupt stop("compare");
  set_threads(a.threads);
  const std::filesystem::path dir = a.scenes_dir.empty() ? verification::default_cases_dir()
                                                         : std::filesystem::path(a.scenes_dir);
  std::ofstream out;
  if (!a.out_file.empty()) {
    out.open(a.out_file);
    if (!out) {
      fmt::print(stderr, "error: cannot write {}\n", a.out_file);
      return 1;
    }
  }
  auto emit = [&](const Json& row) {
    std::string line = row.dump(0);
    while (!line.empty() && line.back() == '\n') {
      line.pop_back(); // one row per line
    }
    fmt::print("{}\n", line);
    std::fflush(stdout);
    if (out) {
      out << line << "\n";
      out.flush();
    }
  };
  if (a.what == "dynamic") {
    verification::compare_integrators_dynamic(dir, a.quick, emit);
    return 0;
  }
  if (a.what == "quasistatic") {
    verification::compare_integrators_quasistatic(dir, a.quick, emit);
    return 0;
  }
  fmt::print(stderr, "error: pd compare needs 'dynamic' or 'quasistatic'\n");
  return 1;
}

} // namespace

Command add_compare_command(CLI::App& app) {
  auto a = std::make_shared<CompareArgs>();
  auto* cmd = app.add_subcommand(
      "compare", "Integrator comparison rows (JSON lines): 'dynamic' = bar-vibration error vs "
                 "cost, 'quasistatic' = clamped-beam cost to steady state");
  cmd->add_option("what", a->what, "dynamic | quasistatic")
      ->required()
      ->check(CLI::IsMember({"dynamic", "quasistatic"}));
  cmd->add_option("-o,--output", a->out_file, "also write the rows to this .jsonl file");
  cmd->add_option("--scenes", a->scenes_dir,
                  "folder of the case folders (bar-vibration/, clamped-beam/)");
  cmd->add_flag("--quick", a->quick,
                "dynamic: one period and a coarser reference; quasistatic: twice the spacing, "
                "no adaptive Dormand–Prince");
  add_threads_option(*cmd, a->threads);
  return {cmd, [a] { return compare(*a); }, true};
}

} // namespace pd::cli
