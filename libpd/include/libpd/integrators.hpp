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
#pragma once

#include "libpd/force_kernel.hpp"
#include "libpd/model.hpp"

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

namespace pd {

enum class IntegratorKind { damped_euler, euler_cromer, verlet };

std::string to_string(IntegratorKind kind);

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

class Integrator {
public:
  virtual ~Integrator() = default;
  /// Advance the state by dt.
  virtual StepReport step(State& state, double dt) = 0;
  virtual std::string name() const = 0;
  std::size_t force_evaluations() const { return force_evaluations_; }

protected:
  std::size_t force_evaluations_ = 0;
};

struct IntegratorSettings {
  IntegratorKind kind = IntegratorKind::damped_euler;
  double damping = 0; ///< c_v [kg/(m³ s)], damped-euler only
  LoadRamp ramp;
};

std::unique_ptr<Integrator> make_integrator(const IntegratorSettings& settings, Model& model,
                                            ForceEvaluator& forces);

/// Apply prescribed displacements at time t to positions (and velocities if given).
void apply_constraints(const Model& model, const LoadRamp& ramp, double t, double* position,
                       double* velocity);

} // namespace pd
