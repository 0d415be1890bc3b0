// Which of a model's particles this process owns, when a run is split over MPI ranks
// (discretisation/distribution.hpp builds the split). A serial model owns every particle.
//
// A rank's model holds its owned particles and, as halo copies, every particle its owned
// particles' forces depend on: their bond neighbours, and the sources of the ghost and clamp
// particles among those. Under virtual fibres a force also reads the neighbours' mean strains, so
// the neighbours' rows are kept too and the halo reaches two horizons. Local indices keep the
// global order, so every bond family row, every fold of a dependant's force onto its sources and
// every constraint list is the global one restricted — each owned particle's force is summed in
// exactly the order of the serial run.
// Only owned particles enter sums over the body (exact sums, core/exact_sum.hpp), so each
// particle counts once over all ranks.
#pragma once

#include "libpd/core/communicator.hpp"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace pd {

struct Ownership {
  const Communicator* comm = nullptr;      ///< nullptr: the serial communicator
  std::vector<std::uint8_t> owned;         ///< per local particle; empty: every particle
  std::vector<std::uint32_t> global_index; ///< per local particle; empty: the identity
  /// Virtual fibres: per local particle, 1 where the rank keeps the bond row only for the mean
  /// strain its neighbours' forces read (discretisation/distribution.cpp); its force is another
  /// rank's, and the fibre kernel leaves it zero. Empty: no such particle.
  std::vector<std::uint8_t> row_for_mean_only;
  /// Halo copies of particles other ranks own; refreshed by apply_constraints (time/) before the
  /// dependants are set, so a step sees the owners' positions.
  HaloPlan halo;
  std::size_t global_particles = 0;      ///< particles of the whole model
  std::size_t global_body_particles = 0; ///< its body particles (without ghost sites)

  const Communicator& communicator() const {
    return comm != nullptr ? *comm : serial_communicator();
  }
  bool owns(std::size_t i) const { return owned.empty() || owned[i] != 0; }
  std::uint32_t global(std::size_t i) const {
    return global_index.empty() ? static_cast<std::uint32_t>(i) : global_index[i];
  }
  /// True when the model is one rank's part of a larger one.
  bool partial() const { return !owned.empty(); }
};

} // namespace pd
