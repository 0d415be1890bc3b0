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
//
// run_fracture is the path of a scene (`integrator: static` with damage): sequentially linear,
// one bond (or a tie) per break at the load where it reaches s0, so that its failure load depends
// on neither a rate nor the levels. The built-in cases keep run() (rc-beam breaks 5,400 bonds in
// its first increment: two solves per bond would cost hours).
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

/// Quasi-static fracture, the path of a scene with `integrator: static` and damage (issue 36):
/// the scene's prescribed displacements and loads scaled by each level in turn, every state an
/// equilibrium solved by the static solver, bonds broken one group at a time (run_fracture).
struct FracturePoint {
  std::size_t level = 0;        ///< the level (1-based) the driver is on its way to
  double load_factor = 0;       ///< of the scene's prescribed displacements and loads
  bool critical = false;        ///< the most overstretched bonds are at s0 here and break after it
  std::size_t bonds_broken = 0; ///< bonds broken so far, this point's breaks included
  double dissipated_energy = 0; ///< Σ over them of the energy each stored as it broke [J]
  std::size_t breaking = 0;     ///< bonds that break at this (critical) point
};

struct FractureSettings {
  std::vector<double> levels; ///< increasing fractions of the scene's values, the last ≤ 1 is up
                              ///< to the caller (usually 1)
  /// Checked before every solve; true ends the run (an interrupt).
  std::function<bool()> stop_requested;
};

struct FractureOutcome {
  enum class End {
    completed,     ///< every level reached in equilibrium
    stopped,       ///< the observer or stop_requested ended it
    no_equilibrium ///< after bonds broke no equilibrium exists at the load: the specimen failed
  } end = End::completed;
  std::string message;
  std::size_t solves = 0;
  std::size_t break_events = 0;
  std::size_t bonds_broken = 0;
  double dissipated_energy = 0; ///< [J]
  double peak_load_factor = 0;  ///< the largest load factor of an equilibrium with its bonds
};

/// Called with every recorded equilibrium: each level reached, and each critical state before
/// its bonds break. Returns false to stop the run (solver.stop_when).
using FractureObserver = std::function<bool(const Simulation&, const FracturePoint&)>;

/// Sequentially linear fracture on `sim` (a static-solver Simulation of `model`, damage on).
/// Through each level: solve; if bonds are beyond s0, scale the level down to where the most
/// overstretched one is exactly at s0 (stretch is linear in the level on a fixed set of bonds),
/// solve there, record that critical state and break that bond (and those within a relative
/// 1e-6 of it), then solve again at the level; repeat until no bond is beyond s0. Ladder levels
/// only decide where equilibria are recorded between breaks: the sequence of critical states, and
/// so the failure load, is that of the bonds alone (to the kernel's nonlinearity in the stretch).
FractureOutcome run_fracture(Simulation& sim, Model& model, const FractureSettings& settings,
                             const FractureObserver& observer);

/// Run the model (its constraints' values are the full prescribed displacements) through
/// `settings.levels` with the solver settings of the scene (the integrator is replaced by ADR)
/// and its initial state.
Outcome run(Model& model, const SolverSpec& solver, const InitialSpec& initial,
            const Settings& settings, const IncrementObserver& after_increment);

} // namespace pd::quasi_static
