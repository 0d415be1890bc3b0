// Per-bond correction factors: surface corrections (a particle near a free surface misses part of
// its horizon and is too soft) and partial-volume corrections (a neighbour whose cell is cut by the
// horizon sphere counts with only part of its volume). Both become one multiplicative factor per
// directed bond, folded into the bond stiffness once at set-up, so the force kernel only sees the
// per-bond field.
#pragma once

#include "libpd/bond_family.hpp"
#include "libpd/lattice.hpp"
#include "libpd/model.hpp"

#include <vector>

namespace pd {

/// Fraction of neighbour j's volume that counts for a bond of reference length r.
double volume_fraction(VolumeCorrection correction, double r, double horizon, double spacing);

/// Family volume Σ_j V_j·(volume fraction) of a particle in the bulk of the spec's lattice:
/// the V0 of the `volume` surface correction (the lattice sum, not 4πδ³/3, so that quadrature
/// error does not become a spurious bulk factor).
double bulk_family_volume(const ModelSpec& spec);

/// The product of the surface and volume correction factors for every directed bond, in CSR
/// order. All ones when both corrections are `none`.
std::vector<double> bond_correction_factors(const ModelSpec& spec, const ParticleSet& particles,
                                            const BondFamily& family);

} // namespace pd
