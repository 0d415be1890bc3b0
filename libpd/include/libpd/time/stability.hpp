// Stability limits of the explicit integrators, predicted and measured.
//
// Predictions. The conservative one is Miranda eq. 31 (`stable_time_step`, a Gershgorin bound).
// The sharp one comes from the largest frequency ω_max of the linearised PD operator (Miranda
// eq. 30, bond operator C = c ξ⊗ξ/|ξ|³ per unit neighbour volume) with the supports removed from
// the free degrees of freedom: central differences (Verlet, Euler–Cromer) are stable for
// Δt ≤ 2/ω_max; a Runge–Kutta table applied to y' = [v; −ω² u] is stable for Δt ≤ β/ω_max with β
// the imaginary-axis stability interval of its stability polynomial R(z) (√3 for 3-stage order-3
// tables, 2√2 for 4-stage order-4 tables), computed here from the Butcher table itself.
//
// Measurement. Bisection on a fixed Δt: a bounded run of N steps without loads or damping from a
// small random perturbation of the free degrees of freedom is unstable if its energy grows by more
// than a threshold or any value becomes non-finite.
#pragma once

#include "libpd/discretisation/model.hpp"
#include "libpd/kernel/spectrum.hpp"
#include "libpd/time/integrator.hpp"
#include "libpd/time/simulation.hpp"

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace pd {

/// Coefficients γ_k of R(z) = Σ_k γ_k z^k for an explicit table: γ_0 = 1, γ_k = bᵀ A^{k−1} 1.
std::vector<double> stability_polynomial(const ButcherTableau& table);
/// |R(iy)| for the polynomial's coefficients.
double stability_modulus_on_imaginary_axis(const std::vector<double>& gamma, double y);
/// Largest β such that |R(iy)| ≤ 1 for all y ∈ [0, β]; 0 if there is none (|R(iy)| > 1 for
/// small y, as for Heun–Euler, Cash–Karp and Fehlberg 4(5)).
double imaginary_stability_interval(const ButcherTableau& table);

/// Largest Δt at which a bounded run of `steps` steps from the perturbation keeps its energy
/// within `growth` × the initial one, if each mode's energy is multiplied by
/// exp(2 N log_amplification(ω Δt)) (log |R(iy)| of an RK table, or of the growing root of
/// central differences): the sharp prediction of what `measure_stability` measures.
double bounded_run_limit(const PerturbationSpectrum& spectrum,
                         const std::function<double(double)>& log_amplification, std::size_t steps,
                         double growth);
/// log |μ| of the larger root of central differences (Verlet) for y = ω Δt: 0 up to y = 2.
double central_difference_log_amplification(double y);

/// What to measure: an integrator, and for arkode its table (fixed steps).
struct StabilityTarget {
  IntegratorKind kind = IntegratorKind::verlet;
  ArkodeTable table = ArkodeTable::rk4;
  std::string label() const;
};

/// Fewest steps a bounded run may have: near the limit a mode grows by a factor close to 1 per
/// step, so a shorter run calls almost any Δt stable.
inline constexpr std::size_t min_stability_steps = 100;

struct StabilityOptions {
  std::size_t steps = 1000; ///< N, steps of each bounded run
  double growth = 1e3;      ///< unstable when the energy exceeds growth × its initial value
  double relative_tolerance = 0.01; ///< bisection stops when hi/lo < 1 + this
  double perturbation = 1e-6;       ///< amplitude of the random initial displacement, × spacing
  std::uint64_t seed = 1;
};

struct StabilityResult {
  std::string integrator;     ///< "verlet", "arkode:rk4", …
  double measured = 0;        ///< largest Δt found stable [s]
  double unstable = 0;        ///< smallest Δt found unstable [s]
  double eq31 = 0;            ///< Miranda eq. 31 [s]
  double sharp = 0;           ///< 2/ω_max or β/ω_max [s]
  double interval = 0;        ///< 2 (central differences) or β of the table
  double sharp_finite = 0;    ///< bounded_run_limit for the run's N, growth and perturbation
  double interval_finite = 0; ///< sharp_finite × ω_max
  double omega_max = 0;
  int runs = 0;
  double seconds = 0;
};

/// The model a stability measurement runs: the scene's, without loads, damping or body force.
ModelSpec stability_model(const ModelSpec& spec);
/// Bisection of the largest stable fixed Δt (see the file comment); omega_max > 0 skips the
/// eigenvalue estimate (it depends only on the model).
StabilityResult measure_stability(const ModelSpec& model, const SolverSpec& solver,
                                  const StabilityTarget& target, const StabilityOptions& options,
                                  double omega_max = 0);

} // namespace pd
