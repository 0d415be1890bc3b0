// Resource estimates: how many particles, bonds and bytes a scene will need, computed from its
// specification alone (no lattice is generated, nothing large is allocated), and the memory the
// machine can offer. The scene parser uses them to refuse scenes that cannot fit before anything
// is enumerated, and `pd info` prints them beside the actual numbers.
#pragma once

#include "libpd/core/memory.hpp"
#include "libpd/discretisation/model.hpp"
#include "libpd/time/simulation.hpp"

#include <optional>
#include <string>
#include <string_view>

namespace pd {

/// Lattice points of `lattice` inside one closed box, counted per axis in floating point (exact
/// below 2^53 points, never overflowing; +inf if the box is beyond the double range at this
/// spacing). Same membership rule as `count_lattice_points`: faces count, within 1e-6 λ.
double lattice_points_in_box(const ModelDimension& d, const LatticeSpec& lattice, const Box& box);

/// Lattice points in a union of boxes. Exact by coordinate compression for up to a few dozen
/// boxes; beyond that the sum over the boxes, an upper bound (overlaps are counted twice).
double lattice_points_in_union(const ModelDimension& d, const LatticeSpec& lattice,
                               const Region& region);

/// Directed bonds of a particle in the bulk (its family size): lattice offsets within the horizon,
/// counted exactly for horizon factors up to 40 and from the ball volume beyond (4/3 π m³,
/// π m², 2m), the larger of the two for jittered lattices.
double bulk_family_size(const ModelDimension& d, const LatticeSpec& lattice, HorizonRule rule);

struct ResourceEstimate {
  double particles = 0;          ///< lattice points in the union of the body boxes
  double bonds_per_particle = 0; ///< bulk family size, capped at particles − 1
  double bonds = 0;              ///< unordered pairs, particles × bonds_per_particle / 2
  double model_bytes = 0;        ///< what `Model::memory_bytes()` will report (ModelStorage)
  double integrator_bytes = 0;   ///< vectors of the integrator beyond the model's run state
  double build_bytes = 0;        ///< transient while building: neighbour grid, correction factors
  double bytes = 0;              ///< total: model + integrator + build transients
  double grid_bytes = 0;         ///< the neighbour-search cell list alone (part of build_bytes)
};

/// Estimate from the specification; every term leans high (surface particles are counted with
/// bulk families), never low. O(boxes^(dim+1) + m^dim) work, no allocation proportional to the
/// particle count.
ResourceEstimate estimate_resources(const ModelSpec& spec, const SolverSpec& solver = {});

} // namespace pd
