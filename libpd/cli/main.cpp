// pd — the libpd command line.
//
//   pd run SCENE [-o DIR] [--threads N]       run a scene, write summary.json, probes.csv, VTU
//          [--checkpoint-every N] [--checkpoint FILE] [--restart FILE]
//   pd info SCENE [--json]                    sizes, memory estimate, stable time step
//   pd bench SCENE [--steps N] [--threads N]  force-evaluation throughput
//   pd verify [CASE...] [-o DIR] [--list]     verification cases with their gates
//   pd stability SCENE... [--integrator X]    measured vs predicted stable time steps
//   pd compare dynamic|quasistatic [-o F]     integrator cost/accuracy rows (JSON lines)
//   pd section SCENE [--depth z] [--plate]    PD/continuum stiffness of a beam or plate section
//
// Exit codes: 0 success, 1 bad input or usage, 2 a verification gate failed, 3 the run became
// unstable.
#include "libpd/discretisation/corrections.hpp"
#include "libpd/kernel/force_kernel.hpp"
#include "libpd/io/resources.hpp"
#include "libpd/app/run.hpp"
#include "libpd/io/scene.hpp"
#include "libpd/time/stability.hpp"
#include "libpd/kernel/stable_time_step.hpp"
#include "section_stiffness.hpp"
#include "verification.hpp"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fmt/format.h>
#include <fstream>
#include <iostream>
#include <numbers>
#include <optional>
#include <unistd.h>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace {

void set_threads(int threads) {
#ifdef _OPENMP
  if (threads > 0) {
    omp_set_num_threads(threads);
  }
#else
  (void)threads;
#endif
}

int thread_count() {
#ifdef _OPENMP
  return omp_get_max_threads();
#else
  return 1;
#endif
}

pd::Scene load_or_explain(const std::string& path) {
  pd::Scene scene = pd::load_scene(path);
  for (const auto& w : scene.warnings) {
    fmt::print(stderr, "{}\n", w);
  }
  return scene;
}

struct CheckpointArgs {
  std::size_t every = 0;
  std::string file;
  std::string restart;
};

int cmd_run(const std::string& scene_path, const std::string& out_dir, int threads,
            const CheckpointArgs& ck) {
  set_threads(threads);
  const pd::Scene scene = load_or_explain(scene_path);
  pd::RunOptions opt;
  opt.output_dir = out_dir;
  opt.progress = ::isatty(STDERR_FILENO) != 0;
  opt.checkpoint_every = ck.every;
  opt.checkpoint = ck.file;
  opt.restart = ck.restart;
  const pd::RunOutcome out = pd::run_scene(scene, opt);
  if (out.restarted_from_step) {
    fmt::print("restarted from {} at step {}\n", ck.restart, *out.restarted_from_step);
  }
  fmt::print(
      "{}: {} particles, {} bonds, {} steps of {:.4g} s (eq. 31 limit {:.4g} s), status {}\n",
      scene_path, out.particles, out.bonds, out.result.steps, out.result.dt, out.result.dt_stable,
      pd::to_string(out.result.status));
  fmt::print(
      "wall {:.3f} s, {:.3g} bond updates/s, {} threads\n", out.result.wall_seconds,
      pd::bond_updates_per_second(out.bonds, out.result.force_evaluations, out.result.wall_seconds),
      thread_count());
  for (const auto& [name, value] : out.probes) {
    fmt::print("  probe {:<20} {:.9g}\n", name, value);
  }
  if (!out_dir.empty()) {
    fmt::print("results in {}/summary.json\n", out_dir);
  }
  if (!out.checkpoint.empty()) {
    fmt::print("checkpoint {} (step {}); to continue: pd run {} -o {} --restart {}{}\n",
               out.checkpoint.string(), out.checkpoint_step, scene_path, out_dir,
               out.checkpoint.string(),
               ck.every > 0 ? fmt::format(" --checkpoint-every {}", ck.every) : "");
  }
  if (!out.checkpoint_note.empty()) {
    fmt::print(stderr, "warning: {}\n", out.checkpoint_note);
  }
  if (out.result.status == pd::RunStatus::unstable) {
    fmt::print(stderr, "error: {}\n", out.result.message);
    return 3;
  }
  return 0;
}

/// Section stiffness of the scene's first body (section_stiffness.hpp), for the scene's own
/// corrections or for every pair: the a-priori part of a bending structure's error budget.
int cmd_section(const std::string& scene_path, const std::string& span, const std::string& depth,
                bool plate, bool all_pairs, bool json) {
  const pd::Scene scene = pd::load_scene(scene_path);
  if (span == depth) {
    fmt::print(stderr, "error: --span and --depth must be different axes\n");
    return 1;
  }
  std::vector<std::pair<pd::SurfaceCorrection, pd::VolumeCorrection>> pairs;
  if (all_pairs) {
    for (auto sc : pd::all_surface_corrections) {
      for (auto vc : pd::all_volume_corrections) {
        pairs.emplace_back(sc, vc);
      }
    }
  } else {
    pairs.emplace_back(scene.model.surface_correction, scene.model.volume_correction);
  }
  if (!json) {
    fmt::print("{}: section of body '{}', span {}, depth {}{}; PD / continuum stiffness\n",
               scene_path, scene.model.bodies.front().name, span, depth,
               plate ? ", plate (long in the third axis too)" : "");
    fmt::print("{:<30} {:>9} {:>9} {:>9}\n", "surface + volume correction", "bending", "shear",
               "axial");
  }
  for (const auto& [sc, vc] : pairs) {
    pd::ModelSpec spec = scene.model;
    spec.surface_correction = sc;
    spec.volume_correction = vc;
    const auto s = pd::verification::section_stiffness(spec, spec.bodies.front(),
                                                       pd::verification::axis_of(span),
                                                       pd::verification::axis_of(depth), plate);
    const std::string name = fmt::format("{} + {}", pd::to_string(sc), pd::to_string(vc));
    if (json) {
      pd::Json j;
      j["surface_correction"] = pd::to_string(sc);
      j["volume_correction"] = pd::to_string(vc);
      j["bending"] = s.bending;
      j["shear"] = s.shear;
      j["membrane"] = s.membrane;
      j["section_particles"] = s.section_particles;
      fmt::print("{}", j.dump(0)); // dump ends the line
    } else {
      fmt::print("{:<30} {:>9.4f} {:>9.4f} {:>9.4f}\n", name, s.bending, s.shear, s.membrane);
    }
  }
  return 0;
}

int cmd_info(const std::string& scene_path, bool json) {
  const pd::Scene scene = load_or_explain(scene_path);
  // The estimate the scene parser's memory guard used, shown beside the actual numbers so that
  // its accuracy can be checked on any scene.
  const pd::ResourceEstimate est = pd::estimate_resources(scene.model, scene.solver);
  const auto budget = pd::available_memory();
  const pd::Model model = pd::build_model(scene.model);
  const double dt = pd::stable_time_step(model);
  const double per_particle = 2.0 * static_cast<double>(model.family.bond_count()) /
                              static_cast<double>(std::max<std::size_t>(model.size(), 1));
  pd::Json j;
  j["scene"] = scene_path;
  j["particles"] = model.size();
  j["bonds"] = model.family.bond_count();
  j["bonds_per_particle"] = per_particle;
  j["horizon"] = model.horizon();
  j["memory_bytes"] = model.memory_bytes();
  j["memory_estimate_bytes"] = est.model_bytes;
  j["estimate_particles"] = est.particles;
  j["estimate_bonds"] = est.bonds;
  j["estimate_total_bytes"] = est.bytes;
  if (budget) {
    j["memory_available_bytes"] = budget->bytes;
  }
  j["dt_stable"] = dt;
  j["effects"] = pd::Json::array_of(model.effects.names());
  if (json) {
    fmt::print("{}", j.dump());
    return 0;
  }
  fmt::print("scene              {}\n", scene_path);
  fmt::print("                   {:>14} {:>14}\n", "actual", "estimate");
  fmt::print("particles          {:>14} {:>14.0f}\n", model.size(), est.particles);
  fmt::print("bonds              {:>14} {:>14.0f}\n", model.family.bond_count(), est.bonds);
  fmt::print("bonds per particle {:>14.2f} {:>14.2f} (family size, both directions; estimate: "
             "bulk)\n",
             per_particle, est.bonds_per_particle);
  fmt::print("model memory       {:>14} {:>14}\n",
             pd::format_bytes(static_cast<double>(model.memory_bytes())),
             pd::format_bytes(est.model_bytes));
  fmt::print("memory guard       {:>14} {:>14} (estimate with integrator and build transients; "
             "{})\n",
             "", pd::format_bytes(est.bytes),
             budget
                 ? fmt::format("{} available, {}", pd::format_bytes(budget->bytes), budget->source)
                 : std::string("available memory unknown"));
  fmt::print("horizon            {:.6g} m\n", model.horizon());
  fmt::print("stable dt (eq. 31) {:.6g} s\n", dt);
  fmt::print("effects            {}\n", fmt::join(model.effects.names(), ", "));
  return 0;
}

int cmd_bench(const std::string& scene_path, std::size_t steps, int threads, bool json,
              const std::string& stretch, int repeats) {
  set_threads(threads);
  pd::Scene scene = load_or_explain(scene_path);
  if (!stretch.empty()) {
    scene.model.effects.stretch = *pd::from_name<pd::StretchKind>(stretch);
  }
  pd::Model model = pd::build_model(scene.model);
  auto forces = pd::make_force_evaluator(model);
  // A small smooth deformation so that every bond is stretched (no special zero-stretch path).
  std::vector<double> y(3 * model.size()), b(3 * model.size());
  for (std::size_t i = 0; i < model.size(); ++i) {
    for (int c = 0; c < 3; ++c) {
      const double x = model.particles.position[i][c];
      y[3 * i + c] = x + 1e-4 * std::sin(3.0 * x + c);
    }
  }
  forces->compute(y.data(), b.data()); // warm-up: page in every array
  std::vector<double> seconds;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    for (std::size_t s = 0; s < steps; ++s) {
      forces->compute(y.data(), b.data());
    }
    seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  std::sort(seconds.begin(), seconds.end());
  const double median = seconds[seconds.size() / 2];
  const double rate = pd::bond_updates_per_second(model.family.bond_count(), steps, median);
  pd::Json j;
  j["scene"] = scene_path;
  j["kernel"] = forces->description();
  j["threads"] = thread_count();
  j["particles"] = model.size();
  j["bonds"] = model.family.bond_count();
  j["steps"] = steps;
  j["repeats"] = repeats;
  j["seconds"] = median;
  j["seconds_all"] = pd::Json::array_of(seconds);
  j["bond_updates_per_second"] = rate;
  if (json) {
    fmt::print("{}", j.dump());
  } else {
    fmt::print("{}: {} particles, {} bonds, kernel {}, {} threads\n", scene_path, model.size(),
               model.family.bond_count(), forces->description(), thread_count());
    fmt::print("{} evaluations: median {:.4f} s of {} repeats -> {:.4g} bond updates/s\n", steps,
               median, repeats, rate);
  }
  return 0;
}

int cmd_verify(const std::vector<std::string>& names, const std::string& out_dir, bool list,
               const std::string& scenes_dir, int threads) {
  set_threads(threads);
  const auto& cases = pd::verification::all_cases();
  if (list) {
    for (const auto& c : cases) {
      fmt::print("{:<20} {}\n", c.name, c.summary);
    }
    return 0;
  }
  pd::verification::Context ctx;
  ctx.scenes_dir = scenes_dir.empty() ? pd::verification::default_scenes_dir()
                                      : std::filesystem::path(scenes_dir);
  ctx.output_dir = out_dir;
  ctx.progress = ::isatty(STDERR_FILENO) != 0;
  std::vector<const pd::verification::Case*> selected;
  for (const auto& name : names) {
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
    fmt::print("== {} — {}\n", c->name, c->summary);
    std::fflush(stdout);
    const auto t0 = std::chrono::steady_clock::now();
    pd::Json result = c->run(ctx);
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    result["wall_seconds"] = wall;
    pd::write_file_atomically(std::filesystem::path(out_dir) / (c->name + ".json"), result.dump());
    const pd::Json* verdict = result.find("passed");
    const bool passed = verdict != nullptr && verdict->boolean().value_or(false);
    fmt::print("   {} in {:.1f} s -> {}/{}.json\n", passed ? "PASSED" : "FAILED", wall, out_dir,
               c->name);
    if (!passed) {
      ++failed;
    }
  }
  fmt::print("{} passed, {} failed\n", selected.size() - static_cast<std::size_t>(failed), failed);
  return failed > 0 ? 2 : 0;
}

// ---- pd stability ----------------------------------------------------------------------------

std::optional<pd::StabilityTarget> parse_target(const std::string& word) {
  pd::StabilityTarget t;
  // Fixed-step integrators by their own word; adr has no stable step to measure.
  if (const auto kind = pd::from_name<pd::IntegratorKind>(word);
      kind && *kind != pd::IntegratorKind::adr && *kind != pd::IntegratorKind::arkode) {
    t.kind = *kind;
    return t;
  }
  const std::string name = word.starts_with("arkode:") ? word.substr(7) : word;
  if (const auto table = pd::from_name<pd::ArkodeTable>(name)) {
    t.kind = pd::IntegratorKind::arkode;
    t.table = *table;
    return t;
  }
  return std::nullopt;
}

int cmd_stability(const std::vector<std::string>& scenes, std::vector<std::string> integrators,
                  std::size_t steps, double tolerance, double gate, bool json, int threads) {
  set_threads(threads);
  if (integrators.empty()) {
    integrators.push_back("verlet");
    if (pd::arkode_available()) {
      for (const std::string_view table : pd::enum_words<pd::ArkodeTable>) {
        integrators.push_back("arkode:" + std::string(table));
      }
    }
  }
  std::vector<pd::StabilityTarget> targets;
  for (const auto& w : integrators) {
    auto t = parse_target(w);
    if (!t) {
      fmt::print(stderr,
                 "error: unknown integrator '{}' (verlet, euler-cromer, damped-euler or "
                 "arkode:TABLE)\n",
                 w);
      return 1;
    }
    if (t->kind == pd::IntegratorKind::arkode && !pd::arkode_available()) {
      fmt::print(stderr, "error: '{}' needs SUNDIALS, which this build lacks\n", w);
      return 1;
    }
    targets.push_back(*t);
  }
  pd::StabilityOptions opt;
  opt.steps = steps;
  opt.relative_tolerance = tolerance;
  pd::Json rows = pd::Json::array();
  std::vector<std::string> gate_failures;
  if (!json) {
    fmt::print("{:<16} {:<24} {:>6} {:>10} {:>10} {:>10} {:>7} {:>7} {:>10} {:>7} {:>4} {:>6}\n",
               "case", "integrator", "beta", "measured", "eq31", "sharp", "m/sharp", "m/eq31",
               "sharp_N", "m/shN", "runs", "wall");
  }
  for (const auto& path : scenes) {
    const pd::Scene scene = load_or_explain(path);
    const pd::Model model = pd::build_model(pd::stability_model(scene.model));
    const pd::FrequencyEstimate freq = pd::max_frequency(model);
    const std::string name = std::filesystem::path(path).stem().string();
    for (const auto& t : targets) {
      const pd::StabilityResult r = pd::measure_stability(scene.model, scene.solver, t, opt, freq.omega_max);
      pd::Json j;
      j["case"] = name;
      j["scene"] = path;
      j["integrator"] = r.integrator;
      j["interval"] = r.interval;
      j["omega_max"] = r.omega_max;
      j["lanczos_iterations"] = freq.iterations;
      j["measured_dt"] = r.measured;
      j["unstable_dt"] = r.unstable;
      j["eq31_dt"] = r.eq31;
      j["sharp_dt"] = r.sharp;
      j["interval_finite_horizon"] = r.interval_finite;
      j["sharp_finite_horizon_dt"] = r.sharp_finite;
      j["measured_over_sharp"] = r.sharp > 0 ? r.measured / r.sharp : 0.0;
      j["measured_over_sharp_finite_horizon"] = r.measured / r.sharp_finite;
      j["measured_over_eq31"] = r.measured / r.eq31;
      j["steps_per_run"] = opt.steps;
      j["runs"] = r.runs;
      j["wall_seconds"] = r.seconds;
      if (gate > 0) {
        // The prediction the bounded run can be held to is the finite-horizon one; for Verlet
        // the measured limit must also respect the conservative eq. 31 bound.
        const double ratio = r.measured / r.sharp_finite;
        if (!(std::abs(ratio - 1.0) <= gate)) {
          gate_failures.push_back(
              fmt::format("{} {}: measured / predicted = {:.4f}", name, r.integrator, ratio));
        }
        if (t.kind != pd::IntegratorKind::arkode && r.measured < r.eq31) {
          gate_failures.push_back(fmt::format("{} {}: measured {:.4e} s below eq. 31 {:.4e} s",
                                              name, r.integrator, r.measured, r.eq31));
        }
      }
      if (json) {
        rows.push_back(j);
      } else {
        fmt::print("{:<16} {:<24} {:>6.4f} {:>10.4e} {:>10.4e} {:>10.4e} {:>7.4f} {:>7.4f} "
                   "{:>10.4e} {:>7.4f} {:>4} {:>5.0f}s\n",
                   name, r.integrator, r.interval, r.measured, r.eq31, r.sharp,
                   r.sharp > 0 ? r.measured / r.sharp : 0.0, r.measured / r.eq31, r.sharp_finite,
                   r.measured / r.sharp_finite, r.runs, r.seconds);
        std::fflush(stdout);
      }
    }
  }
  if (json) {
    fmt::print("{}\n", rows.dump());
  }
  if (!gate_failures.empty()) {
    fmt::print(stderr, "stability gate ({:.0f} %) failed:\n", 100 * gate);
    for (const auto& f : gate_failures) {
      fmt::print(stderr, "  {}\n", f);
    }
    return 4;
  }
  return 0;
}

// ---- pd compare ------------------------------------------------------------------------------

struct CompareConfig {
  pd::IntegratorKind kind;
  pd::ArkodeTable table = pd::ArkodeTable::rk4;
  bool adaptive = false;
  double dt_factor = 0; ///< × eq. 31 × stability scale; 0: the scene's dt
  double rtol = 1e-6;
};

std::string config_table(const CompareConfig& c) {
  return c.kind == pd::IntegratorKind::arkode ? pd::to_string(c.table) : std::string("-");
}

pd::Scene configured(const pd::Scene& base, const CompareConfig& c, double eq31) {
  pd::Scene s = base;
  s.solver.integrator = c.kind;
  s.solver.arkode.table = c.table;
  s.solver.arkode.adaptive = c.adaptive;
  s.solver.arkode.rtol = c.rtol;
  s.output.vtu = false;
  if (c.dt_factor > 0) {
    double scale = 1.0;
    if (c.kind == pd::IntegratorKind::arkode) {
      const double beta = pd::imaginary_stability_interval(pd::butcher_tableau(c.table));
      scale = beta > 0 ? 0.5 * beta : 0.5;
    }
    s.solver.dt = c.dt_factor * eq31 * scale;
  }
  if (c.kind == pd::IntegratorKind::euler_cromer || c.kind == pd::IntegratorKind::verlet) {
    s.solver.damping = 0; // undamped schemes; ADR ignores c_v, arkode uses it
    s.model.effects.damping = false;
  }
  return s;
}

int cmd_compare(const std::string& which, const std::string& out_file,
                const std::string& scenes_dir, bool quick, int threads) {
  set_threads(threads);
  const std::filesystem::path dir = scenes_dir.empty() ? pd::verification::default_scenes_dir()
                                                       : std::filesystem::path(scenes_dir);
  std::ofstream out;
  if (!out_file.empty()) {
    out.open(out_file);
    if (!out) {
      fmt::print(stderr, "error: cannot write {}\n", out_file);
      return 1;
    }
  }
  auto emit = [&](const pd::Json& row) {
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
  std::vector<pd::ArkodeTable> tables;
  if (pd::arkode_available()) {
    for (int i = 0; i < pd::arkode_table_count; ++i) {
      tables.push_back(static_cast<pd::ArkodeTable>(i));
    }
  }

  if (which == "dynamic") {
    const pd::Scene base = pd::load_scene((dir / "bar-vibration.yaml").string());
    const pd::Model probe_model = pd::build_model(base.model);
    const double eq31 = pd::stable_time_step(probe_model);
    const pd::Material& steel = base.model.materials.front();
    const double wave_speed = std::sqrt(steel.youngs_modulus / steel.density);
    const double strain = base.initial.displacement_gradient[0][0];
    const double length = 1.0;
    const double x_probe = base.probes.front().point[0];
    const double sample = 10 * base.solver.dt.value_or(eq31); // the case's sampling interval
    auto run = [&](const CompareConfig& c) {
      pd::Scene s = configured(base, c, eq31);
      const double dt = s.solver.dt.value_or(eq31);
      s.output.history_every = std::max<std::size_t>(1, static_cast<std::size_t>(sample / dt));
      pd::RunOptions opt;
      return std::pair{s, pd::run_scene(s, opt)};
    };
    // Reference PD solution (temporal error only): Dormand–Prince at 1/20 of its stable step.
    std::vector<double> ref_t, ref_u;
    if (!tables.empty()) {
      CompareConfig rc{pd::IntegratorKind::arkode, pd::ArkodeTable::dormand_prince, false,
                       quick ? 0.2 : 0.05};
      pd::Scene s = configured(base, rc, eq31);
      s.output.history_every = 1;
      const pd::RunOutcome ro = pd::run_scene(s, pd::RunOptions{});
      for (std::size_t r = 0; r < ro.history.time.size(); ++r) {
        ref_t.push_back(ro.history.time[r]);
        ref_u.push_back(ro.history.values[r][0]);
      }
    }
    auto reference_at = [&](double t) {
      const auto it = std::lower_bound(ref_t.begin(), ref_t.end(), t);
      if (it == ref_t.begin()) {
        return ref_u.front();
      }
      if (it == ref_t.end()) {
        return ref_u.back();
      }
      const std::size_t k = static_cast<std::size_t>(it - ref_t.begin());
      const double w = (t - ref_t[k - 1]) / (ref_t[k] - ref_t[k - 1]);
      return (1 - w) * ref_u[k - 1] + w * ref_u[k];
    };
    std::vector<CompareConfig> configs;
    const std::vector<double> factors =
        quick ? std::vector<double>{0.9, 0.45} : std::vector<double>{0.9, 0.45, 0.225, 0.1125};
    for (double f : factors) {
      configs.push_back({pd::IntegratorKind::verlet, pd::ArkodeTable::rk4, false, f});
    }
    for (auto t : tables) {
      if (t == pd::ArkodeTable::heun_euler) {
        continue; // no imaginary-axis stability interval: undamped runs grow for any Δt
      }
      // --quick keeps one table per order class (3, 4, 5), which is what the report plots.
      if (quick && t != pd::ArkodeTable::bogacki_shampine && t != pd::ArkodeTable::rk4 &&
          t != pd::ArkodeTable::dormand_prince) {
        continue;
      }
      for (double f : factors) {
        configs.push_back({pd::IntegratorKind::arkode, t, false, f});
      }
    }
    for (const auto& c : configs) {
      const auto [s, ro] = run(c);
      double rms = 0, rms_ref = 0;
      const std::size_t n = ro.history.time.size();
      for (std::size_t r = 0; r < n; ++r) {
        const double t = ro.history.time[r];
        const double u = ro.history.values[r][0];
        const double e =
            u - pd::verification::bar_modal_series(x_probe, t, strain, length, wave_speed);
        rms += e * e;
        if (!ref_t.empty()) {
          const double er = u - reference_at(t);
          rms_ref += er * er;
        }
      }
      const double norm = strain * length;
      pd::Json j;
      j["case"] = "bar-vibration";
      j["integrator"] = pd::to_string(c.kind);
      j["table"] = config_table(c);
      j["dt"] = ro.result.dt;
      j["dt_over_eq31"] = ro.result.dt / eq31;
      j["error"] = std::sqrt(rms / static_cast<double>(std::max<std::size_t>(n, 1))) / norm;
      j["error_vs_reference_pd"] =
          ref_t.empty()
              ? 0.0
              : std::sqrt(rms_ref / static_cast<double>(std::max<std::size_t>(n, 1))) / norm;
      j["error_measure"] = "free-end history RMS / (eps L)";
      j["force_evaluations"] = ro.result.force_evaluations;
      j["wall_seconds"] = ro.result.wall_seconds;
      j["steps"] = ro.result.steps;
      j["status"] = pd::to_string(ro.result.status);
      emit(j);
    }
    return 0;
  }
  if (which == "quasistatic") {
    const pd::Scene base = pd::load_scene((dir / "clamped-beam.yaml").string());
    std::vector<CompareConfig> configs = {
        {pd::IntegratorKind::damped_euler},
        {pd::IntegratorKind::adr},
    };
    for (auto t : {pd::ArkodeTable::rk4, pd::ArkodeTable::bogacki_shampine}) {
      if (pd::arkode_available()) {
        configs.push_back({pd::IntegratorKind::arkode, t});
      }
    }
    // Adaptive Dormand–Prince needs ~16× the force evaluations of damped-euler here (72,863 vs
    // 4,600): it is part of the full comparison, not of --quick.
    if (pd::arkode_available() && !quick) {
      configs.push_back(
          {pd::IntegratorKind::arkode, pd::ArkodeTable::dormand_prince, true, 0, 1e-6});
    }
    double reference = 0;
    for (const auto& c : configs) {
      const pd::Scene s = configured(base, c, 0);
      const pd::RunOutcome ro = pd::run_scene(s, pd::RunOptions{});
      const double w =
          ro.probes.count("midspan_deflection") ? ro.probes.at("midspan_deflection") : 0.0;
      if (c.kind == pd::IntegratorKind::damped_euler) {
        reference = w;
      }
      pd::Json j;
      j["case"] = "clamped-beam";
      j["integrator"] = pd::to_string(c.kind);
      j["table"] = config_table(c);
      j["adaptive"] = c.adaptive;
      j["dt"] = ro.result.dt;
      j["midspan_deflection"] = w;
      j["error"] = reference != 0 ? std::abs(w - reference) / std::abs(reference) : 0.0;
      j["error_measure"] = "|w - w(damped-euler)| / |w(damped-euler)|";
      j["force_tolerance"] = s.solver.steady.force_tolerance;
      j["residual"] = ro.result.residual;
      j["force_evaluations"] = ro.result.force_evaluations;
      j["wall_seconds"] = ro.result.wall_seconds;
      j["steps"] = ro.result.steps;
      j["internal_steps"] = ro.result.internal_steps;
      j["status"] = pd::to_string(ro.result.status);
      emit(j);
    }
    return 0;
  }
  fmt::print(stderr, "error: pd compare needs 'dynamic' or 'quasistatic'\n");
  return 1;
}

} // namespace

int main(int argc, char** argv) {
  CLI::App app{"pd — bond-based peridynamics with its own verification"};
  app.require_subcommand(1);
  int threads = 0;

  std::string scene, out_dir = "out";
  bool print_defaults = false;
  auto* run =
      app.add_subcommand("run", "Run a scene: writes DIR/summary.json, probes.csv and VTU files");
  run->add_option("scene", scene, "scene file (YAML)");
  run->add_option("-o,--output", out_dir, "output folder")->capture_default_str();
  run->add_option("--threads", threads, "OpenMP threads (default: all)");
  run->add_flag("--print-defaults", print_defaults, "print a commented scene template and exit");
  CheckpointArgs ckpt;
  run->add_option("--checkpoint-every", ckpt.every,
                  "write the complete run state every N steps (atomically; also at the end and "
                  "on Ctrl-C)");
  run->add_option("--checkpoint", ckpt.file, "checkpoint file (default: OUTDIR/checkpoint.pdcp)");
  run->add_option("--restart", ckpt.restart,
                  "continue from a checkpoint of the same scene; the result is bitwise that of an "
                  "uninterrupted run")
      ->check(CLI::ExistingFile);

  bool json = false;
  auto* info = app.add_subcommand("info", "Particles, bonds, memory estimate and stable time step");
  info->add_option("scene", scene, "scene file (YAML)")->required();
  info->add_flag("--json", json, "machine-readable output");

  std::size_t steps = 100;
  std::string stretch;
  int repeats = 5;
  auto* bench =
      app.add_subcommand("bench", "Force-evaluation throughput (bond updates per second)");
  bench->add_option("scene", scene, "scene file (YAML)")->required();
  bench->add_option("--steps", steps, "force evaluations per repeat")->capture_default_str();
  bench->add_option("--repeats", repeats, "repeats; the median is reported")->capture_default_str();
  bench->add_option("--threads", threads, "OpenMP threads (default: all)");
  bench->add_option("--stretch", stretch, "override the stretch measure")
      ->check(CLI::IsMember(pd::enum_word_list<pd::StretchKind>()));
  bench->add_flag("--json", json, "machine-readable output");

  std::vector<std::string> cases;
  bool list = false;
  std::string scenes_dir;
  std::string verify_out = "verification-out";
  auto* verify =
      app.add_subcommand("verify", "Run verification cases; exit code 2 if a gate fails");
  verify->add_option("cases", cases, "case names (default: all)");
  verify->add_option("-o,--output", verify_out, "output folder")->capture_default_str();
  verify->add_flag("--list", list, "list the cases");
  bool sweep = false;
  verify->add_flag("--sweep", sweep,
                   "run the accuracy-vs-time sweep of each named case (the case CASE-sweep): one "
                   "JSON row per run in DIR/CASE-sweep.jsonl");
  verify->add_option("--scenes", scenes_dir, "folder with the shipped scenes");
  verify->add_option("--threads", threads, "OpenMP threads (default: all)");

  std::vector<std::string> stability_scenes, stability_integrators;
  std::size_t stability_steps = 1000;
  double stability_tolerance = 0.01;
  auto* stability = app.add_subcommand(
      "stability", "Largest stable fixed time step, measured by bisection, beside eq. 31 and the "
                   "sharp prediction from the largest frequency of the linearised operator");
  stability->add_option("scenes", stability_scenes, "scene files (YAML)")->required();
  stability->add_option("--integrator", stability_integrators,
                        "verlet, euler-cromer, damped-euler or arkode:TABLE (repeatable; default: "
                        "verlet and every offered table)");
  stability->add_option("--steps", stability_steps, "steps of each bounded run")
      ->capture_default_str();
  stability->add_option("--tolerance", stability_tolerance, "relative bisection tolerance")
      ->capture_default_str();
  double stability_gate = 0;
  stability->add_option("--gate", stability_gate,
                        "exit with status 4 unless every measured limit is within this fraction "
                        "of the finite-horizon prediction (and, for Verlet, not below eq. 31)");
  stability->add_flag("--json", json, "machine-readable output");
  stability->add_option("--threads", threads, "OpenMP threads (default: all)");

  std::string compare_what, compare_out;
  bool compare_quick = false;
  auto* compare = app.add_subcommand(
      "compare", "Integrator comparison rows (JSON lines): 'dynamic' = bar-vibration error vs "
                 "cost, 'quasistatic' = clamped-beam cost to steady state");
  compare->add_option("what", compare_what, "dynamic | quasistatic")
      ->required()
      ->check(CLI::IsMember({"dynamic", "quasistatic"}));
  compare->add_option("-o,--output", compare_out, "also write the rows to this .jsonl file");
  compare->add_option("--scenes", scenes_dir, "folder with the shipped scenes");
  compare->add_flag("--quick", compare_quick, "fewer time steps and a coarser reference");
  compare->add_option("--threads", threads, "OpenMP threads (default: all)");

  std::string section_span = "x", section_depth = "z";
  bool section_plate = false, section_all = false;
  auto* section = app.add_subcommand(
      "section", "PD / continuum bending, shear and axial stiffness of the cross-section of the "
                 "scene's first body, infinitely long (the a-priori part of a structure's error "
                 "budget, verification/cases/STRUCTURES.md)");
  section->add_option("scene", scene, "scene file (YAML)")->required();
  section->add_option("--span", section_span, "axis along which the body is long")
      ->check(CLI::IsMember({"x", "y", "z"}))
      ->capture_default_str();
  section->add_option("--depth", section_depth, "bending (load) direction")
      ->check(CLI::IsMember({"x", "y", "z"}))
      ->capture_default_str();
  section->add_flag("--plate", section_plate, "the third axis is long too (a plate)");
  section->add_flag("--all-pairs", section_all,
                    "every surface/volume correction pair instead of the scene's");
  section->add_flag("--json", json, "JSON lines");

  CLI11_PARSE(app, argc, argv);
  try {
    if (*run) {
      if (print_defaults) {
        fmt::print("{}", pd::scene_template());
        return 0;
      }
      if (scene.empty()) {
        fmt::print(stderr, "error: pd run needs a scene file (or --print-defaults)\n");
        return 1;
      }
      return cmd_run(scene, out_dir, threads, ckpt);
    }
    if (*info) {
      return cmd_info(scene, json);
    }
    if (*bench) {
      return cmd_bench(scene, steps, threads, json, stretch, std::max(repeats, 1));
    }
    if (*verify) {
      if (sweep) {
        for (auto& c : cases) {
          c += "-sweep";
        }
      }
      return cmd_verify(cases, verify_out, list, scenes_dir, threads);
    }
    if (*stability) {
      return cmd_stability(stability_scenes, stability_integrators, stability_steps,
                           stability_tolerance, stability_gate, json, threads);
    }
    if (*compare) {
      return cmd_compare(compare_what, compare_out, scenes_dir, compare_quick, threads);
    }
    if (*section) {
      return cmd_section(scene, section_span, section_depth, section_plate, section_all, json);
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
