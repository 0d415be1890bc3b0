// Bonds that must not exist: across a pre-crack (ModelSpec::cracks), or through a hole that a
// body's `minus` shapes leave (issue 19).
#pragma once

#include "libpd/core/geometry.hpp"
#include "libpd/discretisation/bond_family.hpp"
#include "libpd/discretisation/lattice.hpp"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace pd {

/// Pre-cracks and holes: the bonds that cross a crack, and the bonds between body particles that
/// pass through a hole, leave the family (both directions, so it stays symmetric); returns the
/// pairs each crack removed. A ghost particle in a hole continues the body around its nearest
/// body particle: a bond into it stays if that particle and the bond's other end see each other,
/// so a ghost inside a notch does not tie the notch's two faces together. A ghost that is the
/// mirror image of a body particle across symmetry planes (`mirror_image`, per particle, or empty)
/// is judged as that particle's mirror in the full model is: by its own position.
/// Whether a bond between body particles at a and b passes through a hole: a point of it, sampled
/// every λ/8 outside the two ends' own cells, lies in some body's `minus` shape and in no body.
bool bond_passes_through_hole(int dim, double spacing, const std::vector<BodySpec>& bodies,
                              const Vec3& a, const Vec3& b);

std::vector<std::size_t> cut_bonds_across_cracks_and_holes(
    int dim, double spacing, const std::vector<Crack>& cracks, const std::vector<BodySpec>& bodies,
    const ParticleSet& particles, std::size_t body_count,
    const std::vector<std::uint8_t>& mirror_image, BondFamily& family);

} // namespace pd
