// A run: integrate a model until a fixed time, a steady state or a step limit, watching for
// instability. Quasi-static runs end when they have converged, not after a fixed step count.
#pragma once

#include "libpd/core/names.hpp"
#include "libpd/discretisation/model.hpp"
#include "libpd/time/integrator.hpp"

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>

namespace pd {

/// Steady state: after the load ramp, kinetic energy ≤ kinetic_tolerance × strain energy and
/// residual force norm ≤ force_tolerance × reference force (applied loads, or the support reactions
/// when only displacements are prescribed). Checked every `check_every` steps. A force_tolerance
/// below the residual's round-off floor (kernel/round_off.hpp) could never be met: the check then
/// uses round_off_margin × the floor instead (Simulation::steady_force_tolerance).
struct SteadyStateCriterion {
  bool enabled = false;
  double kinetic_tolerance = 1e-10;
  double force_tolerance = 1e-6;
  std::size_t check_every = 100;
};

struct SolverSpec {
  IntegratorKind integrator = IntegratorKind::damped_euler;
  ArkodeSpec arkode; ///< `solver.arkode`, for the arkode integrator
  /// nullopt: auto = safety × eq. 31 × the integrator's stability_scale() (β/2 for an RK table).
  /// ADR iterates in fictitious time (Δt = 1); dt then only maps iterations onto the scene's time
  /// axis (end_time, ramp_time).
  std::optional<double> dt;
  double safety = 0.8;
  std::optional<double> end_time;
  SteadyStateCriterion steady;
  double ramp_time = 0;
  double damping = 0; ///< c_v
  std::size_t max_steps = 100'000'000;
  /// A displacement larger than this means the run has blown up. 0: the bounding-box diagonal.
  double blowup_displacement = 0;
  /// `integrator: static` with damage (quasi-static fracture, time/quasi_static.hpp): the
  /// prescribed displacements and loads are applied in this many equal levels.
  std::size_t load_steps = 10;
  /// Bond forces linearised at the reference configuration (kernel/linear_operator.hpp,
  /// make_linearised_force_evaluator): the linear-elastic problem of small displacements, which a
  /// finite-element reference solves (pd verify sets it). Off: each bond's stretch measure at any
  /// rotation. Elastic bond-based models only.
  bool small_displacements = false;
  /// Stop as unstable when the kinetic energy outgrows the energy put in (time/energy_watch.hpp).
  /// Off only where a caller measures growth itself (pd stability's bounded runs).
  bool energy_check = true;
};

/// Initial displacement u0 = H (X − about) and uniform initial velocity.
struct InitialSpec {
  std::array<std::array<double, 3>, 3> displacement_gradient{};
  Vec3 about{0, 0, 0};
  Vec3 velocity{0, 0, 0};
};

enum class RunStatus { end_time, converged, max_steps, unstable, interrupted, failed };

template <>
struct EnumName<RunStatus> {
  static constexpr NameTable<RunStatus, 6> table{{
      {"end_time", RunStatus::end_time, "reached solver.end_time"},
      {"converged", RunStatus::converged, "met the steady-state criterion"},
      {"max_steps", RunStatus::max_steps, "stopped at solver.max_steps"},
      {"unstable", RunStatus::unstable, "a displacement exceeded solver.blowup_displacement"},
      {"interrupted", RunStatus::interrupted, "stopped by SIGINT"},
      {"failed", RunStatus::failed, "the specimen failed: solver.stop_when was met"},
  }};
};
std::string to_string(RunStatus status);

struct RunResult {
  RunStatus status = RunStatus::end_time;
  std::size_t steps = 0;
  std::size_t internal_steps = 0; ///< steps of the method (adaptive ARKode: its accepted steps)
  double time = 0;
  double dt = 0;
  double dt_stable = 0;
  double wall_seconds = 0;
  std::size_t force_evaluations = 0;
  double kinetic_energy = 0;
  double strain_energy = 0;
  /// With a steady-state criterion, of the final state (NaN without one): the relative residual
  /// force, the relative force tolerance of the check (the requested one, or just above the
  /// round-off floor where that is higher) and that floor relative to the same reference (NaN
  /// when the reference is 0).
  double residual = 0;
  double force_tolerance = 0;
  double residual_floor = 0;
  std::string message; ///< for unstable runs: step, Δt and limit
};

class Simulation {
public:
  /// `stop_requested`: polled inside a step that can take long (IntegratorSettings).
  Simulation(Model& model, const SolverSpec& solver, const InitialSpec& initial = {},
             std::function<bool()> stop_requested = {});

  /// Observer called after every step with the current state; return false to stop the run
  /// (status `interrupted`).
  using Observer = std::function<bool(const Simulation&)>;
  RunResult run(const Observer& observer = {});

  const Model& model() const { return model_; }
  const State& state() const { return state_; }
  double dt() const { return dt_; }
  double dt_stable() const { return dt_stable_; }
  double kinetic_energy() const;
  double strain_energy() const;
  /// Displacement u = y − X of particle i, component c.
  double displacement(std::size_t i, int c) const {
    return state_.position[3 * i + c] - model_.particles.position[i][c];
  }
  const ForceEvaluator& forces() const { return *forces_; }
  /// Add du (3N) to the positions of the unconstrained components before a run (stability
  /// measurements start from a perturbed state).
  void perturb(const std::vector<double>& du);
  const Integrator& integrator() const { return *integrator_; }
  /// The round-off floor of the residual force [N] this run can reach: kernel/round_off.hpp's
  /// estimate at the initial positions times the integrator's round_off_amplification.
  double residual_floor() const { return residual_floor_; }
  /// The relative force tolerance the steady-state check uses at the full applied load:
  /// solver.steady.force_tolerance, raised to round_off_margin × the round-off floor where that
  /// is higher. A run without loads normalises by its reactions, known only at the check: there
  /// this is the requested tolerance and RunResult::force_tolerance says what was used.
  double steady_force_tolerance() const;

  /// Checkpoints (checkpoint.hpp): the State, the model's bond history (broken bonds, damage,
  /// plastic stretch), the step at which the run started (max_steps counts from it) and the
  /// integrator's own state. A Simulation built from the same model and solver settings and
  /// restored from it continues bitwise as the saved one would have. Throws CheckpointError if the
  /// integrator cannot be checkpointed (see Integrator::checkpoint_refusal) or the data do not fit.
  void save(CheckpointWriter& w) const;
  void restore(CheckpointReader& r);

private:
  /// "run became unstable at step …: WHAT. " and whether Δt is to blame.
  std::string unstable_message(const std::string& what) const;

  Model& model_;
  SolverSpec solver_;
  State state_;
  std::unique_ptr<ForceEvaluator> forces_;
  std::unique_ptr<Integrator> integrator_;
  LoadRamp ramp_;
  double dt_ = 0;
  double dt_stable_ = 0;
  double blowup_squared_ = 0;
  /// 1 for each constrained degree of freedom; fixed for the run, so built once.
  std::vector<std::uint8_t> constrained_;
  std::vector<std::uint8_t> massless_; ///< mirror dependants (no mass, no kinetic energy)
  /// Step at which the current run started; a restored run keeps the original one.
  std::size_t run_origin_ = 0;
  bool resumed_ = false;

  /// Out-of-balance force norm over the free dofs and the reference it is measured against [N].
  struct ForceBalance {
    double residual = 0;
    double reference = 0;
    double relative() const { return reference > 0 ? residual / reference : residual; }
  };
  ForceBalance force_balance() const;
  /// The tolerance for a residual measured against `reference` [N] (see steady_force_tolerance).
  double force_tolerance_for(double reference) const;
  /// The residual, its tolerance and the floor of the current state into r.
  void record_balance(RunResult& r) const;

  double residual_floor_ = 0;
};

/// ‖V b_ext‖ at the full load [N], 0 without loads: the reference force of a residual where loads
/// are applied (Simulation::force_balance, the static solver), summed exactly over the ranks.
double full_load_norm(const Model& model);

/// Why a static solve's answer is no answer, in the user's terms, as a predicate ("moves a
/// particle …"): the largest displacement of `position` (3N, y = X + u) against the body's size and
/// the largest bond strain, and, beyond the body's size or a strain of 1, that the loads ask for
/// more than the elastic range holds. A static solve has no Δt, so the explicit runs' instability
/// advice does not apply to it.
std::string static_state_report(const Model& model, const std::vector<double>& position);

} // namespace pd
