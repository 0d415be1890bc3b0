// A body given as particles instead of a lattice region: positions, volumes and, optionally,
// each particle's own size h (Olsson, Ander & Williams 2021: particle a has size h_a and horizon
// α·h_a). Read from a file by io/particle_file.hpp; only the virtual-fibre model runs such bodies.
#pragma once

#include "libpd/core/geometry.hpp"
#include "libpd/discretisation/bond_family.hpp"

#include <cstdint>
#include <vector>

namespace pd {

struct PointCloud {
  std::vector<Vec3> position;
  std::vector<double> volume; ///< [m³] (2D: area × thickness; the file gives it as it is)
  std::vector<double> size;   ///< h [m] per particle, or empty: derived (eq. 115)
  /// The region a mesh body's particles fill (io/mesh_file.hpp), for the ghost sites outside it
  /// (ghost_layers.hpp): its elements cut into simplices, dim + 1 indices into `corner` each.
  /// Empty for particle files.
  std::vector<Vec3> corner;
  std::vector<std::uint32_t> simplex;
  std::vector<std::uint32_t> simplex_particle; ///< each simplex's element (its particle here)

  std::size_t count() const { return position.size(); }
};

/// The indices of each point's `count` nearest other points (fewer if the set is smaller),
/// nearest first, ties broken by index. A cell list of the mean spacing.
std::vector<std::vector<std::uint32_t>> nearest_neighbours(const std::vector<Vec3>& points, int dim,
                                                           int count);

/// Sizes by eq. 115: h_a = Σ_{b among the n nearest} |x_b − x_a| / (2n), for every point of
/// `points` among all of them (n = `neighbours`, fewer if the set is smaller). O(N log N + N n)
/// with a cell list; ties are broken by index, so the result is deterministic.
std::vector<double> sizes_from_neighbours(const std::vector<Vec3>& points, int dim, int neighbours);

/// The arms of particles with their own horizons H_i (α·h_i): every pair with
/// |x_j − x_i| ≤ max(H_i, H_j), i.e. inside either particle's horizon, stored in both directions
/// (rows sorted by neighbour), so the family stays symmetric. A cell list of the largest horizon.
BondFamily variable_horizon_family(const std::vector<Vec3>& position, int dim,
                                   const std::vector<double>& horizon);

} // namespace pd
