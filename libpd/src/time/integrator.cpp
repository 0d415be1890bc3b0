// What every integrator shares: the checkpointed counters, prescribed and mirror displacements,
// the displacement report, and the factory that picks a scheme. Each scheme has its own file
// (damped_euler.cpp, verlet.cpp, adr.cpp, arkode.cpp).
#include "libpd/time/integrator.hpp"

#include "libpd/core/binary_state.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <limits>
#include <stdexcept>

namespace pd {

std::string to_string(IntegratorKind kind) {
  return std::string(name_of(kind));
}

std::string to_string(ArkodeTable table) {
  return std::string(name_of(table));
}

void Integrator::save(CheckpointWriter& w) const {
  w.section("INTG");
  w.string(name());
  w.u64(force_evaluations_);
  w.u64(calls_);
  save_state(w);
}

void Integrator::restore(CheckpointReader& r) {
  r.section("INTG");
  const std::string saved = r.string();
  if (saved != name()) {
    r.fail(fmt::format("written by integrator '{}', this run uses '{}'", saved, name()));
  }
  force_evaluations_ = r.u64();
  calls_ = r.u64();
  restore_state(r);
}

double kinematic_damping_amplification(const Model& model, double damping, double dt) {
  if (!(damping > 0) || model.density.empty()) {
    return 1.0;
  }
  const double rho = model.ownership.communicator().max(
      *std::max_element(model.density.begin(), model.density.end()));
  const double loss = dt * damping / rho / (1.0 + dt * damping / rho); // 1 − ψ
  return std::max(1.0, 0.5 / std::sqrt(loss));
}

std::vector<std::uint8_t> held_dofs(const Model& model) {
  std::vector<std::uint8_t> held(3 * model.size(), 0);
  for (const Constraint& c : model.constraints) {
    held[3 * c.particle + c.component] = 1;
  }
  for (const std::uint32_t d : model.extrapolated.particle) {
    held[3 * d] = held[3 * d + 1] = held[3 * d + 2] = 1;
  }
  return held;
}

void apply_constraints(const Model& model, const LoadRamp& ramp, double t, double* position,
                       double* velocity) {
  // A rank's halo copies take their owners' values first: the dependants below may be set from
  // them (ownership.hpp).
  if (const Ownership& own = model.ownership; !own.halo.empty()) {
    own.communicator().exchange(own.halo, position, 3);
    if (velocity != nullptr) {
      own.communicator().exchange(own.halo, velocity, 3);
    }
  }
  const double factor = ramp.factor(t);
  const double rate = ramp.rate(t);
  const auto& x = model.particles.position;
  for (const Constraint& c : model.constraints) {
    const std::size_t dof = 3 * c.particle + c.component;
    if (c.mirror_of != Constraint::no_mirror) { // sources are free particles, already updated
      const std::size_t src = 3 * c.mirror_of + c.component;
      position[dof] = x[c.particle][c.component] +
                      c.mirror_sign * (position[src] - x[c.mirror_of][c.component]);
      if (velocity != nullptr) {
        velocity[dof] = c.mirror_sign * velocity[src];
      }
      continue;
    }
    position[dof] = x[c.particle][c.component] + factor * c.value;
    if (velocity != nullptr) {
      velocity[dof] = rate * c.value;
    }
  }
  // Extrapolated particles (ghost_layers.hpp) last: their sources may be prescribed.
  const ExtrapolatedParticles& e = model.extrapolated;
  for (std::size_t d = 0; d < e.size(); ++d) {
    const std::size_t p = e.particle[d];
    double du[3] = {0, 0, 0};
    double dv[3] = {0, 0, 0};
    for (std::size_t term = e.offsets[d]; term < e.offsets[d + 1]; ++term) {
      const std::size_t s = e.source[term];
      for (std::size_t c = 0; c < 3; ++c) {
        const double a = e.sign(term, c) * e.coefficient[term];
        du[c] += a * (position[3 * s + c] - x[s][c]);
        if (velocity != nullptr) {
          dv[c] += a * velocity[3 * s + c];
        }
      }
    }
    for (std::size_t c = 0; c < 3; ++c) {
      position[3 * p + c] = x[p][c] + du[c];
      if (velocity != nullptr) {
        velocity[3 * p + c] = dv[c];
      }
    }
  }
}

StepReport displacement_report(const Model& m, const double* y) {
  const auto n = static_cast<std::ptrdiff_t>(m.size());
  double worst = 0;
  bool finite = true;
#pragma omp parallel for schedule(static) reduction(max : worst) reduction(&& : finite) \
    if (m.size() >= parallel_min_particles)
  for (std::ptrdiff_t ii = 0; ii < n; ++ii) {
    const auto i = static_cast<std::size_t>(ii);
    double u2 = 0;
    for (int c = 0; c < 3; ++c) {
      const double u = y[3 * i + c] - m.particles.position[i][c];
      finite = finite && std::isfinite(u); // u² may overflow while u is still finite
      u2 += u * u;
    }
    worst = std::max(worst, u2);
  }
  StepReport r;
  r.max_displacement_squared =
      m.ownership.communicator().max(finite ? worst : std::numeric_limits<double>::quiet_NaN());
  return r;
}

std::unique_ptr<Integrator> make_integrator(const IntegratorSettings& s, Model& model,
                                            ForceEvaluator& forces) {
  switch (s.kind) {
  case IntegratorKind::damped_euler:
  case IntegratorKind::euler_cromer:
    return make_damped_euler_integrator(s, model, forces);
  case IntegratorKind::verlet:
    return make_verlet_integrator(s, model, forces);
  case IntegratorKind::adr:
    return make_adr_integrator(s, model, forces);
  case IntegratorKind::arkode:
    return make_arkode_integrator(s, model, forces);
  case IntegratorKind::static_solve:
    return make_static_solver(s, model, forces);
  }
  throw std::logic_error("unknown integrator");
}

} // namespace pd
