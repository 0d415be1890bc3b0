// pd verify [CASE...] [-o DIR] [--list [--json]] [--sweep [--quick]] [--scenes DIR] [--threads N]
// pd verify SCENE.yaml... [--fe-levels N] [--fe-coarse] [--gate FRACTION]
// Verification cases with their gates: CASE.json in DIR for each, exit code 2 if a gate fails.
// A scene file instead of a case name runs the scene beside its FE reference (pd-fem --scene).
// The cases are the folders of verification/cases (or $PD_CASES_DIR), read at run time.
#include "case_folders.hpp"
#include "commands.hpp"
#include "libpd/core/atomic_file.hpp"
#include "libpd/io/scene.hpp"
#include "scene_verification.hpp"
#include "verification.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fmt/format.h>
#include <memory>
#include <unistd.h>
#include <vector>

namespace pd::cli {

namespace {

struct VerifyArgs {
  std::vector<std::string> cases;
  std::string out_dir = "verification-out";
  bool list = false;
  bool json = false;
  bool sweep = false;
  bool quick = false;
  std::string scenes_dir;
  int threads = 0;
  verification::SceneVerifyOptions scene;
  int fe_levels = 0;
  double gate = 0;
};

bool is_scene_file(const std::string& arg) {
  const auto ext = std::filesystem::path(arg).extension();
  return ext == ".yaml" || ext == ".yml";
}

/// pd verify SCENE.yaml: the scene against its FE reference; exit 1 if it cannot run, 2 if the
/// gate fails.
int verify_scenes(const VerifyArgs& a, const verification::Context& ctx) {
  int failed = 0;
  for (const std::string& file : a.cases) {
    fmt::print("== {} — PD vs deal.II on the same continuum problem\n", file);
    std::fflush(stdout);
    const auto t0 = std::chrono::steady_clock::now();
    Json result;
    try {
      result = verification::verify_scene(file, ctx, a.scene);
    } catch (const SceneError& e) {
      fmt::print(stderr, "{}\n", e.what());
      return 1;
    } catch (const std::exception& e) {
      fmt::print(stderr, "error: {}\n", e.what());
      return 1;
    }
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    result["wall_seconds"] = wall;
    const std::string name = std::filesystem::path(file).stem().string();
    write_file_atomically(std::filesystem::path(a.out_dir) / (name + ".json"), result.dump());
    const bool passed = result.find("passed")->boolean().value_or(false);
    fmt::print("   {} in {:.1f} s -> {}/{}.json\n", passed ? "PASSED" : "FAILED", wall, a.out_dir,
               name);
    failed += passed ? 0 : 1;
  }
  return failed > 0 ? 2 : 0;
}

/// Run one case, write its JSON and say whether its gate passed.
bool run_case(const verification::Case& c, verification::Context ctx, const std::string& out_dir) {
  fmt::print("== {} — {}\n", c.name, c.summary);
  std::fflush(stdout);
  ctx.folder = c.folder->path;
  ctx.case_folder = c.folder;
  ctx.run = c.info;
  const auto t0 = std::chrono::steady_clock::now();
  Json result = c.run(ctx);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  result["wall_seconds"] = wall;
  write_file_atomically(std::filesystem::path(out_dir) / (c.name + ".json"), result.dump());
  const Json* verdict = result.find("passed");
  const bool passed = verdict != nullptr && verdict->boolean().value_or(false);
  fmt::print("   {} in {:.1f} s -> {}/{}.json\n", passed ? "PASSED" : "FAILED", wall, out_dir,
             c.name);
  return passed;
}

int verify(const VerifyArgs& a) {
  set_threads(a.threads);
  verification::Context ctx;
  ctx.scenes_dir = a.scenes_dir.empty() ? verification::default_scenes_dir()
                                        : std::filesystem::path(a.scenes_dir);
  ctx.output_dir = a.out_dir;
  ctx.quick = a.quick;
  ctx.progress = ::isatty(STDERR_FILENO) != 0;
  if (!a.list && !a.cases.empty() && std::all_of(a.cases.begin(), a.cases.end(), is_scene_file)) {
    VerifyArgs scene_args = a;
    if (a.fe_levels > 0) {
      scene_args.scene.fe_levels = a.fe_levels;
    }
    if (a.gate > 0) {
      scene_args.scene.gate = a.gate;
    }
    return verify_scenes(scene_args, ctx);
  }
  const verification::CaseSet set = verification::discover_cases(verification::default_cases_dir());
  const auto& cases = set.cases;
  if (a.list && a.json) {
    fmt::print("{}\n", verification::cases_json(set).dump());
    return 0;
  }
  if (a.list) {
    for (const auto& c : cases) {
      fmt::print("{:<20} {}\n", c.name, c.summary);
    }
    return 0;
  }
  std::vector<const verification::Case*> selected;
  for (const auto& case_name : a.cases) {
    // --sweep runs each named case's accuracy-vs-time sweep, the case CASE-sweep.
    const std::string name = a.sweep ? case_name + "-sweep" : case_name;
    auto it =
        std::find_if(cases.begin(), cases.end(), [&](const auto& c) { return c.name == name; });
    if (it == cases.end()) {
      fmt::print(stderr, "error: unknown verification case '{}' (see pd verify --list)\n", name);
      return 1;
    }
    selected.push_back(&*it);
  }
  if (selected.empty()) {
    for (const auto& c : cases) {
      selected.push_back(&c);
    }
  }
  int failed = 0;
  for (const auto* c : selected) {
    if (!run_case(*c, ctx, a.out_dir)) {
      ++failed;
    }
  }
  fmt::print("{} passed, {} failed\n", selected.size() - static_cast<std::size_t>(failed), failed);
  return failed > 0 ? 2 : 0;
}

} // namespace

Command add_verify_command(CLI::App& app) {
  auto a = std::make_shared<VerifyArgs>();
  auto* cmd = app.add_subcommand("verify", "Run verification cases; exit code 2 if a gate fails");
  cmd->add_option("cases", a->cases,
                  "case names (default: all), or scene files (.yaml) to verify against FE");
  cmd->add_option("-o,--output", a->out_dir, "output folder")->capture_default_str();
  cmd->add_flag("--list", a->list, "list the cases");
  cmd->add_flag("--json", a->json,
                "with --list: a JSON array, one object per case with its folder and metadata");
  cmd->add_flag("--quick", a->quick,
                "the default report's extent: with --sweep the case file's quick_sweep lists "
                "where it has them; rc-beam without its s0 sensitivity runs");
  cmd->add_flag("--sweep", a->sweep,
                "run the accuracy-vs-time sweep of each named case (the case CASE-sweep): one "
                "JSON row per run in DIR/CASE-sweep.jsonl");
  cmd->add_option("--scenes", a->scenes_dir, "folder with the shipped scenes");
  cmd->add_option("--fe-levels", a->fe_levels,
                  "scene files: number of FE meshes (pd-fem --levels; default its own)");
  cmd->add_flag("--fe-coarse", a->scene.fe_coarse, "scene files: pd-fem --coarse (quick check)");
  cmd->add_option("--gate", a->gate,
                  "scene files: fail (exit 2) if a probe's |PD − FE| / |FE| exceeds this fraction");
  add_threads_option(*cmd, a->threads);
  return {cmd, [a] { return verify(*a); }};
}

} // namespace pd::cli
