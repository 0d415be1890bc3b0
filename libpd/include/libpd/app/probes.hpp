// Probes of a run: the scene's probe specs bound to particles, their values on a simulation, and
// the history of those values that becomes probes.csv.
#pragma once

#include "libpd/io/scene.hpp"
#include "libpd/time/simulation.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace pd {

/// A probe bound to particles: the mean of one quantity over them (a displacement component,
/// the normal stress σ_cc, the damage index), or for a reaction the sum over the support's
/// particles held in that component.
struct ResolvedProbe {
  std::string name;
  int component = 0;
  std::vector<std::uint32_t> particles;
  ProbeSpec::Quantity quantity = ProbeSpec::Quantity::displacement;
  std::vector<std::uint8_t> dependant; ///< stress: the model's massless dependants
  /// Particles the probe averages over, on all ranks together (particles.size() in one process).
  std::size_t count = 0;
};

std::vector<ResolvedProbe> resolve_probes(const std::vector<ProbeSpec>& probes, const Model& model);
/// The probes of the whole model, resolved by resolve_probes, restricted to the particles
/// `local` owns (its part of a run split over ranks, discretisation/distribution.hpp).
std::vector<ResolvedProbe> localise_probes(std::vector<ResolvedProbe> probes, const Model& local);
double probe_value(const ResolvedProbe& probe, const Simulation& sim);

struct ProbeHistory {
  std::vector<double> time;
  std::vector<std::vector<double>> values; ///< one row per sample, one column per probe

  /// Append the probes' values at the simulation's current time.
  void record(const std::vector<ResolvedProbe>& probes, const Simulation& sim);
  /// The rows whose values are all finite: after an instability the last rows may hold huge
  /// (but finite) values, and a file written from this never carries NaN or inf.
  ProbeHistory finite_rows() const;
};

/// probes.csv: a `time` column, then one column per probe.
std::string probes_csv(const std::vector<ResolvedProbe>& probes, const ProbeHistory& history);

} // namespace pd
