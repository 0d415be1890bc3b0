// Private to libpd's discretisation: how the model weighs the particles of cut cells
// (lattice.hpp), apart so that model.cpp stays readable.
#pragma once

#include "libpd/discretisation/ghost_layers.hpp"
#include "libpd/discretisation/model.hpp"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace pd::detail {

/// The share of its lattice cell each body particle holds (lattice.hpp, cut cells; above 1 where
/// a sliver joined it), 1 for the particles of point clouds; empty when every lattice particle
/// holds a whole cell.
std::vector<double> cell_shares(const ModelSpec& spec, const ParticleSet& particles,
                                std::size_t body_count);

/// The weight each body particle's energy density takes in the body's energy, in units of a cell.
/// A cut cell's particle sits at its cell's site, while the material it stands for has its
/// centroid nearer the body's inside; the energy density under a stress that varies near the
/// surface (the hoop stress at a hole) is then weighed at the wrong place, an error of the first
/// order in λ. Moving the share t_a = |d_a|/λ of the weight to the neighbour site along each axis
/// a towards the centroid offset d keeps the weights' sum and puts their first moment at the
/// centroid. Moved only onto body particles, and at most ¾ of the weight.
std::vector<double> energy_weights(const ModelSpec& spec, const ParticleSet& particles,
                                   const std::vector<double>& share);

/// Cut cells under ghost layers. A ghost continues the body beyond its surface, so the part of a
/// cut cell outside the body is continued too: each body particle's horizon holds whole cells,
/// and the body's energy counts each particle's energy density W_i with its weight ω'_i V
/// (energy_weights), while its mass is its share ω_i V:
///   E = Σ_i ω'_i V W_i,   W_i = ¼ Σ_j c s_ij² |ξ_ij| V   (whole cells j, ghosts included).
/// A bond between body particles i and j then stores ¼ c s² |ξ| V² (ω'_i + ω'_j), and the force
/// density on i is Σ_j c s n V (ω'_i + ω'_j)/(2 ω_i): the bond's stiffness c V_j = c ω_j V
/// scaled by (ω'_i + ω'_j)/(2 ω_i ω_j), so the pair's forces stay equal and opposite and the
/// operator symmetric. A bond between i and a ghost counts from i's side only (the ½ of W_c):
/// both its directions scale by ω'_i/ω_i, or, where the ghost is the mirror image of a body
/// particle s across a symmetry plane (one tie of coefficient ±1), by (ω'_i + ω'_s)/(2 ω_i):
/// half of what the full model's pair of i and the image stores, as the half model's energy must
/// be half the full model's.
void scale_bonds_of_cut_cells(const std::vector<double>& share, const std::vector<double>& weight,
                              const BondFamily& family, const ExtrapolatedParticles& ties,
                              std::vector<double>& correction);

/// The ghosts that are the mirror image of a body particle across the symmetry planes (one plane
/// or several): for holes they stand for themselves (bond_cuts.hpp), as that particle's mirror in
/// the full model would. Empty without symmetry planes.
std::vector<std::uint8_t> images_of_body_particles(const ModelSpec& spec,
                                                   const ParticleSet& particles,
                                                   std::size_t body_count);

} // namespace pd::detail
