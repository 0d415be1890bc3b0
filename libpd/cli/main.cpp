// pd — the libpd command line. Each subcommand lives in its own file, which registers its
// options and implements it; this file only sets up the app and dispatches.
//
//   pd run SCENE [-o DIR] [--threads N]       run a scene, write summary.json, probes.csv, VTU
//          [--checkpoint-every N] [--checkpoint FILE] [--restart FILE]
//   pd info SCENE [--json]                    sizes, memory estimate, stable time step
//   pd bench SCENE [--steps N] [--threads N]  force-evaluation throughput
//          [--kernel simd|scalar] [--damage] [--lammps LMP]  (--lammps: alternate with LAMMPS)
//   pd verify [CASE...] [-o DIR] [--list]     verification cases with their gates
//   pd stability SCENE... [--integrator X]    measured vs predicted stable time steps
//   pd compare dynamic|quasistatic [-o F]     integrator cost/accuracy rows (JSON lines)
//   pd section SCENE [--depth z] [--plate]    PD/continuum stiffness of a beam or plate section
//
// Exit codes: 0 success, 1 bad input or usage, 2 a verification gate failed, 3 the run became
// unstable, 4 a stability gate failed.
#include "commands.hpp"

#include <fmt/format.h>
#include <vector>

int main(int argc, char** argv) {
  CLI::App app{"pd — bond-based peridynamics with its own verification"};
  app.require_subcommand(1);
  const std::vector<pd::cli::Command> commands = {
      pd::cli::add_run_command(app),       pd::cli::add_info_command(app),
      pd::cli::add_bench_command(app),     pd::cli::add_verify_command(app),
      pd::cli::add_stability_command(app), pd::cli::add_compare_command(app),
      pd::cli::add_section_command(app),
  };
  CLI11_PARSE(app, argc, argv);
  try {
    for (const auto& command : commands) {
      if (*command.app) {
        return command.run();
      }
    }
  } catch (const pd::SceneError& e) {
    fmt::print(stderr, "{}\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return 1;
  }
  return 0;
}
