// Splitting a model over MPI ranks: Zoltan assigns each particle an owner (partition_particles),
// and each rank keeps its owned particles with the halo their forces need (localise; what the
// halo holds and why the answers cannot depend on the split: ownership.hpp).
//
// The global model is built on every rank first (the same deterministic set-up, so every rank
// agrees on every index, bond weight and ghost fit without communicating); localise then drops
// what the rank does not need. The set-up's peak memory is therefore that of the whole model on
// every rank; the run's is the rank's share plus its halo.
#pragma once

#include "libpd/core/communicator.hpp"
#include "libpd/core/names.hpp"
#include "libpd/discretisation/model.hpp"

#include <cstdint>
#include <vector>

namespace pd {

/// How particles are assigned to ranks. `rcb`: Zoltan's recursive coordinate bisection (equal
/// particle counts, straight cuts). `graph`: Zoltan's graph partitioner (Scotch) on the bond
/// graph, which minimises the bonds cut.
enum class PartitionMethod { rcb, graph };

template <>
struct EnumName<PartitionMethod> {
  static constexpr NameTable<PartitionMethod, 2> table{{
      {"rcb", PartitionMethod::rcb, "Zoltan recursive coordinate bisection"},
      {"graph", PartitionMethod::graph, "Zoltan graph partitioning of the bond graph (Scotch)"},
  }};
};

/// The owning rank of every particle of `global` (collective: every rank calls it with the same
/// model and gets the same answer). One rank owns everything without MPI or Zoltan.
std::vector<std::int32_t> partition_particles(const Model& global, const Communicator& comm,
                                              PartitionMethod method = PartitionMethod::rcb);

/// Rank `rank`'s part of `global` under `owner` (see ownership.hpp): its owned particles, the
/// halo their forces need, bond rows only where this rank computes forces, the constraints and
/// extrapolation ties of the particles it holds, and the halo plan for `ranks` ranks. Pure: no
/// communication (every rank can compute every other rank's halo from the global model).
Model localise(const Model& global, const std::vector<std::int32_t>& owner, int rank, int ranks,
               const Communicator& comm);

/// How good a split is: bonds between particles of different owners and particles per rank
/// (each rank's halo is what localise kept beyond its own: Ownership).
struct PartitionQuality {
  std::size_t cut_bonds = 0;
  std::vector<std::size_t> owned;
};
PartitionQuality partition_quality(const Model& global, const std::vector<std::int32_t>& owner,
                                   int ranks);

} // namespace pd
