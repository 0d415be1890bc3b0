#include "libpd/app/run.hpp"

#include "libpd/kernel/stable_time_step.hpp"

#include <atomic>
#include <chrono>
#include <csignal>
#include <fmt/format.h>
#include <limits>

namespace pd {

namespace {

std::atomic<bool> interrupt_requested{false};

extern "C" void on_interrupt(int) {
  interrupt_requested.store(true);
}

std::string history_csv(const std::vector<ResolvedProbe>& probes, const ProbeHistory& h) {
  std::string s = "time";
  for (const auto& p : probes) {
    s += "," + p.name;
  }
  s += "\n";
  for (std::size_t r = 0; r < h.time.size(); ++r) {
    s += fmt::format("{}", h.time[r]);
    for (double v : h.values[r]) {
      s += fmt::format(",{}", v);
    }
    s += "\n";
  }
  return s;
}

std::string hex(std::uint64_t v) {
  return fmt::format("{:016x}", v);
}

/// Everything build_model derived from the scene that the forces, the integrator and the
/// constraints read; two runs with equal hashes integrate the same equations.
std::uint64_t model_hash(const Model& m) {
  Fnv1a h;
  h.add_vector(m.particles.position);
  h.add_vector(m.particles.volume);
  h.add_vector(m.particles.material);
  h.add_vector(m.density);
  h.add_vector(m.family.offsets);
  h.add_vector(m.family.neighbour);
  h.add_vector(m.family.inverse_length);
  h.add_value(m.field.stiffness);
  h.add_value(m.field.critical_stretch);
  h.add_value(m.field.yield_stretch);
  h.add_vector(m.field.bond_stiffness);
  h.add_vector(m.field.bond_critical_stretch);
  h.add_vector(m.field.bond_yield_stretch);
  h.add_value(static_cast<std::uint64_t>(m.constraints.size()));
  for (const Constraint& c : m.constraints) { // field by field: the struct has padding
    h.add_value(c.particle);
    h.add_value(c.component);
    h.add_value(c.value);
    h.add_value(c.mirror_of);
    h.add_value(c.mirror_sign);
  }
  h.add_vector(m.external_force_density);
  return h.value();
}

void save_history(CheckpointWriter& w, const ProbeHistory& history,
                  const std::vector<std::pair<double, std::string>>& vtu_files) {
  w.section("HIST");
  w.doubles(history.time);
  for (const auto& row : history.values) {
    w.doubles(row);
  }
  w.section("VTUF");
  w.u64(vtu_files.size());
  for (const auto& [t, name] : vtu_files) {
    w.f64(t);
    w.string(name);
  }
}

void restore_history(CheckpointReader& r, std::size_t columns, ProbeHistory& history,
                     std::vector<std::pair<double, std::string>>& vtu_files) {
  r.section("HIST");
  history.time = r.doubles();
  history.values.clear();
  for (std::size_t k = 0; k < history.time.size(); ++k) {
    history.values.push_back(r.doubles(columns, "a probe history row"));
  }
  r.section("VTUF");
  const std::uint64_t n = r.u64();
  vtu_files.clear();
  for (std::uint64_t k = 0; k < n; ++k) {
    const double t = r.f64();
    vtu_files.emplace_back(t, r.string());
  }
  r.finish();
}

} // namespace

std::filesystem::path checkpoint_path(const RunOptions& options) {
  if (!options.checkpoint.empty()) {
    return options.checkpoint;
  }
  return options.output_dir.empty() ? std::filesystem::path{}
                                    : options.output_dir / "checkpoint.pdcp";
}

CheckpointFingerprint run_fingerprint(const Scene& scene, const Simulation& sim,
                                      const std::vector<ResolvedProbe>& probes) {
  const Model& m = sim.model();
  CheckpointFingerprint f;
  f.scene = scene.path.empty() ? scene.title : scene.path;
  f.add("dimension", std::to_string(m.spec.dimension.dim));
  f.add("particles", std::to_string(m.size()));
  f.add("bonds", std::to_string(m.family.bond_count()));
  f.add("integrator", sim.integrator().name());
  if (scene.solver.integrator == IntegratorKind::arkode) {
    const ArkodeSpec& a = scene.solver.arkode;
    f.add("arkode", fmt::format("adaptive={} rtol={} atol={} issue_311_workaround={}", a.adaptive,
                                exact_text(a.rtol), exact_text(a.atol), a.issue_311_workaround));
  }
  f.add("kernel", sim.forces().description());
  std::string effects;
  for (const auto& e : m.effects.names()) {
    effects += (effects.empty() ? "" : ",") + e;
  }
  f.add("effects", effects);
  f.add("dt", exact_text(sim.dt()));
  f.add("damping", exact_text(scene.solver.damping));
  f.add("ramp_time", exact_text(scene.solver.ramp_time));
  f.add("model_hash", hex(model_hash(m)));
  Fnv1a ph;
  std::string names;
  for (const auto& p : probes) {
    names += (names.empty() ? "" : ",") + p.name;
    ph.add_value(p.component);
    ph.add_vector(p.particles);
  }
  f.add("probes", names + " #" + hex(ph.value()));
  f.add("history_every", std::to_string(scene.output.history_every));
  return f;
}

std::vector<ResolvedProbe> resolve_probes(const std::vector<ProbeSpec>& probes,
                                          const Model& model) {
  std::vector<ResolvedProbe> out;
  const int dim = model.spec.dimension.dim;
  const double tol = 1e-6 * model.spec.lattice.spacing;
  for (const ProbeSpec& p : probes) {
    ResolvedProbe r{p.name, p.component, {}};
    if (p.kind == ProbeSpec::Kind::point) {
      // Nearest particle; ties go to the lowest index so the choice is reproducible.
      double best = std::numeric_limits<double>::max();
      std::uint32_t arg = 0;
      for (std::size_t i = 0; i < model.size(); ++i) {
        double d2 = 0;
        for (int c = 0; c < 3; ++c) {
          const double d = model.particles.position[i][c] - p.point[c];
          d2 += d * d;
        }
        if (d2 < best * (1 - 1e-12)) {
          best = d2;
          arg = static_cast<std::uint32_t>(i);
        }
      }
      r.particles.push_back(arg);
    } else {
      for (std::size_t i = 0; i < model.size(); ++i) {
        if (p.region.contains(model.particles.position[i], dim, tol)) {
          r.particles.push_back(static_cast<std::uint32_t>(i));
        }
      }
    }
    if (r.particles.empty()) {
      throw std::runtime_error("probe '" + p.name + "' selects no particle");
    }
    out.push_back(std::move(r));
  }
  return out;
}

double probe_value(const ResolvedProbe& probe, const Simulation& sim) {
  double sum = 0;
  for (std::uint32_t i : probe.particles) {
    sum += sim.displacement(i, probe.component);
  }
  return sum / static_cast<double>(probe.particles.size());
}

RunOutcome run_scene(const Scene& scene, const RunOptions& options) {
  using clock = std::chrono::steady_clock;
  const auto t0 = clock::now();
  RunOutcome out;
  Model model = build_model(scene);
  Simulation sim(model, scene.solver, scene.initial);
  const auto probes = resolve_probes(scene.probes, model);
  out.particles = model.size();
  out.bonds = model.family.bond_count();

  const auto& dir = options.output_dir;
  const bool writing = !dir.empty();
  const bool vtu = writing && options.write_vtu && scene.output.vtu;
  std::vector<std::pair<double, std::string>> vtu_files;

  // Checkpoints. Refuse up front what cannot be continued bitwise, rather than after hours.
  const std::filesystem::path ckpt = checkpoint_path(options);
  const std::size_t ckpt_every = options.checkpoint_every;
  if (ckpt_every > 0 && ckpt.empty()) {
    throw CheckpointError("checkpoints need a file: give an output folder or a checkpoint path");
  }
  const std::string refusal = sim.integrator().checkpoint_refusal();
  if (!refusal.empty() &&
      (ckpt_every > 0 || !options.checkpoint.empty() || !options.restart.empty())) {
    throw CheckpointError(fmt::format("cannot checkpoint this run: {}", refusal));
  }
  // Hashing the model reads every bond array: only when a checkpoint is read or written.
  std::optional<CheckpointFingerprint> fingerprint;
  auto get_fingerprint = [&]() -> const CheckpointFingerprint& {
    if (!fingerprint) {
      fingerprint = run_fingerprint(scene, sim, probes);
    }
    return *fingerprint;
  };
  if (!options.restart.empty()) {
    CheckpointReader reader = read_checkpoint(options.restart, get_fingerprint());
    sim.restore(reader);
    restore_history(reader, probes.size(), out.history, vtu_files);
    out.restarted_from_step = sim.state().step;
  }
  out.setup_seconds = std::chrono::duration<double>(clock::now() - t0).count();
  auto write_vtu_frame = [&](const Simulation& s) {
    const std::string name = fmt::format("particles-{:08d}.vtu", s.state().step);
    write_vtu(dir / name, s);
    vtu_files.emplace_back(s.state().time, name);
    std::string pvd =
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n<Collection>\n";
    for (const auto& [t, f] : vtu_files) {
      pvd += fmt::format("<DataSet timestep=\"{}\" file=\"{}\"/>\n", t, f);
    }
    pvd += "</Collection>\n</VTKFile>\n";
    write_file_atomically(dir / "particles.pvd", pvd);
  };

  auto record = [&](const Simulation& s) {
    out.history.time.push_back(s.state().time);
    std::vector<double> row;
    for (const auto& p : probes) {
      row.push_back(probe_value(p, s));
    }
    out.history.values.push_back(std::move(row));
  };

  const std::size_t history_every = scene.output.history_every;
  const std::size_t vtu_every = scene.output.vtu_every;
  auto last_flush = clock::now();
  auto last_progress = clock::now();
  const auto run_start = clock::now();
  const double end_time = scene.solver.end_time.value_or(0.0);
  if (history_every > 0 && !out.restarted_from_step) {
    record(sim); // a restored history already holds the initial row
  }
  auto save_checkpoint = [&](const Simulation& s) {
    CheckpointWriter w;
    s.save(w);
    save_history(w, out.history, vtu_files);
    write_checkpoint(ckpt, get_fingerprint(), w);
    out.checkpoint = ckpt;
    out.checkpoint_step = s.state().step;
    ++out.checkpoints_written;
    // probes.csv on disk then matches the checkpoint: a restart appends to what is there.
    if (writing && history_every > 0) {
      write_file_atomically(dir / "probes.csv", history_csv(probes, out.history));
      last_flush = clock::now();
    }
  };
  interrupt_requested.store(false);
  void (*previous)(int) = SIG_DFL;
  if (options.stop_on_interrupt) {
    previous = std::signal(SIGINT, on_interrupt);
  }
  auto observer = [&](const Simulation& s) {
    const std::size_t step = s.state().step;
    if (history_every > 0 && step % history_every == 0) {
      record(s);
    }
    if (vtu && vtu_every > 0 && step % vtu_every == 0) {
      write_vtu_frame(s);
    }
    if (ckpt_every > 0 && step % ckpt_every == 0) {
      save_checkpoint(s);
    }
    const auto now = clock::now();
    // Flush the probe history every few seconds so an interrupted run keeps what it computed.
    if (writing && history_every > 0 && now - last_flush > std::chrono::seconds(5)) {
      write_file_atomically(dir / "probes.csv", history_csv(probes, out.history));
      last_flush = now;
    }
    if (options.progress && now - last_progress > std::chrono::milliseconds(500)) {
      last_progress = now;
      const double elapsed = std::chrono::duration<double>(now - run_start).count();
      std::string eta;
      if (end_time > 0 && s.state().time > 0) {
        eta = fmt::format(" ({:4.1f} %, ETA {:.0f} s)", 100.0 * s.state().time / end_time,
                          elapsed * (end_time / s.state().time - 1.0));
      }
      fmt::print(stderr, "\r  step {:>9}  t = {:.4g} s{}   ", step, s.state().time, eta);
    }
    return !interrupt_requested.load();
  };
  out.result = sim.run(observer);
  if (options.stop_on_interrupt) {
    std::signal(SIGINT, previous);
  }
  if (options.progress) {
    fmt::print(stderr, "\r{:80}\r", "");
  }
  const bool unstable = out.result.status == RunStatus::unstable;
  // The final state too: Ctrl-C loses nothing, and a finished run can be extended (restart with a
  // later end_time). An unstable state is never saved; the last good checkpoint stays.
  if (!unstable && !ckpt.empty()) {
    const bool interrupted = out.result.status == RunStatus::interrupted;
    if (interrupted || ckpt_every > 0 || !options.checkpoint.empty()) {
      if (refusal.empty()) {
        save_checkpoint(sim);
      } else {
        out.checkpoint_note = "no checkpoint written: " + refusal;
      }
    }
  }
  if (!unstable) {
    for (const auto& p : probes) {
      out.probes[p.name] = probe_value(p, sim);
    }
    if (options.keep_final_field) {
      out.positions = model.particles.position;
      out.displacement.resize(3 * model.size());
      for (std::size_t i = 0; i < model.size(); ++i) {
        for (int c = 0; c < 3; ++c) {
          out.displacement[3 * i + c] = sim.displacement(i, c);
        }
      }
    }
  }

  Json& j = out.summary;
  j["scene"] = scene.path;
  j["title"] = scene.title;
  j["status"] = to_string(out.result.status);
  if (!out.result.message.empty()) {
    j["message"] = out.result.message;
  }
  j["dimension"] = scene.model.dimension.dim;
  j["particles"] = out.particles;
  j["bonds"] = out.bonds;
  j["bonds_per_particle"] =
      2.0 * static_cast<double>(out.bonds) / static_cast<double>(out.particles);
  j["horizon"] = model.horizon();
  j["spacing"] = scene.model.lattice.spacing;
  j["integrator"] = to_string(scene.solver.integrator);
  j["kernel"] = sim.forces().description();
  j["effects"] = Json::array_of(model.effects.names());
  j["steps"] = out.result.steps;
  j["time"] = out.result.time;
  j["dt"] = out.result.dt;
  j["dt_stable"] = out.result.dt_stable;
  j["force_evaluations"] = out.result.force_evaluations;
  j["setup_seconds"] = out.setup_seconds;
  j["wall_seconds"] = out.result.wall_seconds;
  j["bond_updates"] =
      static_cast<double>(out.bonds) * static_cast<double>(out.result.force_evaluations);
  j["bond_updates_per_second"] =
      bond_updates_per_second(out.bonds, out.result.force_evaluations, out.result.wall_seconds);
  j["kinetic_energy"] = out.result.kinetic_energy;
  j["strain_energy"] = out.result.strain_energy;
  j["residual"] = out.result.residual;
  j["memory_bytes"] = model.memory_bytes();
  Json& pj = j["probes"];
  pj = Json::object();
  for (const auto& [name, value] : out.probes) {
    pj[name] = value;
  }
  if (!scene.warnings.empty()) {
    j["warnings"] = Json::array_of(scene.warnings);
  }
  if (!out.checkpoint.empty()) {
    j["checkpoint"] = out.checkpoint.string();
    j["checkpoint_step"] = out.checkpoint_step;
  }
  if (out.restarted_from_step) {
    Json& rj = j["restarted_from"];
    rj["file"] = options.restart.string();
    rj["step"] = *out.restarted_from_step;
  }

  if (writing) {
    if (!unstable && vtu) {
      write_vtu_frame(sim);
    }
    if (history_every > 0) {
      // After an instability the last rows may hold huge (but finite) values: keep only rows that
      // are finite, so the file never carries NaN or inf.
      ProbeHistory clean;
      for (std::size_t r = 0; r < out.history.time.size(); ++r) {
        bool finite = true;
        for (double v : out.history.values[r]) {
          finite = finite && std::isfinite(v);
        }
        if (finite) {
          clean.time.push_back(out.history.time[r]);
          clean.values.push_back(out.history.values[r]);
        }
      }
      write_file_atomically(dir / "probes.csv", history_csv(probes, clean));
    }
    write_file_atomically(dir / "summary.json", j.dump());
  }
  return out;
}

} // namespace pd
