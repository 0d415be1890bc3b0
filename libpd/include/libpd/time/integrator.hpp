// Explicit time integrators. All share one interface so that a run, a verification case or the
// stability bisection can swap them; each reports the same counters.
//
//  damped-euler  Miranda §3.2: semi-implicit Euler with kinematic damping
//                v ← ψ [v + Δt a],  y ← y + Δt v,  ψ = (1 + Δt c_v/ρ)⁻¹ (eq. 32), loads and
//                prescribed displacements ramped with F = min(t/t_max, 1) (eq. 33).
//  euler-cromer  the same without damping (Pasupathy eq. 6 as Euler–Cromer: the position update
//                uses the new velocity; with the old one, as eq. 6 is printed, the scheme is
//                forward Euler and unconditionally unstable for an undamped oscillator).
//  verlet        velocity Verlet, second order and symplectic; for dynamics and energy checks.
//  adr           adaptive dynamic relaxation (Kilic & Madenci 2010; time/adr.cpp): central
//                differences in fictitious time (Δt = 1) with a fictitious diagonal density from
//                the Gershgorin bound of the stiffness and a damping coefficient from the Rayleigh
//                quotient of the local stiffness, recomputed every step. Quasi-static only.
//  arkode        SUNDIALS ARKode ERKStep on y = [u; v], y' = [v; a(u, v, t)]
//                (time/arkode.cpp): a Butcher table, fixed or adaptive steps, kinematic
//                damping as a term of the right-hand side. Needs LIBPD_WITH_SUNDIALS.
#pragma once

#include "libpd/core/json.hpp"
#include "libpd/core/names.hpp"
#include "libpd/discretisation/model.hpp"
#include "libpd/kernel/force_kernel.hpp"

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

namespace pd {

enum class IntegratorKind { damped_euler, euler_cromer, verlet, adr, arkode, static_solve };

template <>
struct EnumName<IntegratorKind> {
  static constexpr NameTable<IntegratorKind, 6> table{{
      {"damped-euler", IntegratorKind::damped_euler, "explicit Euler with kinematic damping"},
      {"euler-cromer", IntegratorKind::euler_cromer, "symplectic Euler, no damping"},
      {"verlet", IntegratorKind::verlet, "velocity Verlet, no damping"},
      {"adr", IntegratorKind::adr, "adaptive dynamic relaxation (Kilic & Madenci 2010)"},
      {"arkode", IntegratorKind::arkode, "SUNDIALS ARKode ERKStep with a Butcher table"},
      {"static", IntegratorKind::static_solve,
       "equilibrium by a sparse solve refined by Newton; with damage, quasi-static fracture "
       "in load levels (solver.load_steps)"},
  }};
};

std::string to_string(IntegratorKind kind);

/// Butcher tables offered for `arkode` (their scene words: EnumName<ArkodeTable> below).
/// Only tables that compute correctly with SUNDIALS 6.4.1 are offered: the native tables whose
/// last node c_s ≠ 1 or that are truly FSAL (last row of A = bᵀ), and two tables hit by upstream
/// issue #311 (c_s = 1, not FSAL) that run with the reset work-around (see ArkodeSpec).
enum class ArkodeTable {
  heun_euler,       ///< ARKODE_HEUN_EULER_2_1_2, order 2(1); c_s = 1, not FSAL: work-around
  bogacki_shampine, ///< ARKODE_BOGACKI_SHAMPINE_4_2_3, order 3(2), FSAL
  knoth_wolke,      ///< ARKODE_KNOTH_WOLKE_3_3, order 3, c_s = 3/4, no embedding
  rk4,              ///< classic 4-stage RK4 (Kutta 1901), c_s = 1, not FSAL: work-around
  zonneveld,        ///< ARKODE_ZONNEVELD_5_3_4, order 4(3), c_s = 3/4
  cash_karp,        ///< ARKODE_CASH_KARP_6_4_5, order 5(4), c_s = 7/8
  fehlberg,         ///< ARKODE_FEHLBERG_6_4_5, order 5(4), c_s = 1/2
  dormand_prince,   ///< ARKODE_DORMAND_PRINCE_7_4_5, order 5(4), FSAL
};

template <>
struct EnumName<ArkodeTable> {
  static constexpr NameTable<ArkodeTable, 8> table{{
      {"heun-euler", ArkodeTable::heun_euler, "order 2(1)"},
      {"bogacki-shampine", ArkodeTable::bogacki_shampine, "order 3(2)"},
      {"knoth-wolke", ArkodeTable::knoth_wolke, "order 3, no embedding"},
      {"rk4", ArkodeTable::rk4, "classic RK4, no embedding"},
      {"zonneveld", ArkodeTable::zonneveld, "order 4(3)"},
      {"cash-karp", ArkodeTable::cash_karp, "order 5(4)"},
      {"fehlberg", ArkodeTable::fehlberg, "order 5(4)"},
      {"dormand-prince", ArkodeTable::dormand_prince, "order 5(4)"},
  }};
};
inline constexpr int arkode_table_count = static_cast<int>(EnumName<ArkodeTable>::table.size());
std::string to_string(ArkodeTable table);

/// An explicit Butcher table (c, A, b and the embedding d), as handed to SUNDIALS.
struct ButcherTableau {
  std::string name;
  int stages = 0;
  int order = 0;
  int embedded_order = 0; ///< 0: no embedding (fixed steps only)
  std::vector<double> c;  ///< s nodes
  std::vector<double> a;  ///< s × s, row-major, strictly lower triangular
  std::vector<double> b;  ///< s weights
  std::vector<double> d;  ///< s embedding weights (empty without embedding)
  /// c_s = 1 but the last row of A differs from bᵀ: SUNDIALS 6.4.1 (issue #311, fixed in 6.7.0)
  /// reuses f at the last stage as f(y_{n+1}) for such tables.
  bool hit_by_issue_311() const;
};

/// Coefficients of one of the offered tables (from SUNDIALS' own table for the native ones).
/// Throws std::runtime_error if libpd was built without SUNDIALS.
ButcherTableau butcher_tableau(ArkodeTable table);
/// A native SUNDIALS ERK table by its ARKODE_ERKTableID number (tests of tables not offered).
ButcherTableau sundials_erk_tableau(int table_id);
/// Whether libpd was built with SUNDIALS (LIBPD_WITH_SUNDIALS and the package found).
bool arkode_available();

/// `solver.arkode`: options of the ARKode ERKStep integrator.
struct ArkodeSpec {
  ArkodeTable table = ArkodeTable::rk4;
  bool adaptive = false; ///< false: fixed steps of solver.dt; true: error control inside each dt
  double rtol = 1e-6;    ///< relative tolerance (adaptive only)
  double atol = 1e-12;   ///< absolute tolerance on u [m] and v [m/s] (adaptive only)
  /// Work around SUNDIALS issue #311 for tables with c_s = 1 that are not FSAL by resetting the
  /// integrator (ERKStepReset) before every step, so that the first stage is f(y_n) recomputed.
  /// Only tests switch it off, to demonstrate the defect.
  bool issue_311_workaround = true;
};

/// Positions, velocities and the last internal force density of every particle.
struct State {
  std::vector<double> position; ///< y = X + u, 3N
  std::vector<double> velocity; ///< 3N
  std::vector<double> force;    ///< internal force density b at the last evaluation, 3N
  double time = 0;
  std::size_t step = 0;
};

/// Load factor F(t) = min(t/t_ramp, 1) (eq. 33); F = 1 without a ramp.
struct LoadRamp {
  double ramp_time = 0;
  double factor(double t) const {
    return ramp_time > 0 ? (t < ramp_time ? t / ramp_time : 1.0) : 1.0;
  }
  double rate(double t) const { return ramp_time > 0 && t < ramp_time ? 1.0 / ramp_time : 0.0; }
};

struct StepReport {
  /// Largest squared displacement |y − X|² after the step; NaN if any value is non-finite.
  double max_displacement_squared = 0;
  std::size_t max_displacement_particle = 0;
};

class CheckpointWriter;
class CheckpointReader;

class Integrator {
public:
  virtual ~Integrator() = default;
  /// Advance the state by dt (ADR: one iteration in fictitious time; the state's time still
  /// advances by dt, so loads ramp over iterations as over steps).
  virtual StepReport step(State& state, double dt) = 0;
  virtual std::string name() const = 0;
  std::size_t force_evaluations() const { return force_evaluations_; }
  /// Steps taken by the method itself; differs from the calls to step() only for adaptive ARKode.
  virtual std::size_t internal_steps() const { return calls_; }
  /// Imaginary-axis stability interval of the method divided by that of central differences (2):
  /// the factor on the eq. 31 step that keeps the same margin. 1 for the Störmer-type schemes.
  virtual double stability_scale() const { return 1.0; }
  /// How far above the residual's round-off floor (kernel/round_off.hpp) the method settles with
  /// steps of dt: every step rounds the positions afresh, and the damping per step decides how much
  /// of that noise the modes keep. 1 for a method that adds none (static) or never settles (no
  /// damping).
  virtual double round_off_amplification(double /*dt*/) const { return 1.0; }

  /// Checkpoints: everything the next step() reads besides the State and the model's bond
  /// history (counters, the integrator's own vectors and flags), so that a restored run continues
  /// bitwise. save() writes the name and counters, then save_state(); restore() reads them back and
  /// refuses a checkpoint of another integrator.
  void save(CheckpointWriter& w) const;
  void restore(CheckpointReader& r);
  /// Empty if a checkpoint can continue this integrator bitwise; otherwise the reason it cannot.
  virtual std::string checkpoint_refusal() const { return {}; }
  /// True once the method has its answer and further steps would change nothing (static).
  virtual bool finished() const { return false; }
  /// What the method did, for the run's summary (empty: nothing to say).
  virtual std::string report() const { return {}; }
  /// The same as numbers, for summary.json's `integrator_details` (null: nothing to say).
  virtual Json summary() const { return {}; }

protected:
  virtual void save_state(CheckpointWriter&) const {}
  virtual void restore_state(CheckpointReader&) {}

  std::size_t force_evaluations_ = 0;
  std::size_t calls_ = 0;
};

struct IntegratorSettings {
  IntegratorKind kind = IntegratorKind::damped_euler;
  double damping = 0; ///< c_v [kg/(m³ s)]: damped-euler, and arkode as a right-hand-side term
  LoadRamp ramp;
  ArkodeSpec arkode;
  /// Step bound handed to ERKStepSetStabilityFn for adaptive ARKode [s]; 0: none.
  double stable_dt = 0;
  double cfl_fraction = 0.8; ///< fraction of stable_dt the adaptive controller may use
  /// static: the residual, relative to the load, the solve must reach (the scene's
  /// solver.steady.force_tolerance, which dynamic relaxation is held to); 0: the solver's own.
  double force_tolerance = 0;
};

/// Throws std::invalid_argument for combinations that cannot run (arkode without SUNDIALS, with
/// damage or plasticity, adaptive without an embedding).
std::unique_ptr<Integrator> make_integrator(const IntegratorSettings& settings, Model& model,
                                            ForceEvaluator& forces);
/// The factories of each integrator's own file (make_integrator picks one by settings.kind).
std::unique_ptr<Integrator> make_damped_euler_integrator(const IntegratorSettings& settings,
                                                         Model& model, ForceEvaluator& forces);
std::unique_ptr<Integrator> make_verlet_integrator(const IntegratorSettings& settings, Model& model,
                                                   ForceEvaluator& forces);
std::unique_ptr<Integrator> make_adr_integrator(const IntegratorSettings& settings, Model& model,
                                                ForceEvaluator& forces);
std::unique_ptr<Integrator> make_arkode_integrator(const IntegratorSettings& settings, Model& model,
                                                   ForceEvaluator& forces);
std::unique_ptr<Integrator> make_static_solver(const IntegratorSettings& settings, Model& model,
                                               ForceEvaluator& forces);

/// ADR's fictitious density λ per degree of freedom (3N): ¼ Δt² times the Gershgorin row sum of
/// the linearised bond operator, Δt = 1 (time/adr.cpp).
std::vector<double> adr_fictitious_density(const Model& model);

/// round_off_amplification of a scheme with kinematic damping c_v that rounds the positions once
/// per step of dt: 1/(2 √(1 − ψ)) for the least damped particle (the densest), with
/// ψ = (1 + Δt c_v/ρ)⁻¹. A mode keeps the energy ½ω²σ² that each step's rounding (variance σ²)
/// adds until the damping takes 2(1 − ψ) of it per step, so its amplitude settles at
/// σ/(2√(1 − ψ)). Damped Euler on a 2D steel cantilever at three dampings: 12.7, 30 and 62× the
/// floor measured against 14.4, 24.9 and 49.9 predicted. At least 1.
double kinematic_damping_amplification(const Model& model, double damping, double dt);

/// Largest |u|² over particles (may be +inf), NaN as soon as any coordinate is not finite.
StepReport displacement_report(const Model& model, const double* y);

/// Per dof: 1 where the dof is not an unknown of the equations of motion: held by a support
/// (fixed, prescribed or a mirror image) or belonging to an extrapolated particle (ghosts,
/// quadratic clamps), which apply_constraints sets from its sources. Their force entries are
/// reactions, never residuals.
std::vector<std::uint8_t> held_dofs(const Model& model);

/// Apply prescribed displacements at time t to positions (and velocities if given).
void apply_constraints(const Model& model, const LoadRamp& ramp, double t, double* position,
                       double* velocity);

} // namespace pd
