// Probes of a run: the scene's probe specs bound to particles, their values on a simulation, and
// the history of those values that becomes probes.csv.
#pragma once

#include "libpd/io/scene.hpp"
#include "libpd/time/simulation.hpp"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace pd {

/// A probe bound to particles: the mean of one quantity over them (a displacement, stress or
/// strain component, the von Mises stress, the damage index), or a sum (probe_sums): a reaction
/// or moment over the support's particles held, an opening over its two particles.
struct ResolvedProbe {
  std::string name;
  int component = 0;
  std::vector<std::uint32_t> particles;
  /// Beside `particles`: a moment's, the components each is held in (bit c); an opening's, 0
  /// for the particle nearest 'point', 1 for the one nearest 'to'.
  std::vector<std::uint8_t> role;
  ProbeSpec::Quantity quantity = ProbeSpec::Quantity::displacement;
  std::vector<std::uint8_t> dependant; ///< stress, von Mises: the model's massless dependants
  Vec3 about{0, 0, 0};                 ///< moment
  Vec3 direction{0, 0, 0};             ///< opening: unit vector from 'point' to 'to'
  /// Particles the probe averages over, on all ranks together (particles.size() in one process).
  std::size_t count = 0;
};

std::vector<ResolvedProbe> resolve_probes(const std::vector<ProbeSpec>& probes, const Model& model);
/// The probes of the whole model, resolved by resolve_probes, restricted to the particles
/// `local` owns (its part of a run split over ranks, discretisation/distribution.hpp).
std::vector<ResolvedProbe> localise_probes(std::vector<ResolvedProbe> probes, const Model& local);
double probe_value(const ResolvedProbe& probe, const Simulation& sim);

/// A reaction, moment or opening is a sum over its particles; the rest are means.
constexpr bool probe_sums(ProbeSpec::Quantity q) {
  return q == ProbeSpec::Quantity::reaction || q == ProbeSpec::Quantity::moment ||
         q == ProbeSpec::Quantity::opening;
}

/// The von Mises stress √(½ Σ (σ_aa − σ_bb)² + 3 Σ σ_ab²) of a symmetric stress.
double von_mises(const std::array<std::array<double, 3>, 3>& stress);

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
