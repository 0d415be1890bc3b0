// A run of a scene as named steps, in the manner of a deal.II tutorial's run(): set up the model
// and its simulation, restore a checkpoint if asked, advance in time while recording, save the
// final state, write the results. Each step's policy lives in its own file (checkpoints,
// interrupts, progress, output files, summary); this file only says in which order they act.
#include "libpd/app/run.hpp"

#include "libpd/app/interrupt.hpp"
#include "libpd/app/output_folder.hpp"
#include "libpd/app/progress.hpp"
#include "libpd/app/run_checkpoints.hpp"
#include "libpd/app/run_output.hpp"
#include "libpd/app/run_summary.hpp"
#include "libpd/core/atomic_file.hpp"
#include "libpd/kernel/round_off.hpp"
#include "libpd/time/quasi_static.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <fmt/format.h>
#include <limits>
#include <memory>
#include <optional>
#include <vector>

namespace pd {

namespace {

/// One run of one scene. Its one public verb, run(), calls the private steps below in the order
/// they are written; the state they share (model, simulation, probes, output, checkpoints) is
/// held here so that each step reads as a few lines.
class SceneRun {
public:
  SceneRun(const Scene& scene, const RunOptions& options) : scene_(scene), options_(options) {}

  RunOutcome run() {
    // From the set-up to the last file: a stop request (Ctrl-C, SIGTERM, SIGHUP) ends the run
    // at the first step after it (one during set-up, once the set-up is done), and one arriving
    // while the final files are written only repeats the request. A scheduler's SIGTERM during
    // a long set-up still leaves a summary and a checkpoint.
    const InterruptGuard interrupt(options_.stop_on_interrupt);
    interrupt_ = &interrupt;
    const auto start = std::chrono::steady_clock::now();
    claim_output();
    {
      // Set-up and a step need not poll: where they do not answer a request in time (a large
      // model's bonds, the static solve's factorisation), the run is abandoned with a summary.
      std::optional<AbandonOnInterrupt> abandon;
      if (options_.stop_on_interrupt) {
        if (folder_) { // listed now: the watchdog's summary must not miss the manifest
          folder_->add(folder_->dir() / "summary.json");
        }
        abandon.emplace([this](int sig) { write_abandoned_summary(sig); });
      }
      setup();
      restore();
      out_.setup_seconds =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      progress_.phase = "solve";
      advance(interrupt);
    }
    save_final_state();
    write_results();
    return std::move(out_);
  }

private:
  // Claim the output. Before any work: the folder is created, proven writable and locked, and a
  // checkpoint path that would destroy a file is refused — not found out after hours.
  void claim_output() {
    const bool checkpointing = options_.checkpoint_every > 0 || !options_.checkpoint.empty() ||
                               (!options_.output_dir.empty() && options_.stop_on_interrupt);
    if (checkpointing && !checkpoint_path(options_).empty()) {
      check_checkpoint_target(checkpoint_path(options_), options_.output_dir);
    }
    if (!options_.output_dir.empty()) {
      // One folder, claimed once: rank 0 locks it and keeps the manifest; the others write
      // their VTU pieces and checkpoint files into it once it exists.
      if (comm().root()) {
        folder_.emplace(options_.output_dir, options_.overwrite, !options_.restart.empty());
      }
      comm().barrier();
    }
  }

  // How big the run will be, from the scene alone: absurd settings (E = 1e300 gave Δt = 4.5e-151
  // s; a small vtu_every gave 9,490 files in 30 s) are said before the run, and what it will
  // write is checked against the free disk space.
  void check_run_size() {
    const double dt = sim_->dt();
    const double max_steps = static_cast<double>(scene_.solver.max_steps);
    const double to_end =
        scene_.solver.end_time && dt > 0 ? *scene_.solver.end_time / dt : max_steps;
    const double steps = std::min(max_steps, to_end);
    if (to_end > max_steps) {
      warn(fmt::format("reaching end_time takes {:.3g} steps of Δt = {:.3g} s; the run stops at "
                       "solver.max_steps = {:.3g}",
                       to_end, dt, max_steps));
    } else if (steps > many_steps) {
      warn(fmt::format("the run takes {:.3g} steps of Δt = {:.3g} s", steps, dt));
    }
    double frames = 1;
    if (folder_ && options_.write_vtu && scene_.output.vtu && scene_.output.vtu_every > 0) {
      frames += steps / static_cast<double>(scene_.output.vtu_every);
      if (frames > many_files) {
        warn(fmt::format("the run writes {:.3g} VTU files (output.vtu_every = {}); raise "
                         "vtu_every for fewer",
                         frames, scene_.output.vtu_every));
      }
    }
    if (!folder_) {
      return;
    }
    constexpr double vtu_bytes_per_particle = 200; // positions, displacement, damage as text
    const double bytes = frames * vtu_bytes_per_particle * static_cast<double>(model_.size()) +
                         2.0 * static_cast<double>(model_.memory_bytes());
    const std::string warning =
        folder_->check_space(static_cast<std::uint64_t>(std::min(bytes, 1e18)));
    if (!warning.empty()) {
      warn(warning);
    }
  }

  /// Above these a run's size is worth a warning before it starts.
  static constexpr double many_steps = 1e8;
  static constexpr double many_files = 1000;

  void warn(const std::string& warning) {
    out_.warnings.push_back(warning);
    if (options_.on_warning && comm().root()) {
      options_.on_warning(warning);
    }
  }

  // The balance of a point cloud's arms (discretisation/fibre_arms.hpp) is all or nothing: where
  // its conditions cannot be met with positive weights it is not applied, and interior
  // particles keep the force imbalance of their irregular arrangement. The moduli are then
  // corrected for the relaxation that imbalance allows; the run says both.
  void check_fibre_balance() {
    const FibreArms& a = model_.fibre_arms;
    if (a.balance_passes > 0 && !a.balance_applied) {
      warn(fmt::format(
          "virtual fibres: the arm balance was not applied (relative residual {:.2g} after {} "
          "passes, {} arms at their floor): under a homogeneous strain interior particles keep "
          "forces of order 0.2 σ/h. {}",
          a.balance_residual, a.balance_passes, a.balance_floored,
          a.relaxed.applied
              ? fmt::format("Their relaxation releases {:.1f} % (isotropic) and {:.1f} % "
                            "(deviatoric) of a homogeneous strain's energy; the particles' moduli "
                            "are raised to match",
                            100 * a.relaxed.bulk, 100 * a.relaxed.shear)
              : std::string("The relaxed moduli could not be measured (no particle away from a "
                            "surface, or a free region with no held particle): the body is softer "
                            "than its material")));
    }
  }

  // An explicit Δt above the eq. 31 limit (times the integrator's own factor) is said before the
  // run and kept in the summary: such a run may still finish, and then its numbers must not pass
  // unremarked. ADR's Δt is fictitious and has no such limit.
  void check_time_step() {
    // A step longer than the whole run (a material soft enough, E = 1e-300, makes Δt 1e149 s)
    // ends it at once: "0 steps, status end_time" must not pass for a finished run.
    const std::optional<double>& end = scene_.solver.end_time;
    if (scene_.solver.integrator != IntegratorKind::static_solve && end && *end > 0 &&
        sim_->dt() > *end) {
      warn(fmt::format("a step (Δt = {:.4g} s) is longer than solver.end_time = {:.4g} s: the "
                       "run takes no step; check the material's units (E in Pa, density in "
                       "kg/m³) or lower dt",
                       sim_->dt(), *end));
    }
    if (!scene_.solver.dt || scene_.solver.integrator == IntegratorKind::adr) {
      return;
    }
    const double limit = sim_->dt_stable() * sim_->integrator().stability_scale();
    if (*scene_.solver.dt > limit) {
      warn(fmt::format(
          "solver.dt = {:.4g} s is {:.3g}× the stable limit {:.4g} s (Miranda eq. 31 × {:.3g} for "
          "{}): the run may become unstable; use dt: auto or a smaller dt",
          *scene_.solver.dt, *scene_.solver.dt / limit, limit, sim_->integrator().stability_scale(),
          sim_->integrator().name()));
    }
  }

  // Setup. The model, its simulation and the probes bound to its particles; the checkpoint
  // policy is checked here, so a run that could not be continued is refused before it starts.
  void setup() {
    using clock = std::chrono::steady_clock;
    const auto start = clock::now();
    model_ = build_model(scene_);
    probes_ = resolve_probes(scene_.probes, model_); // on the whole model, before any split
    out_.particles = model_.size();
    out_.bonds = model_.family.bond_count();
    progress_.particles = out_.particles;
    progress_.bonds = out_.bonds;
    for (const LoadSpec& load : scene_.model.loads) {
      if (load.load.kind == BoxRegionLoad::Kind::point) {
        out_.point_load_particles[load.name] =
            load_particles(model_.spec, model_.particles, load, model_.body_particle_count())
                .size();
      }
    }
    split_over_ranks();
    const auto built = clock::now();
    sim_ = std::make_unique<Simulation>(model_, scene_.solver, scene_.initial,
                                        [this] { return interrupt_->requested(); });
    out_.model_seconds = std::chrono::duration<double>(built - start).count();
    out_.simulation_seconds = std::chrono::duration<double>(clock::now() - built).count();
    output_.emplace(folder_ ? &*folder_ : nullptr, options_, scene_.output, probes_);
    checkpoints_.emplace(options_, sim_->integrator().checkpoint_refusal());
    check_run_size();
    check_time_step();
    check_fibre_balance();
    check_steady_tolerance();
  }

  // Split over ranks. Each rank keeps its particles and their halo (discretisation/
  // distribution.hpp) and the probes' particles it owns; the whole model is then freed.
  void split_over_ranks() {
    model_.ownership.comm = &comm();
    if (comm().size() == 1) {
      return;
    }
    // ARKode's stages combine vectors entry by entry, and its norms are exact sums over the owned
    // entries (time/arkode.cpp): each rank's steps are the serial ones on its particles. The
    // static solver splits its matrix by rows (time/distributed_solve.hpp).
    const auto owner = partition_particles(model_, comm(), options_.partition);
    const PartitionQuality quality = partition_quality(model_, owner, comm().size());
    model_ = localise(model_, owner, comm().rank(), comm().size(), comm());
    probes_ = localise_probes(std::move(probes_), model_);
    Json& d = out_.distribution;
    d["ranks"] = comm().size();
    d["partition"] = std::string(name_of(options_.partition));
    d["cut_bonds"] = quality.cut_bonds;
    d["owned_particles"] = Json::array_of(quality.owned);
  }

  // Per rank, what the split costs: the model's bytes, the peak resident bytes and the halo
  // bytes sent per step (gathered on rank 0 for summary.json).
  void describe_ranks() {
    if (!out_.distribution.is_object()) {
      return;
    }
    const double steps = std::max<double>(
        1.0, static_cast<double>(out_.result.steps - out_.restarted_from_step.value_or(0)));
    const auto& owned = model_.ownership.owned;
    const auto halo = static_cast<double>(std::count(owned.begin(), owned.end(), 0));
    const std::string mine =
        fmt::format("{} {} {} {} {}", model_.memory_bytes(), peak_resident_bytes(),
                    static_cast<double>(comm().halo_bytes()) / steps, comm().halo_seconds(), halo);
    const std::vector<std::string> all = comm().gather(mine);
    std::vector<double> model_bytes, peak_bytes, halo_bytes, halo_seconds, halo_particles;
    for (const std::string& line : all) {
      double m = 0, p = 0, h = 0, s = 0, n = 0;
      if (std::sscanf(line.c_str(), "%lf %lf %lf %lf %lf", &m, &p, &h, &s, &n) == 5) {
        model_bytes.push_back(m);
        peak_bytes.push_back(p);
        halo_bytes.push_back(h);
        halo_seconds.push_back(s);
        halo_particles.push_back(n);
      }
    }
    Json& d = out_.distribution;
    d["memory_bytes"] = Json::array_of(model_bytes);
    d["peak_memory_bytes"] = Json::array_of(peak_bytes);
    d["halo_bytes_per_step"] = Json::array_of(halo_bytes);
    d["halo_exchange_seconds"] = Json::array_of(halo_seconds);
    d["halo_particles"] = Json::array_of(halo_particles); // held copies of others' particles
  }

  const Communicator& comm() const {
    return options_.communicator != nullptr ? *options_.communicator : serial_communicator();
  }

  // A force tolerance below the residual's round-off floor can never be met: the run would go on
  // to end_time however converged it is. The check uses a tolerance just above the floor, and
  // says so before the run (here when the loads fix the reference, after it when the reactions
  // do) and in the summary.
  void check_steady_tolerance() {
    if (!steady_asked()) {
      return;
    }
    const double used = sim_->steady_force_tolerance();
    if (used > scene_.solver.steady.force_tolerance) {
      warn_raised_tolerance(used);
    }
  }
  void warn_raised_tolerance(double used) {
    warned_tolerance_ = true;
    warn(fmt::format("solver.steady.force_tolerance = {:.3g} is below the round-off floor of the "
                     "residual under {} ({:.2g} of the reference force: positions carry about 16 "
                     "digits of their distance from the origin, kernel/round_off.hpp); the steady "
                     "check uses {:.3g} ({:g}× the floor) instead",
                     scene_.solver.steady.force_tolerance, sim_->integrator().name(),
                     used / round_off_margin, used, round_off_margin));
  }

  // A run that asked for a steady state and stopped at its time or step limit has not reached it:
  // its numbers are not converged, and exit status 0 must not let that pass unremarked.
  void check_steady_reached() {
    if (!steady_asked()) {
      return;
    }
    const RunResult& r = out_.result;
    if (!warned_tolerance_ && r.force_tolerance > scene_.solver.steady.force_tolerance) {
      warn_raised_tolerance(r.force_tolerance);
    }
    if (r.status != RunStatus::end_time && r.status != RunStatus::max_steps) {
      return;
    }
    warn(fmt::format(
        "the run asked for a steady state (solver.steady) but stopped at {} (step {}, t = {:.6g} "
        "s) without reaching it: residual {:.3g} of the reference force (tolerance {:.3g}), "
        "kinetic energy {:.3g} of the strain energy (tolerance {:.3g}); its results are not "
        "converged",
        r.status == RunStatus::end_time ? "solver.end_time" : "solver.max_steps", r.steps, r.time,
        r.residual, r.force_tolerance,
        r.strain_energy > 0 ? r.kinetic_energy / r.strain_energy : 0.0,
        scene_.solver.steady.kinetic_tolerance));
  }

  bool steady_asked() const {
    return scene_.solver.steady.enabled && scene_.solver.integrator != IntegratorKind::static_solve;
  }

  // Restore. A restart continues the state, the probe history and the list of VTU frames of
  // the checkpoint, so the files it ends with are those of an uninterrupted run.
  void restore() {
    if (options_.restart.empty()) {
      return;
    }
    const int writers = checkpoint_set_ranks(options_.restart, comm());
    recover_checkpoint_set(options_.restart, writers, comm()); // a set a killed rank left
    // Every piece is read by every rank: values are keyed by global particle index, so the set
    // may come from any number of ranks, and pieces of different steps are refused.
    CheckpointPolicy::restore(checkpoint_set(options_.restart, writers), fingerprint(),
                              probes_.size(), *sim_, out_.history, output_->frames());
    out_.restarted_from_step = sim_->state().step;
    evaluations_restored_ = sim_->integrator().force_evaluations();
  }

  // Advance. The integrator's loop, with the recording after each step; a stop request ends it
  // cleanly between two steps (status `interrupted`). A fresh run's history starts with its
  // initial state (a restored history already holds that row).
  void advance(const InterruptGuard& interrupt) {
    if (scene_.output.history_every > 0 && !out_.restarted_from_step) {
      record(*sim_);
    }
    damage_before_sample_ = local_damage(); // of the initial or restored state
    if (quasi_static_fracture()) {
      advance_by_levels(interrupt);
      return;
    }
    ProgressLine progress(options_.progress && comm().root(), scene_.solver.end_time.value_or(0.0));
    out_.result = sim_->run([&](const Simulation& s) {
      after_step(s);
      progress.update(s);
      const bool failed =
          failure_seen(s, s.state().time); // collective: probes are summed over the ranks
      // A signal may reach the ranks at different steps; they stop together.
      return !comm().any(interrupt.requested()) && !failed;
    });
    progress.clear();
    out_.stop_peak = stop_peak_;
    out_.stop_peak_time = stop_peak_time_;
    if (!failure_.empty()) {
      out_.result.status = RunStatus::failed;
      out_.result.message = failure_;
      if (scene_.output.history_every > 0) {
        record(*sim_); // the state at which the run stopped
      }
    }
    out_.stop_signal = interrupt.signal();
    out_.evaluations_this_run = out_.result.force_evaluations - evaluations_restored_;
    check_steady_reached();
  }

  // The static solver with damage is quasi-static fracture (time/quasi_static.hpp): levels of
  // the scene's displacements and loads instead of time steps.
  bool quasi_static_fracture() const {
    return scene_.solver.integrator == IntegratorKind::static_solve && model_.effects.damage;
  }

  // Advance by levels. Every equilibrium the driver reaches (each level, each critical state
  // before its bonds break) is a row of the load curve (load_curve.csv) and of the probe history,
  // whose time column is then the load factor; stop_when judges the same rows. The specimen
  // failed where stop_when says so, or where no equilibrium is left with the bonds that remain
  // (status `failed` either way, the failure load the largest in equilibrium).
  void advance_by_levels(const InterruptGuard& interrupt) {
    using clock = std::chrono::steady_clock;
    const auto start = clock::now();
    quasi_static::FractureSettings settings;
    const std::size_t n = scene_.solver.load_steps;
    for (std::size_t k = 1; k <= n; ++k) {
      settings.levels.push_back(static_cast<double>(k) / static_cast<double>(n));
    }
    settings.stop_requested = [&] { return interrupt.requested(); };
    std::string curve = "level,load_factor,critical,bonds_broken,breaking,dissipated_energy";
    for (const ResolvedProbe& p : probes_) {
      curve += "," + p.name;
    }
    curve += "\n";
    double last_load_factor = 0;
    const quasi_static::FractureOutcome f = quasi_static::run_fracture(
        *sim_, model_, settings, [&](const Simulation& s, const quasi_static::FracturePoint& p) {
          last_load_factor = p.load_factor;
          curve += fmt::format("{},{:.17g},{},{},{},{:.17g}", p.level, p.load_factor,
                               p.critical ? 1 : 0, p.bonds_broken, p.breaking, p.dissipated_energy);
          for (const ResolvedProbe& probe : probes_) {
            curve += fmt::format(",{:.17g}", probe_value(probe, s));
          }
          curve += "\n";
          if (scene_.output.history_every > 0) {
            record(s);
            out_.history.time.back() = p.load_factor;
          }
          if (!p.critical) { // a level reached: the files on disk catch up
            output_->write_load_curve(curve);
            output_->flush_probes_if_stale(out_.history);
          }
          return !failure_seen(s, p.load_factor);
        });
    output_->write_load_curve(curve);
    RunResult& r = out_.result;
    r.steps = f.solves;
    r.internal_steps = f.solves;
    r.time = last_load_factor; // the time axis of a run by levels
    r.dt = sim_->dt();
    r.force_evaluations = sim_->integrator().force_evaluations();
    r.strain_energy = sim_->strain_energy();
    r.residual = std::numeric_limits<double>::quiet_NaN();
    r.force_tolerance = std::numeric_limits<double>::quiet_NaN();
    r.residual_floor = std::numeric_limits<double>::quiet_NaN();
    r.wall_seconds = std::chrono::duration<double>(clock::now() - start).count();
    r.message = f.message;
    using End = quasi_static::FractureOutcome::End;
    r.status = f.end == End::completed        ? RunStatus::converged
               : f.end == End::no_equilibrium ? RunStatus::failed
               : failure_.empty()             ? RunStatus::interrupted
                                              : RunStatus::failed;
    if (!failure_.empty()) {
      r.message = failure_;
    }
    Json& q = out_.quasi_static;
    q["load_steps"] = n;
    q["solves"] = f.solves;
    q["break_events"] = f.break_events;
    q["bonds_broken"] = f.bonds_broken;
    q["dissipated_energy"] = f.dissipated_energy; // Σ energy stored at break [J]
    q["peak_load_factor"] = f.peak_load_factor;
    out_.stop_peak = stop_peak_;
    out_.stop_peak_time = stop_peak_time_;
    out_.stop_signal = interrupt.signal();
    out_.evaluations_this_run = r.force_evaluations;
  }

  // What each step leaves behind: a probe row, a VTU frame and a checkpoint when they are due,
  // and probes.csv now and then so that a killed run keeps its history.
  void after_step(const Simulation& s) {
    const std::size_t step = s.state().step;
    progress_.steps = step;
    const std::size_t history_every = scene_.output.history_every;
    if (history_every > 0 && step % history_every == 0) {
      record(s);
    }
    output_->frame_if_due(s);
    if (checkpoints_->due(step)) {
      save_checkpoint(s);
    }
    output_->flush_probes_if_stale(out_.history);
  }

  // solver.stop_when: whether the watched probe shows failure now; if so, says how in failure_.
  bool failure_seen(const Simulation& s, double time) {
    const StopWhenSpec& stop = scene_.stop_when;
    if (!stop.enabled()) {
      return false;
    }
    const auto watched = std::find_if(probes_.begin(), probes_.end(),
                                      [&](const ResolvedProbe& p) { return p.name == stop.probe; });
    const double value = std::abs(probe_value(*watched, s));
    // A drop is a failure only when bonds have broken since the peak (in the step that reached
    // it or later: a grip that tears off does so in the step of the peak). The probe of a
    // dynamic or relaxing run swings about its equilibrium: on the centre-cracked plate
    // (fracture-stop) under ADR the grip's force spiked to twice its equilibrium in one step with
    // no bond broken and fell back on the next sample, which the plain rule took for the failure
    // at half the strength. Only broken bonds make a specimen weaker, whatever the integrator,
    // so this rule holds for all of them; judging only relaxed states would need a notion of
    // "relaxed" per integrator and would miss a drop during a ramp that never relaxes.
    const double damage = stop.drops_below > 0 ? local_damage() : 0.0;
    if (value > stop_peak_) {
      stop_peak_ = value;
      stop_peak_time_ = time;
      damage_before_peak_ = damage_before_sample_;
    }
    damage_before_sample_ = damage;
    if (stop.drops_below > 0 && stop_peak_ > 0 && value < stop.drops_below * stop_peak_ &&
        comm().max(damage - damage_before_peak_) > 0) {
      failure_ = fmt::format("probe '{}' fell to {:.6g}, below {} of its peak {:.6g} (at {} "
                             "{:.6g}{}): the failure value is the peak",
                             stop.probe, value, stop.drops_below, stop_peak_,
                             quasi_static_fracture() ? "load factor" : "t =", stop_peak_time_,
                             quasi_static_fracture() ? "" : " s");
    } else if (stop.exceeds > 0 && value > stop.exceeds) {
      failure_ =
          fmt::format("probe '{}' reached {:.6g}, above {:.6g}", stop.probe, value, stop.exceeds);
    }
    return !failure_.empty();
  }

  // Σ φ_i over this rank's particles: it grows when, and only when, a bond breaks (each φ_i is
  // the broken fraction of i's bonds, eq. 13). Compared on each rank with its own earlier value,
  // so the order of the sum does not matter.
  double local_damage() const {
    double sum = 0;
    const std::vector<double>& damage = model_.state.damage;
    for (std::size_t i = 0; i < damage.size(); ++i) {
      sum += model_.ownership.owns(i) ? damage[i] : 0.0;
    }
    return sum;
  }

  // Record. One row of probe values at the simulation's current time.
  void record(const Simulation& s) { out_.history.record(probes_, s); }

  // A checkpoint: the simulation's state with the run's record so far (history, VTU frames).
  void save_checkpoint(const Simulation& s) {
    if (folder_) {
      for (int r = 0; r < comm().size(); ++r) { // every rank's piece (rank 0 keeps the list)
        folder_->add(rank_file(checkpoint_base_path(options_), r, comm().size()));
        if (comm().size() > 1) {
          folder_->add(next_piece(rank_file(checkpoint_base_path(options_), r, comm().size())));
        }
      }
      if (comm().size() > 1) {
        folder_->add(set_marker(checkpoint_base_path(options_)));
      }
    }
    checkpoints_->save(fingerprint(), s, out_.history, output_->frames());
    out_.checkpoint = checkpoints_->file();
    out_.checkpoint_step = s.state().step;
    ++out_.checkpoints_written;
    // probes.csv on disk then matches the checkpoint: a restart appends to what is there.
    output_->write_probes(out_.history);
  }

  // The final state: a checkpoint of it when the policy wants one (an integrator that cannot
  // be saved leaves a note instead), the final probe values and, if asked, the displacement
  // field. An unstable state gives neither.
  void save_final_state() {
    if (checkpoints_->wanted_at_end(out_.result.status)) {
      if (checkpoints_->refusal().empty()) {
        save_checkpoint(*sim_);
      } else {
        out_.checkpoint_note = "no checkpoint written: " + checkpoints_->refusal();
      }
    }
    if (unstable()) {
      return;
    }
    for (const auto& p : probes_) {
      out_.probes[p.name] = probe_value(p, *sim_);
    }
    if (options_.keep_final_field) {
      out_.positions = model_.particles.position;
      out_.displacement.resize(3 * model_.size());
      for (std::size_t i = 0; i < model_.size(); ++i) {
        for (int c = 0; c < 3; ++c) {
          out_.displacement[3 * i + c] = sim_->displacement(i, c);
        }
      }
      out_.damage = sim_->model().state.damage;
    }
  }

  // Write the results: summary.json, the last VTU frame and probes.csv (finite rows only).
  void write_results() {
    describe_ranks();
    out_.summary = run_summary(scene_, *sim_, out_, options_);
    output_->write_final(*sim_, unstable(), out_.history, out_.summary);
  }

  bool unstable() const { return out_.result.status == RunStatus::unstable; }

  // The summary of a run abandoned on a stop request (app/interrupt.hpp), written on the
  // watchdog thread beside the busy one: only what progress_ holds, no state, no checkpoint
  // (the state may be half-updated).
  void write_abandoned_summary(int sig) const {
    if (!folder_ || !comm().root()) {
      return;
    }
    Json j = Json::object();
    j["scene"] = scene_.path;
    j["status"] = to_string(RunStatus::interrupted);
    j["stop_signal"] = sig;
    j["interrupted_in"] = std::string(progress_.phase.load());
    j["particles"] = progress_.particles.load();
    j["bonds"] = progress_.bonds.load();
    j["steps"] = progress_.steps.load();
    j["message"] = fmt::format("stopped by signal {} during the {}, which does not stop between "
                               "steps: abandoned without a final state or checkpoint",
                               sig, progress_.phase.load());
    write_file_atomically(folder_->dir() / "summary.json", j.dump());
  }

  // Hashing the model reads every bond array: only when a checkpoint is read or written.
  const CheckpointFingerprint& fingerprint() {
    if (!fingerprint_) {
      fingerprint_ = run_fingerprint(scene_, *sim_, probes_);
    }
    return *fingerprint_;
  }

  const Scene& scene_;
  const RunOptions& options_;
  const InterruptGuard* interrupt_ = nullptr; ///< run()'s, alive while the simulation is
  std::optional<OutputFolder> folder_;        ///< claimed first, released last (holds the lock)
  std::size_t evaluations_restored_ = 0;
  Model model_;
  std::unique_ptr<Simulation> sim_; ///< refers to model_, so made after it
  std::vector<ResolvedProbe> probes_;
  double stop_peak_ = 0;      ///< largest |value| of the stop_when probe so far
  double stop_peak_time_ = 0; ///< when it was reached
  /// local_damage() before the step that reached the peak, and before the current sample.
  double damage_before_peak_ = 0;
  double damage_before_sample_ = 0;
  std::string failure_; ///< why stop_when ended the run; empty while it has not
  std::optional<RunOutputWriter> output_;
  std::optional<CheckpointPolicy> checkpoints_;
  std::optional<CheckpointFingerprint> fingerprint_;
  bool warned_tolerance_ = false;
  RunOutcome out_;
  /// What an abandoned run's summary says, set by the run's thread and read by the watchdog.
  struct {
    std::atomic<const char*> phase{"set-up"};
    std::atomic<std::size_t> particles{0};
    std::atomic<std::size_t> bonds{0};
    std::atomic<std::size_t> steps{0};
  } progress_;
};

} // namespace

RunOutcome run_scene(const Scene& scene, const RunOptions& options) {
  return SceneRun(scene, options).run();
}

} // namespace pd
