// Private to libpd's discretisation: the symmetry supports' side of model building
// (model.cpp), apart so that the model stays readable.
#pragma once

#include "libpd/discretisation/constraint.hpp"
#include "libpd/discretisation/ghost_layers.hpp"
#include "libpd/discretisation/model.hpp"

#include <cstddef>
#include <vector>

namespace pd::detail {

/// The symmetry planes of spec's supports, each with the side the body lies on (that of the mean
/// body particle).
std::vector<SymmetryPlane> symmetry_planes(const ModelSpec& spec, const ParticleSet& particles,
                                           std::size_t body_count);

/// Symmetry supports: every ghost site beyond a symmetry plane (beyond several: across all of
/// them) takes the displacement of its image with the normal components negated, instead of the
/// quadratic fit: the image if it is a free body particle, else what the image takes: its own
/// terms if it is a dependant (a ghost, or a particle of a quadratic clamp the plane cuts), its
/// mirror source if a mirror support sets it. Sources are never dependants (constraint.hpp): a
/// term on one would be dropped by the solvers, and the site would stay at rest (the half model
/// of plate-3clamped read 0.01 % off its full model for that). With these, the half model's
/// energy is exactly half the symmetric full model's (bonds into ghosts count ½), so both have
/// the same equilibrium. Sites without an image keep their fit.
/// `tol` is the supports' region tolerance.
ExtrapolatedParticles symmetry_images(const ModelSpec& spec, const ParticleSet& particles,
                                      std::size_t body_count, double tol,
                                      const std::vector<SymmetryPlane>& sides,
                                      const std::vector<Constraint>& constraints,
                                      ExtrapolatedParticles fitted);

} // namespace pd::detail
