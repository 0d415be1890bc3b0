// The energy bound of a run: kinetic energy against the energy put in.
#include "libpd/time/energy_watch.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <fmt/format.h>
#include <limits>

namespace pd {

EnergyWatch::EnergyWatch(const Model& model, const LoadRamp& ramp,
                         const std::vector<std::uint8_t>& massless)
    : model_(model), ramp_(ramp), massless_(massless) {
  // Each rank watches the work done on its own particles; check() adds them up exactly.
  for (std::size_t d = 0; d < model.external_force_density.size(); ++d) {
    if (model.external_force_density[d] != 0 && model.ownership.owns(d / 3)) {
      loaded_dofs_.push_back(d);
    }
  }
  for (std::size_t k = 0; k < model.constraints.size(); ++k) {
    const Constraint& c = model.constraints[k];
    // A mirror image moves with the body: it does no work on it (under `copy` coupling the
    // constraint can pump energy in, and that is exactly what this watch must catch).
    if (c.mirror_of == Constraint::no_mirror && c.value != 0 && model.ownership.owns(c.particle)) {
      moved_.push_back(k);
    }
  }
}

void EnergyWatch::start(const State& state, double kinetic, double strain) {
  initial_ = kinetic + strain;
  work_loads_ = 0;
  work_supports_ = 0;
  unresolved_ = 0;
  previous_time_ = state.time;
  loaded_previous_.resize(loaded_dofs_.size());
  for (std::size_t k = 0; k < loaded_dofs_.size(); ++k) {
    loaded_previous_[k] = state.position[loaded_dofs_[k]];
  }
}

double EnergyWatch::energy_in() const {
  return initial_ + std::abs(work_loads_) + std::abs(work_supports_);
}

double EnergyWatch::kinetic(const State& state, std::size_t& fastest, double& speed) const {
  ExactSum ke;
  double top = -1;
  for (std::size_t i = 0; i < model_.size(); ++i) {
    if (massless_[i] || !model_.ownership.owns(i)) {
      continue;
    }
    const double* v = &state.velocity[3 * i];
    const double v2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
    ke.add(0.5 * model_.density[i] * model_.particles.volume[i] * v2);
    if (!(v2 <= top)) { // NaN counts as fastest
      top = v2;
      fastest = i;
    }
  }
  speed = std::sqrt(top);
  return model_.ownership.communicator().sum(ke);
}

std::string EnergyWatch::check(const State& state) {
  // Work since the last check, trapezoid rule in the load factor: W = F̄ · Δy for the loads,
  // R · Δū for supports that move (R = −(b V + F b_ext V), the force the support applies).
  const double f0 = ramp_.factor(previous_time_), f1 = ramp_.factor(state.time);
  const double mean = 0.5 * (f0 + f1);
  std::array<ExactSum, 3> work; // of the loads, of the moving supports, unseen (below)
  for (std::size_t k = 0; k < loaded_dofs_.size(); ++k) {
    const std::size_t d = loaded_dofs_[k];
    const double force = mean * model_.external_force_density[d] * model_.particles.volume[d / 3];
    work[0].add(force * (state.position[d] - loaded_previous_[k]));
    loaded_previous_[k] = state.position[d];
  }
  // A particle moving less than half an ulp of its position per step does not move at all: the
  // work its force does (a load's, or a stiff bond's on round-off strain) is then seen nowhere,
  // while the kinetic energy it feeds is seen in full. Unseen, per component: the force times
  // the motion its velocity makes, up to the rounding of every step since the last check. An
  // unstable mode soon outgrows that bound: it grows exponentially, the bound linearly.
  const double elapsed = state.time - previous_time_;
  constexpr double eps = std::numeric_limits<double>::epsilon();
  for (std::size_t i = 0; i < model_.size(); ++i) {
    if (massless_[i] || !model_.ownership.owns(i)) {
      continue;
    }
    for (std::size_t d = 3 * i; d < 3 * i + 3; ++d) {
      const double ext =
          model_.external_force_density.empty() ? 0.0 : f1 * model_.external_force_density[d];
      const double force = (state.force[d] + ext) * model_.particles.volume[i];
      const double rounding = static_cast<double>(every) * eps * std::abs(state.position[d]);
      work[2].add(std::abs(force) * std::min(std::abs(state.velocity[d]) * elapsed, rounding));
    }
  }
  for (const std::size_t k : moved_) {
    const Constraint& c = model_.constraints[k];
    const std::size_t d = 3 * c.particle + c.component;
    const double volume = model_.particles.volume[c.particle];
    const double ext = model_.external_force_density.empty()
                           ? 0.0
                           : f1 * model_.external_force_density[d] * volume;
    const double reaction = -(state.force[d] * volume + ext);
    work[1].add(reaction * c.value * (f1 - f0));
  }
  model_.ownership.communicator().sum(work);
  work_loads_ += work[0].value();
  work_supports_ += work[1].value();
  unresolved_ += work[2].value();
  previous_time_ = state.time;

  std::size_t fastest = 0;
  double speed = 0;
  const double ke = kinetic(state, fastest, speed);
  const double in = energy_in();
  if (ke <= growth * (in + unresolved_) + floor_joules) {
    return {};
  }
  const Vec3& x = model_.particles.position[fastest];
  return fmt::format(
      "kinetic energy {:.3g} J is {} the energy put in ({:.3g} J: initial {:.3g} J, work of the "
      "loads {:.3g} J, of moving supports {:.3g} J); the fastest particle, #{} at ({:.4g}, "
      "{:.4g}, {:.4g}) m, moves at {:.3g} m/s",
      ke, in > 0 ? fmt::format("{:.3g}×", ke / in) : std::string("more than"), in, initial_,
      work_loads_, work_supports_, model_.ownership.global(fastest), x[0], x[1], x[2], speed);
}

} // namespace pd
