// Shared machinery of the stability torture suite: scene loading, a traced run with an honest
// energy balance, and the checks every case ends with (finite fields, damage in [0, 1]).
#pragma once

#include "libpd/discretisation/model.hpp"
#include "libpd/io/scene.hpp"
#include "libpd/time/simulation.hpp"

#include <cstddef>
#include <string>
#include <vector>

namespace stab {

/// A scene of tests/stability/scenes/ by file name.
pd::Scene load(const std::string& file);

/// A traced run. Energies are sampled every `every` steps; the external work is integrated every
/// step.
struct Trace {
  pd::RunResult result;
  double e0 = 0;            ///< kinetic + strain energy after setup [J]
  double work = 0;          ///< external work injected up to the end [J]
  double energy = 0;        ///< kinetic + strain energy at the end [J]
  double max_excess = 0;    ///< max over samples of E − E0 − W [J] (> 0: energy from nowhere)
  double max_deviation = 0; ///< max over samples of |E − E0 − W| [J]
  double max_energy = 0;    ///< max over samples of E [J]
  std::vector<double> time; ///< sample times [s]
  std::vector<double> balance; ///< E − E0 − W at the samples [J]
  bool finite = true;          ///< every sampled position, velocity and force was finite
  double seconds = 0;          ///< wall time of the run
};

/// Run `scene` on `model` (built from scene.model by the caller, so that it can inspect the bond
/// state afterwards).
///
/// External work. Prescribed displacements do work through the support reactions: a constrained
/// degree of freedom that moves by Δu while the bonds pull on it with force b·V must be held by
/// the reaction −b·V, which does work −b·V·Δu (trapezoidal rule over the step). Loads do work
/// F(t)·b_ext·V·Δu. Both are integrated every step from the observer, so this is valid for
/// integrators whose State::force after a step is the force at the new positions (velocity
/// Verlet); with others the balance lags by one step.
Trace run_traced(pd::Model& model, const pd::Scene& scene, std::size_t every);

/// Energy of an undamped velocity Verlet run without loads or moving supports, started from rest.
///
/// For a linear system the sampled energy E_n = ½vᵀMv + ½uᵀKu of velocity Verlet is bounded by
/// two invariants: per mode, H̃ = ½v² + ½ω²u²(1 − h²/4) (h = ωΔt) is conserved exactly, so started
/// from rest E_n ≤ E0 always, and E_n ≥ H̃ = E0 − Σ_k (h_k²/4) E_k ≥ E0 (1 − (ω_max Δt)²/4). The dip
/// is the integrator's known error; it shrinks as Δt². The checks (gtest expectations):
///  * fields finite, run completes its steps;
///  * no growth: max (E − E0)/E0 ≤ 1e-5 (round-off and the small-strain nonlinearity);
///  * dip ≤ (ω_max Δt)²/4 with ω_max from the Lanczos estimate of the run's model;
///  * a second run at half the step (twice the steps, same end time) dips 3 to 5 times less.
struct EnergyCheck {
  double dt = 0, dt_stable = 0, omega_dt = 0;
  double excess = 0;   ///< max (E − E0)/E0
  double dip = 0;      ///< max (E0 − E)/E0
  double dip_half = 0; ///< the same at Δt/2
  std::size_t particles = 0, steps = 0;
  double seconds = 0; ///< wall time of the run at Δt
  std::string summary() const;
};
EnergyCheck check_verlet_energy(const pd::Scene& scene, std::size_t steps);

/// Every position, velocity and force of the simulation is finite.
bool fields_finite(const pd::Simulation& sim);

/// Damage checks on the bond state (gtest expectations): every particle's damage index lies in
/// [0, 1] and equals its broken-bond fraction (eq. 13), and a bond is broken in both directions or
/// in none. Returns the number of broken (undirected) bonds.
std::size_t check_damage(const pd::Model& model);

/// Miranda eq. 31 computed here from scratch, independent of the library's bond family and bond
/// field: an O(N²) neighbour search over the model's particle positions and volumes, c from the
/// closed form of the dimension (3D: c = 12E/(πδ⁴)·factor, 1D: c = 2E/(Aδ²)·factor), the weaker
/// material on bonds between two materials (Miranda §5.2.2), no surface/volume corrections.
double eq31_from_scratch(const pd::Model& model);

} // namespace stab
