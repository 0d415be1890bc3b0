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
// unstable, 4 a stability gate failed, 5 the run was interrupted (a stop signal).
#include "commands.hpp"
#include "libpd/app/interrupt.hpp"
#include "libpd/core/blas.hpp"
#include "libpd/core/communicator.hpp"
#include "libpd/core/stop_signals.hpp"
#include "libpd/core/text.hpp"

#include <algorithm>
#include <csignal>
#include <cstdlib>
#include <fmt/format.h>
#include <string_view>
#include <unistd.h>
#include <vector>

namespace {
/// Before the libraries' initialisers (OpenMPI's, OpenBLAS's take most of pd's first tenth of a
/// second): the stop signals (core/stop_signals.hpp) are blocked, not lost and not fatal, until
/// main holds them as a stop request (pd::hold_stop_requests). Threads those initialisers start
/// keep them blocked, so a signal always reaches a thread that takes it.
void block_stop_signals(int /*argc*/, char** /*argv*/, char** /*envp*/) {
  const sigset_t stop = pd::stop_signal_set();
  sigprocmask(SIG_BLOCK, &stop, nullptr);
}
// NOLINTNEXTLINE: the ELF hook that runs before every shared library's initialiser.
[[gnu::section(".preinit_array"),
  gnu::used]] void (*const block_early)(int, char**, char**) = block_stop_signals;

/// Messages of errors may quote file content and paths: long enough for any real path.
constexpr std::size_t long_word_bytes = 400;

/// No option or path pd takes is longer (PATH_MAX); longer arguments, and arguments with control
/// bytes, are refused before anything echoes them.
constexpr std::size_t longest_argument = 4096;

/// Empty if every argument is acceptable, else why not.
std::string argument_error(int argc, char** argv) {
  for (int k = 1; k < argc; ++k) {
    const std::string_view arg(argv[k]);
    if (arg.size() > longest_argument) {
      return fmt::format("argument {} is {} bytes long; none may exceed {}", k, arg.size(),
                         longest_argument);
    }
    if (std::any_of(arg.begin(), arg.end(),
                    [](char c) { return static_cast<unsigned char>(c) < 0x20 || c == 0x7F; })) {
      return fmt::format("argument {} ('{}') holds control characters", k, pd::printable(arg));
    }
  }
  return {};
}
} // namespace

int main(int argc, char** argv) {
  pd::restart_with_process_settings(argv);
  // Before anything slow (MPI, the scene): a stop request during set-up is not lost.
  pd::hold_stop_requests();
  // Under mpirun every rank runs this main; MPI lives as long as it (a no-op without MPI).
  const pd::MpiSession mpi(argc, argv);
  const bool split = pd::world_communicator().size() > 1;
  CLI::App app{"pd — bond-based peridynamics with its own verification"};
  app.require_subcommand(1);
  const std::vector<pd::cli::Command> commands = {
      pd::cli::add_run_command(app),       pd::cli::add_info_command(app),
      pd::cli::add_bench_command(app),     pd::cli::add_verify_command(app),
      pd::cli::add_stability_command(app), pd::cli::add_compare_command(app),
      pd::cli::add_section_command(app),
  };
  // Under mpirun a rank that stops alone would leave the others waiting in a collective call
  // forever: any rank's error, once said, ends the whole job.
  const auto fail = [split](int code) {
    if (split) {
      pd::MpiSession::abort(code);
    }
    return code;
  };
  if (const std::string why = argument_error(argc, argv); !why.empty()) {
    fmt::print(stderr, "error: {}\n", why);
    return fail(1);
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // A usage error is exit 1 like any bad input (CLI11's own codes are 104–114); help stays 0.
    // CLI11's message quotes the value given, which may be huge or hold control bytes.
    if (e.get_exit_code() == 0) {
      return app.exit(e);
    }
    fmt::print(stderr, "{}\nRun with --help for more information.\n",
               pd::printable_words(e.what()));
    return fail(1);
  }
  try {
    for (const auto& command : commands) {
      if (*command.app) {
        if (!command.stops_cleanly) {
          pd::release_stop_requests();
        }
        const int code = command.run();
        return code == 1 ? fail(code) : code; // 3 and 5 are reached by every rank together
      }
    }
  } catch (const pd::SceneError& e) {
    fmt::print(stderr, "{}\n", pd::printable_words(e.what(), long_word_bytes));
    return fail(1);
  } catch (const std::exception& e) {
    fmt::print(stderr, "error: {}{}\n",
               split ? fmt::format("rank {}: ", pd::world_communicator().rank()) : "",
               pd::printable_words(e.what(), long_word_bytes));
    return fail(1);
  }
  return 0;
}
