// Instability detected from energy, not only from displacements beyond the bounding box (issue 18
// item 2, issue 14 item 3). A body's kinetic energy can never exceed the energy put into it: its
// initial kinetic and strain energy plus the work of the loads and of prescribed support motion
// (damping, breaking bonds and plastic flow only take energy out). An unstable mode grows
// exponentially, so a run whose kinetic energy passes `growth` times that input is unstable, and
// the message names what grew. The watch reads the state every few steps and costs O(N) then
// (kinetic energy, load work): no bond loop, so a fraction of a percent of a step.
#pragma once

#include "libpd/discretisation/model.hpp"
#include "libpd/time/integrator.hpp"

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace pd {

class EnergyWatch {
public:
  /// Kinetic energy above this multiple of the energy put in is an instability. Generous: the
  /// work is integrated between checks with the trapezoid rule, and a growing mode passes any
  /// factor a few steps after it passes 1.
  static constexpr double growth = 10.0;
  /// Input energies below this [J] count as none: round-off alone must not look like growth.
  static constexpr double floor_joules = 1e-20;
  /// Steps between checks.
  static constexpr std::size_t every = 10;

  EnergyWatch(const Model& model, const LoadRamp& ramp, const std::vector<std::uint8_t>& massless);

  /// The run starts (or resumes) here with this much energy in the body.
  void start(const State& state, double kinetic, double strain);
  /// Adds the work done since the last call; returns why the run is unstable, or empty.
  std::string check(const State& state);

  double energy_in() const;

private:
  double kinetic(const State& state, std::size_t& fastest, double& speed) const;

  const Model& model_;
  LoadRamp ramp_;
  const std::vector<std::uint8_t>& massless_;
  std::vector<std::size_t> loaded_dofs_; ///< dofs with an external force
  std::vector<double> loaded_previous_;  ///< their positions at the last check
  std::vector<std::size_t> moved_;       ///< constraints with a prescribed non-zero value
  double previous_time_ = 0;
  double initial_ = 0;
  double work_loads_ = 0;
  double work_supports_ = 0;
  double unresolved_ = 0; ///< load work below the positions' round-off, summed over the checks
};

} // namespace pd
