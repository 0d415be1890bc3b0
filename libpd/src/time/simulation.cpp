#include "libpd/time/simulation.hpp"

#include "libpd/core/binary_state.hpp"
#include "libpd/core/threads.hpp"
#include "libpd/kernel/linear_operator.hpp"
#include "libpd/kernel/round_off.hpp"
#include "libpd/kernel/stable_time_step.hpp"
#include "libpd/time/energy_watch.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <fmt/format.h>
#include <limits>
#include <optional>

namespace pd {

std::string to_string(RunStatus status) {
  return std::string(name_of(status));
}

Simulation::Simulation(Model& model, const SolverSpec& solver, const InitialSpec& initial,
                       std::function<bool()> stop_requested)
    : model_(model), solver_(solver) {
  const std::size_t n = model.size();
  state_.position.resize(3 * n);
  state_.velocity.resize(3 * n);
  state_.force.assign(3 * n, 0.0);
  Vec3 lo = model.particles.position.empty() ? Vec3{0, 0, 0} : model.particles.position[0];
  Vec3 hi = lo;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3& x = model.particles.position[i];
    for (int r = 0; r < 3; ++r) {
      double u = 0;
      for (int c = 0; c < 3; ++c) {
        u += initial.displacement_gradient[r][c] * (x[c] - initial.about[c]);
      }
      state_.position[3 * i + r] = x[r] + u;
      state_.velocity[3 * i + r] = initial.velocity[r];
      lo[r] = std::min(lo[r], x[r]);
      hi[r] = std::max(hi[r], x[r]);
    }
  }
  ramp_.ramp_time = solver.ramp_time;
  apply_constraints(model, ramp_, 0.0, state_.position.data(), state_.velocity.data());
  constrained_ = held_dofs(model);

  // Mirror dependants' forces go back to their images (Rᵀ) under consistent coupling, so every
  // integrator sees the symmetric constrained operator (discretisation/mirror_constraints.hpp).
  if (solver.small_displacements) {
    if (!model.effects.elastic_bonds_only() || model.ownership.communicator().size() > 1) {
      throw std::invalid_argument("solver.small_displacements: elastic bond-based models in one "
                                  "process only");
    }
    forces_ = make_linearised_force_evaluator(model);
  } else {
    forces_ = make_constrained_force_evaluator(model);
  }
  massless_ = massless_dependants(model);
  dt_stable_ = model.ownership.communicator().min(stable_time_step(model));
  IntegratorSettings is;
  is.kind = solver.integrator;
  is.damping = solver.damping;
  is.ramp = ramp_;
  is.arkode = solver.arkode;
  is.cfl_fraction = solver.safety;
  is.force_tolerance = solver.steady.force_tolerance;
  is.stop_requested = std::move(stop_requested);
  if (solver.integrator == IntegratorKind::arkode) {
    // Adaptive ARKode: ERKStepSetStabilityFn gets the eq. 31 step scaled by the table's β/2.
    is.stable_dt = dt_stable_ * make_integrator(is, model, *forces_)->stability_scale();
  }
  integrator_ = make_integrator(is, model, *forces_);
  dt_ = solver.dt ? *solver.dt : solver.safety * dt_stable_ * integrator_->stability_scale();
  if (!(dt_ > 0) || !std::isfinite(dt_)) {
    throw std::runtime_error(
        fmt::format("no usable time step: dt = {} (eq. 31 limit {}); does the model have bonds?",
                    dt_, dt_stable_));
  }
  const Communicator& comm = model.ownership.communicator();
  for (std::size_t r = 0; r < 3; ++r) {
    lo[r] = comm.min(lo[r]);
    hi[r] = comm.max(hi[r]);
  }
  const double diagonal =
      std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                (hi[2] - lo[2]) * (hi[2] - lo[2]));
  const double blowup = solver.blowup_displacement > 0
                            ? solver.blowup_displacement
                            : std::max(diagonal, model.spec.lattice.spacing);
  blowup_squared_ = blowup * blowup;
  if (solver.steady.enabled) {
    residual_floor_ = residual_round_off_floor(model, state_.position.data(), constrained_) *
                      integrator_->round_off_amplification(dt_);
  }
}

void Simulation::perturb(const std::vector<double>& du) {
  for (std::size_t d = 0; d < state_.position.size() && d < du.size(); ++d) {
    state_.position[d] += du[d];
  }
  apply_constraints(model_, ramp_, state_.time, state_.position.data(), state_.velocity.data());
}

double Simulation::kinetic_energy() const {
  // Exact sums over the owned particles: the same energy on any number of ranks (ownership.hpp).
  const Ownership& own = model_.ownership;
  ExactSum ke;
  for (std::size_t i = 0; i < model_.size(); ++i) {
    if (massless_[i] || !own.owns(i)) { // mirror dependants are images of the body, not mass
      continue;
    }
    const double* v = &state_.velocity[3 * i];
    ke.add(0.5 * model_.density[i] * model_.particles.volume[i] *
           (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]));
  }
  return own.communicator().sum(ke);
}

double Simulation::strain_energy() const {
  return forces_->strain_energy(state_.position.data());
}

Simulation::ForceBalance Simulation::force_balance() const {
  // Free degrees of freedom carry the out-of-balance force (b + F b_ext)·V; constrained ones carry
  // reactions, which normalise the residual when no load is applied.
  const double load = ramp_.factor(state_.time);
  const bool has_loads = !model_.external_force_density.empty();
  const Ownership& own = model_.ownership;
  std::array<ExactSum, 3> sums; // residual, applied, reactions
  auto& [residual, applied, reactions] = sums;
  for (std::size_t i = 0; i < model_.size(); ++i) {
    if (!own.owns(i)) {
      continue;
    }
    const double vol = model_.particles.volume[i];
    double particle[3] = {0, 0, 0}; // a particle's terms in a fixed order, then one exact add
    for (std::size_t c = 0; c < 3; ++c) {
      const std::size_t dof = 3 * i + c;
      const double ext = has_loads ? load * model_.external_force_density[dof] * vol : 0.0;
      const double f = state_.force[dof] * vol + ext;
      particle[constrained_[dof] ? 2 : 0] += f * f;
      particle[1] += ext * ext;
    }
    residual.add(particle[0]);
    applied.add(particle[1]);
    reactions.add(particle[2]);
  }
  own.communicator().sum(sums);
  const double applied_norm = applied.value();
  return {std::sqrt(residual.value()),
          std::sqrt(applied_norm > 0 ? applied_norm : reactions.value())};
}

double full_load_norm(const Model& model) {
  ExactSum applied;
  const std::vector<double>& ext = model.external_force_density;
  for (std::size_t dof = 0; dof < ext.size(); ++dof) {
    if (model.ownership.owns(dof / 3)) {
      const double f = ext[dof] * model.particles.volume[dof / 3];
      applied.add(f * f);
    }
  }
  return std::sqrt(model.ownership.communicator().sum(applied));
}

double Simulation::force_tolerance_for(double reference) const {
  const double requested = solver_.steady.force_tolerance;
  return reference > 0 ? std::max(requested, round_off_margin * residual_floor_ / reference)
                       : requested;
}

void Simulation::record_balance(RunResult& r) const {
  const ForceBalance balance = force_balance();
  r.residual = balance.relative();
  r.force_tolerance = force_tolerance_for(balance.reference);
  r.residual_floor = balance.reference > 0 ? residual_floor_ / balance.reference
                                           : std::numeric_limits<double>::quiet_NaN();
}

double Simulation::steady_force_tolerance() const {
  return force_tolerance_for(full_load_norm(model_));
}

namespace {

/// The model's particles and bond rows as a checkpoint keys them (global index, owner, row).
CheckpointLayout checkpoint_layout(const Model& m) {
  CheckpointLayout l;
  l.particles = m.size();
  l.global = m.ownership.global_index;
  l.owned = m.ownership.owned;
  l.rows = m.family.offsets;
  return l;
}

} // namespace

void Simulation::save(CheckpointWriter& w) const {
  const Communicator& comm = model_.ownership.communicator();
  w.keys(checkpoint_layout(model_), static_cast<std::uint64_t>(comm.rank()),
         static_cast<std::uint64_t>(comm.size()));
  w.section("STAT");
  w.f64(state_.time);
  w.u64(state_.step);
  w.u64(run_origin_);
  w.f64(dt_);
  w.per_particle(state_.position, 3);
  w.per_particle(state_.velocity, 3);
  w.per_particle(state_.force, 3);
  w.section("BOND");
  w.per_bond(model_.state.broken);
  w.per_bond(model_.state.plastic_stretch);
  w.per_particle(model_.state.damage, 1);
  integrator_->save(w);
}

void Simulation::restore(CheckpointReader& r) {
  r.keys(checkpoint_layout(model_));
  r.section("STAT");
  State st;
  st.time = r.f64();
  st.step = static_cast<std::size_t>(r.u64());
  const auto origin = static_cast<std::size_t>(r.u64());
  const double dt = r.f64();
  if (dt != dt_) { // the fingerprint compares Δt too; this guards library callers
    r.fail(fmt::format("Δt {} differs from this run's {}", dt, dt_));
  }
  const std::size_t ndof = state_.position.size();
  st.position = r.per_particle(ndof, 3, "positions");
  st.velocity = r.per_particle(ndof, 3, "velocities");
  st.force = r.per_particle(ndof, 3, "forces");
  r.section("BOND");
  auto broken = r.per_bond_bytes(model_.state.broken.size(), "broken-bond flags");
  auto plastic = r.per_bond(model_.state.plastic_stretch.size(), "plastic stretches");
  auto damage = r.per_particle(model_.state.damage.size(), 1, "damage indices");
  integrator_->restore(r);
  // Nothing is changed until everything has been read: a bad checkpoint leaves the run as it was
  // (except the integrator, which only restores after its own checks).
  state_ = std::move(st);
  model_.state.broken = std::move(broken);
  model_.state.plastic_stretch = std::move(plastic);
  model_.state.damage = std::move(damage);
  run_origin_ = origin;
  resumed_ = true;
}

std::string Simulation::unstable_message(const std::string& what) const {
  // Δt is to blame only when it is above the limit; otherwise lowering it would not help and
  // the message must not send the user there.
  const double limit = dt_stable_ * integrator_->stability_scale();
  const std::string cause =
      dt_ > limit
          ? fmt::format("Δt = {:.6g} s is {:.3g}× the stable limit {:.6g} s (eq. 31 × {:.3g}): "
                        "lower solver.dt or solver.safety",
                        dt_, dt_ / limit, limit, integrator_->stability_scale())
          : fmt::format("Δt = {:.6g} s is within the stable limit {:.6g} s (eq. 31 × {:.3g}), so "
                        "this is not a time-step instability: check the supports (a mirror clamp "
                        "with model.mirror_coupling: copy can feed a growing mode), the "
                        "corrections and the loads",
                        dt_, limit, integrator_->stability_scale());
  return fmt::format("run became unstable at step {} (t = {:.6g} s): {}. {}.", state_.step,
                     state_.time, what, cause);
}

RunResult Simulation::run(const Observer& observer) {
  using clock = std::chrono::steady_clock;
  const auto start = clock::now();
  RunResult r;
  r.dt = dt_;
  r.dt_stable = dt_stable_;
  r.residual = std::numeric_limits<double>::quiet_NaN();
  r.force_tolerance = std::numeric_limits<double>::quiet_NaN();
  r.residual_floor = std::numeric_limits<double>::quiet_NaN();
  // Clamped: end_time / dt beyond 2^64 (scene fuzzing: end_time 1e300) must not overflow the
  // cast; max_steps stops such a run.
  const double end_count = solver_.end_time ? std::ceil(*solver_.end_time / dt_ - 1e-9) : 0.0;
  const std::size_t end_steps = end_count < 1.8e19 ? static_cast<std::size_t>(end_count)
                                                   : std::numeric_limits<std::size_t>::max();
  if (!resumed_) {
    run_origin_ = state_.step;
  }
  resumed_ = false;
  const std::size_t first_step = run_origin_;
  // ADR's velocities are fictitious (its masses are chosen for convergence), so its kinetic
  // energy bounds nothing.
  std::optional<EnergyWatch> watch;
  if (solver_.energy_check && solver_.integrator != IntegratorKind::adr &&
      solver_.integrator != IntegratorKind::static_solve) {
    watch.emplace(model_, ramp_, massless_);
    watch->start(state_, kinetic_energy(), strain_energy());
  }
  for (;;) {
    if (solver_.end_time && state_.step >= end_steps) {
      r.status = RunStatus::end_time;
      break;
    }
    if (state_.step - first_step >= solver_.max_steps) {
      r.status = RunStatus::max_steps;
      break;
    }
    // Between steps no parallel region is open; every 64th, so that the smallest models do not
    // pay for the reading.
    if ((state_.step - first_step) % 64 == 0) {
      refresh_thread_count();
    }
    const StepReport rep = integrator_->step(state_, dt_);
    if (!(rep.max_displacement_squared <= blowup_squared_)) {
      r.status = RunStatus::unstable;
      const bool finite = std::isfinite(rep.max_displacement_squared);
      if (solver_.integrator == IntegratorKind::static_solve) {
        // An equilibrium far outside the elastic range, not a growing mode: no step to shorten.
        r.message =
            fmt::format("the static solution passed solver.blowup_displacement ({:.3g} m): it {}",
                        std::sqrt(blowup_squared_), static_state_report(model_, state_.position));
        break;
      }
      r.message = unstable_message(
          finite ? fmt::format("a displacement reached {:.3g} m, beyond the blow-up limit {:.3g} m",
                               std::sqrt(rep.max_displacement_squared), std::sqrt(blowup_squared_))
                 : std::string("non-finite positions"));
      break;
    }
    if (integrator_->finished()) {
      r.status = RunStatus::converged;
      r.message = integrator_->report();
      break;
    }
    if (watch && state_.step % EnergyWatch::every == 0) {
      if (const std::string grew = watch->check(state_); !grew.empty()) {
        r.status = RunStatus::unstable;
        r.message = unstable_message(grew);
        break;
      }
    }
    if (solver_.steady.enabled && state_.step % solver_.steady.check_every == 0 &&
        state_.time >= solver_.ramp_time) {
      const double ke = kinetic_energy();
      const double u = strain_energy();
      record_balance(r);
      if (ke <= solver_.steady.kinetic_tolerance * u && r.residual <= r.force_tolerance) {
        r.status = RunStatus::converged;
        break;
      }
    }
    if (observer && !observer(*this)) {
      r.status = RunStatus::interrupted;
      break;
    }
  }
  r.steps = state_.step;
  r.internal_steps = integrator_->internal_steps();
  r.time = state_.time;
  r.force_evaluations = integrator_->force_evaluations();
  if (r.status != RunStatus::unstable) {
    r.kinetic_energy = kinetic_energy();
    r.strain_energy = strain_energy();
    if (solver_.steady.enabled) {
      record_balance(r);
    }
    // Positions can stay finite while the energies overflow (scene fuzzing: a density of 1e-308
    // kg/m³ under ADR); never report such a run as a success.
    if (!std::isfinite(r.kinetic_energy) || !std::isfinite(r.strain_energy)) {
      r.status = RunStatus::unstable;
      r.message =
          fmt::format("run produced non-finite energies at step {} (kinetic {}, strain {}): "
                      "the scene's values overflow double precision; check densities, "
                      "moduli, loads and solver.dt",
                      state_.step, r.kinetic_energy, r.strain_energy);
    }
  }
  r.wall_seconds = std::chrono::duration<double>(clock::now() - start).count();
  return r;
}

std::string static_state_report(const Model& m, const std::vector<double>& position) {
  const ParticleSet& p = m.particles;
  Vec3 lo = p.position.empty() ? Vec3{0, 0, 0} : p.position.front();
  Vec3 hi = lo;
  double moved = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    double u2 = 0;
    for (std::size_t a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], p.position[i][a]);
      hi[a] = std::max(hi[a], p.position[i][a]);
      const double u = position[3 * i + a] - p.position[i][a];
      u2 += u * u;
    }
    moved = u2 <= moved * moved ? moved : std::sqrt(u2); // NaN is kept, not skipped
  }
  const double size =
      std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                (hi[2] - lo[2]) * (hi[2] - lo[2]));
  double strain = 0;
  const BondFamily& f = m.family;
  for (std::size_t i = 0; i < f.particle_count(); ++i) {
    for (std::size_t k = f.offsets[i]; k < f.offsets[i + 1]; ++k) {
      const std::size_t j = f.neighbour[k];
      double l2 = 0;
      for (std::size_t a = 0; a < 3; ++a) {
        const double d = position[3 * j + a] - position[3 * i + a];
        l2 += d * d;
      }
      const double e = std::abs(std::sqrt(l2) * f.inverse_length[k] - 1);
      strain = e <= strain ? strain : e;
    }
  }
  std::string what = std::isfinite(moved) && std::isfinite(strain)
                         ? fmt::format("moves a particle {:.3g} m (the body is {:.3g} m across) "
                                       "and strains a bond by {:.3g}",
                                       moved, size, strain)
                         : std::string("leaves positions that are not finite numbers");
  if (!(strain <= 1) || !(moved <= size)) {
    what += ": the loads and prescribed displacements ask for strains far beyond the small-strain "
            "range the material's moduli describe: lower them (Δt plays no part in a static "
            "solve)";
  }
  return what;
}

} // namespace pd
