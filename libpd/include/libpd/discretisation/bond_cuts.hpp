// Bonds that must not exist: across a pre-crack (ModelSpec::cracks), or through a hole that a
// body's `minus` shapes leave (issue 19).
#pragma once

#include "libpd/core/geometry.hpp"
#include "libpd/discretisation/bond_family.hpp"
#include "libpd/discretisation/lattice.hpp"

#include <cstddef>
#include <vector>

namespace pd {

/// Pre-cracks and holes: the bonds that cross a crack, and the bonds between body particles that
/// pass through a hole, leave the family (both directions, so it stays symmetric); returns the
/// pairs each crack removed. A ghost particle in a hole continues the body around its nearest
/// body particle: a bond into it stays if that particle and the bond's other end see each other,
/// so a ghost inside a notch does not tie the notch's two faces together.
std::vector<std::size_t>
cut_bonds_across_cracks_and_holes(int dim, double spacing, const std::vector<Crack>& cracks,
                                  const std::vector<BodySpec>& bodies, const ParticleSet& particles,
                                  std::size_t body_count, BondFamily& family);

} // namespace pd
