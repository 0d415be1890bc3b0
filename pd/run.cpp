// pd run SCENE [-o DIR] [--threads N] [--checkpoint-every N] [--checkpoint FILE] [--restart FILE]
// Run a scene: summary.json, probes.csv and VTU files in DIR, a short report on stdout.
#include "libpd/app/run.hpp"

#include "commands.hpp"
#include "libpd/app/interrupt.hpp"
#include "libpd/app/run_checkpoints.hpp"
#include "libpd/app/run_summary.hpp"
#include "libpd/core/communicator.hpp"
#include "libpd/core/text.hpp"
#include "libpd/core/threads.hpp"

#include <chrono>
#include <cstring>
#include <filesystem>
#include <fmt/format.h>
#include <memory>
#include <unistd.h>

namespace pd::cli {

namespace {

struct RunArgs {
  std::string scene;
  std::string out_dir = "out";
  int threads = 0;
  bool print_defaults = false;
  bool print_reference = false;
  std::size_t checkpoint_every = 0;
  std::string checkpoint;
  std::string restart;
  bool overwrite = false;
  std::string partition = "rcb";
};

void print_report(const RunArgs& a, const RunOptions& opt, const RunOutcome& out,
                  double scene_seconds) {
  if (out.restarted_from_step) {
    fmt::print("restarted from {} at step {}\n", a.restart, *out.restarted_from_step);
  }
  fmt::print(
      "{}: {} particles, {} bonds, {} steps of {:.4g} s (eq. 31 limit {:.4g} s), status {}\n",
      a.scene, out.particles, out.bonds, out.result.steps, out.result.dt, out.result.dt_stable,
      to_string(out.result.status));
  // Cost: set-up (scene, model, simulation) and solve separately, and the peak memory; then
  // what the solve did: throughput for the time steppers, the factorisation for static.
  fmt::print("set-up {:.3f} s (scene {:.3f} s, model {:.3f} s, simulation {:.3f} s), solve {:.3f} "
             "s, peak memory {:.1f} MiB, {} threads\n",
             out.setup_seconds + scene_seconds, scene_seconds, out.model_seconds,
             out.simulation_seconds, out.result.wall_seconds,
             static_cast<double>(peak_resident_bytes()) / (1024.0 * 1024.0),
             current_thread_count());
  if (out.summary.find("integrator_details") != nullptr) {
    fmt::print("{}\n", out.result.message); // static: solver, factor size, phase times
  } else {
    fmt::print(
        "{:.3g} bond updates/s\n",
        bond_updates_per_second(out.bonds, out.evaluations_this_run, out.result.wall_seconds));
  }
  for (const auto& [name, value] : out.probes) {
    fmt::print("  probe {:<20} {:.9g}\n", printable(name), value);
  }
  if (!a.out_dir.empty()) {
    fmt::print("results in {}/summary.json\n", a.out_dir);
  }
  if (!out.checkpoint.empty()) {
    // A split run's pieces are restarted by their common name, on as many ranks.
    const int ranks = opt.communicator != nullptr ? opt.communicator->size() : 1;
    const std::string restart =
        ranks > 1 ? checkpoint_base_path(opt).string() : out.checkpoint.string();
    fmt::print("checkpoint {} ({}step {}); to continue: {}pd run {} -o {} --restart {}{}\n",
               restart, ranks > 1 ? fmt::format("{} pieces, ", ranks) : "", out.checkpoint_step,
               ranks > 1 ? fmt::format("mpirun -np {} ", ranks) : "", a.scene, a.out_dir, restart,
               a.checkpoint_every > 0 ? fmt::format(" --checkpoint-every {}", a.checkpoint_every)
                                      : "");
  }
}

int run(const RunArgs& a) {
  if (a.print_defaults) {
    fmt::print("{}", scene_template());
    return 0;
  }
  if (a.print_reference) {
    fmt::print("{}", scene_reference());
    return 0;
  }
  if (a.scene.empty()) {
    fmt::print(stderr,
               "error: pd run needs a scene file (or --print-defaults, --print-scene-reference)\n");
    return 1;
  }
  set_threads(a.threads);
  const auto start = std::chrono::steady_clock::now();
  // Reading a scene can take minutes (Gmsh meshing a CAD part) and cannot poll a stop request;
  // the output folder is not claimed yet, so an abandoned read writes nothing there.
  const Scene scene = [&a] {
    const AbandonOnInterrupt abandon([&a](int sig) {
      fmt::print(stderr,
                 "pd run: interrupted by signal {} ({}) while reading {}: nothing written\n", sig,
                 ::strsignal(sig), a.scene);
    });
    return load_or_explain(a.scene);
  }();
  RunOptions opt;
  opt.scene_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  opt.output_dir = a.out_dir;
  opt.progress = ::isatty(STDERR_FILENO) != 0;
  opt.checkpoint_every = a.checkpoint_every;
  opt.checkpoint = a.checkpoint;
  opt.restart = a.restart;
  opt.overwrite = a.overwrite;
  opt.on_warning = [](const std::string& w) { fmt::print(stderr, "warning: {}\n", w); };
  // Under mpirun the run is split over the ranks (app/run_options.hpp); rank 0 reports.
  const Communicator& world = world_communicator();
  opt.communicator = &world;
  opt.partition = from_name<PartitionMethod>(a.partition).value_or(PartitionMethod::rcb);
  opt.progress = opt.progress && world.root();
  const RunOutcome out = run_scene(scene, opt);
  if (!world.root()) {
    return out.result.status == RunStatus::unstable      ? 3
           : out.result.status == RunStatus::interrupted ? exit_interrupted
                                                         : 0;
  }
  print_report(a, opt, out, opt.scene_seconds);
  if (const Json* d = out.summary.find("distribution"); d != nullptr) {
    fmt::print("split over {} MPI ranks ({} partition): summary.json `distribution` has the "
               "particles, halo, memory and halo bytes per step of each rank\n",
               world.size(), a.partition);
  }
  if (!out.checkpoint_note.empty()) {
    fmt::print(stderr, "warning: {}\n", out.checkpoint_note);
  }
  if (out.result.status == RunStatus::unstable) {
    fmt::print(stderr, "error: {}\n", out.result.message);
    return 3;
  }
  if (out.result.status == RunStatus::interrupted) {
    fmt::print(stderr, "interrupted{}: the results so far are written\n",
               out.stop_signal ? fmt::format(" by signal {} ({})", out.stop_signal,
                                             ::strsignal(out.stop_signal))
                               : "");
    return exit_interrupted;
  }
  return 0;
}

} // namespace

Command add_run_command(CLI::App& app) {
  auto a = std::make_shared<RunArgs>();
  auto* cmd =
      app.add_subcommand("run", "Run a scene: writes DIR/summary.json, probes.csv and VTU files");
  cmd->add_option("scene", a->scene, "scene file (YAML)");
  cmd->add_option("-o,--output", a->out_dir, "output folder")->capture_default_str();
  add_threads_option(*cmd, a->threads);
  cmd->add_flag("--print-defaults", a->print_defaults, "print a commented scene template and exit");
  cmd->add_flag("--print-scene-reference", a->print_reference,
                "print the scene reference (Markdown, docs/scene-reference.md) and exit");
  add_count_option(*cmd, "--checkpoint-every", a->checkpoint_every,
                   "write the complete run state every N steps (atomically; also at the end and "
                   "on Ctrl-C); 0: only then",
                   0);
  cmd->add_option("--checkpoint", a->checkpoint,
                  "checkpoint file (default: OUTDIR/checkpoint.pdcp)");
  cmd->add_flag("--overwrite", a->overwrite,
                "reuse an output folder that holds another run's files: first remove exactly the "
                "files its manifest.txt lists");
  cmd->add_option("--partition", a->partition,
                  "under mpirun: how particles are split over the ranks")
      ->check(CLI::IsMember(enum_word_list<PartitionMethod>()))
      ->capture_default_str();
  cmd->add_option("--restart", a->restart,
                  "continue from a checkpoint of the same scene; the result is bitwise that of an "
                  "uninterrupted run (under mpirun: the name given to --checkpoint, or "
                  "OUTDIR/checkpoint.pdcp; a set written on any number of ranks is read)")
      ->check(CLI::Validator(
          [](const std::string& path) {
            // Only that a set is there: which one, and what kind of file, the library says
            // (checkpoint_set_ranks, the checkpoint reader). Not collective: every rank sees
            // the same folder, so all accept or all refuse.
            std::error_code ec; // e.g. a name too long: said, not thrown out of the parser
            if (std::filesystem::exists(path, ec) || !checkpoint_sets_on_disk(path).empty()) {
              return std::string{};
            }
            if (ec) {
              return path + ": " + ec.message();
            }
            const std::filesystem::path base(path);
            return "File does not exist: " + path + " (nor the pieces " + base.stem().string() +
                   "-rRRRRofNNNN" + base.extension().string() +
                   " of a set written on several ranks)";
          },
          "FILE"));
  return {cmd, [a] { return run(*a); }, true};
}

} // namespace pd::cli
