// Displacement-controlled quasi-static loading for the quasi-brittle cases (rc-beam,
// compression-cube): the prescribed displacements of a scene are applied in equal increments and
// each increment is relaxed with adaptive dynamic relaxation until the out-of-balance force is
// small, so the recorded load–displacement curve is a sequence of equilibrium states with damage
// (Miranda §5.2 loads with a slow ramp under kinematic damping, §3.2; relaxing every increment is
// the quasi-static limit of that ramp and does not depend on a damping coefficient).
//
// Why not a ramp with `steady:`: one ramp gives one steady state at the end; the curve needs the
// equilibrium at every increment. The driver therefore owns the Model and rewrites the prescribed
// values of its constraints between increments (apply_constraints reads them every step).
//
// Each increment: (1) linear predictor — the free particles are moved by the displacement change
// of the previous increment (Simulation::perturb) while the prescribed values jump to the new
// level, so that the bonds next to the moved supports are not stretched by a one-sided jump (a
// jump of Δu over one spacing λ is a stretch Δu/λ, far beyond s0 ≈ 1e-4, and would break bonds
// that equilibrium would never break); the first increment, which has no predictor, moves its
// prescribed values over `first_ramp_iterations` ADR iterations instead; (2) relaxation until
// ‖free-dof force‖ ≤ tol · max(‖reactions‖, 5 % of the largest ‖reactions‖ so far) or
// `max_iterations`. Bonds break during the relaxation, so
// a crack that propagates unstably does so inside the increment, as under displacement control.
//
// Plastic flow within an increment: ADR's iterations are a fictitious path, so for the
// virtual-fibre model each arm's plastic stretch is recomputed at every evaluation from its value
// at the increment's start (BondState::plastic_stretch_at_increment_start), and the increment's
// converged state alone fixes it. The bond-based kernels' micro-plastic bonds would still
// accumulate it along the path; no quasi-static case uses them (rc-beam and compression-cube
// have brittle bonds).
//
// Method::static_ instead solves each level with the static solver, which breaks bonds in events
// at equilibrium (time/static_solver.cpp); the observer sees the same Simulation interface.
#pragma once

#include "libpd/discretisation/model.hpp"
#include "libpd/time/simulation.hpp"

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace pd::quasi_static {

/// How each load level is brought to equilibrium.
enum class Method {
  adr,    ///< relaxed by ADR (above): bonds break as their stretch passes s0 during relaxation
  static_ ///< solved by the static solver (time/static_solver.cpp): Newton on the unbroken
          ///< bonds, then break events (every bond beyond s0) and re-solves at the same level
};

struct Settings {
  /// Levels of the prescribed displacement, as fractions of the scene's values, increasing.
  std::vector<double> levels;
  Method method = Method::adr; ///< the iteration settings below are ADR's
  /// The first increment has no predictor: its prescribed values move over this many iterations.
  std::size_t first_ramp_iterations = 200;
  std::size_t max_iterations = 400; ///< per increment, ramp included
  std::size_t check_every = 10;
  double residual_tolerance = 1e-3;
  double wall_limit_seconds = 0; ///< stop after the increment that crosses it; 0: none
  bool progress = false;
  /// Checked after every increment; true ends the run early (e.g. a sweep that only needs the
  /// peak). Empty: run all increments.
  std::function<bool(const Simulation&)> done;
};

struct IncrementInfo {
  int index = 0;              ///< 1-based
  double fraction = 0;        ///< of the full prescribed displacement
  std::size_t iterations = 0; ///< ADR iterations; static: Newton iterations of the last solve
  double residual = 0; ///< ‖free-dof force‖ / ‖reactions‖ at the end of the increment
  bool converged = false;
  std::size_t break_events = 0; ///< static: re-solves at this level after bonds broke
};

struct Outcome {
  std::vector<IncrementInfo> increments;
  bool completed = false; ///< all increments done (not stopped by the wall limit or instability)
  std::string stop_reason;
  double wall_seconds = 0;
  std::size_t iterations = 0;
};

/// Σ b_c V over the particles: the force the bonds exert on them (the support supplies −that).
double bond_force(const Simulation& sim, const std::vector<std::uint32_t>& particles,
                  int component);

/// Particles of a region (any body), as the model resolves supports.
std::vector<std::uint32_t> particles_in(const Model& model, const Region& region);

/// Broken bonds (each counted once).
std::size_t broken_bonds(const Model& model);

/// Called after every increment with its equilibrium state: the caller records it (a curve row,
/// a VTU file). The driver itself writes nothing.
using IncrementObserver = std::function<void(const Simulation&, const IncrementInfo&)>;

/// Run the model (its constraints' values are the full prescribed displacements) through
/// `settings.levels` with the solver settings of the scene (the integrator is replaced by ADR)
/// and its initial state.
Outcome run(Model& model, const SolverSpec& solver, const InitialSpec& initial,
            const Settings& settings, const IncrementObserver& after_increment);

} // namespace pd::quasi_static
