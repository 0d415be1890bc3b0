// Cut cells (lattice.hpp): the weights and bond factors the model gives their particles.
#include "cut_cells.hpp"

#include "symmetry_images.hpp"

#include <array>
#include <cmath>
#include <map>
#include <set>

namespace pd::detail {

std::vector<double> cell_shares(const ModelSpec& spec, const ParticleSet& particles,
                                std::size_t body_count) {
  if (spec.lattice.volume_variation > 0) {
    return {}; // volumes that vary on purpose, not shares
  }
  const double whole = cell_volume(spec.dimension, spec.lattice.spacing);
  std::vector<double> share(body_count, 1.0);
  bool cut = false;
  for (std::size_t i = 0; i < body_count; ++i) {
    if (!spec.bodies[particles.body[i]].points &&
        std::abs(particles.volume[i] - whole) > 1e-12 * whole) {
      share[i] = particles.volume[i] / whole;
      cut = true;
    }
  }
  return cut ? share : std::vector<double>{};
}

std::vector<double> energy_weights(const ModelSpec& spec, const ParticleSet& particles,
                                   const std::vector<double>& share) {
  const int dim = spec.dimension.dim;
  const double spacing = spec.lattice.spacing;
  std::map<std::array<long long, 3>, std::size_t> body_at;
  for (std::size_t i = 0; i < share.size(); ++i) {
    if (!spec.bodies[particles.body[i]].points) { // a point cloud's particles are not at sites
      body_at.emplace(nearest_lattice_site(spec.lattice, dim, particles.position[i]), i);
    }
  }
  std::vector<double> weight = share;
  for (std::size_t i = 0; i < share.size(); ++i) {
    const BodySpec& body = spec.bodies[particles.body[i]];
    if (share[i] >= 1 || body.points) {
      continue; // whole, or holding a sliver beside it (lattice.cpp): no centroid of its own
    }
    const CellShare cut = cell_share(body.region, dim, particles.position[i], spacing);
    if (std::abs(cut.share - share[i]) > 1e-9) {
      continue; // a cell two bodies share: its centroid is not this body's alone
    }
    const auto site = nearest_lattice_site(spec.lattice, dim, particles.position[i]);
    std::array<double, 3> moved{0, 0, 0};
    std::array<std::size_t, 3> to{0, 0, 0};
    double total = 0;
    for (std::size_t a = 0; a < static_cast<std::size_t>(dim); ++a) {
      auto next = site;
      next[a] += cut.centroid_offset[a] > 0 ? 1 : -1;
      const auto it = body_at.find(next);
      // The cap counts every axis, found or not, so that a half model on a symmetry plane (whose
      // neighbour across the plane is an image, not a body particle) moves what its full model
      // moves along the plane; across it the full model's pair of mirror cells trade equal shares.
      total += std::abs(cut.centroid_offset[a]) / spacing;
      if (it != body_at.end()) {
        to[a] = it->second;
        moved[a] = std::abs(cut.centroid_offset[a]) / spacing;
      }
    }
    const double scale = total > 0.75 ? 0.75 / total : 1.0;
    for (std::size_t a = 0; a < static_cast<std::size_t>(dim); ++a) {
      weight[to[a]] += share[i] * moved[a] * scale;
      weight[i] -= share[i] * moved[a] * scale;
    }
  }
  return weight;
}

void scale_bonds_of_cut_cells(const std::vector<double>& share, const std::vector<double>& weight,
                              const BondFamily& family, const ExtrapolatedParticles& ties,
                              std::vector<double>& correction) {
  const std::size_t body_count = share.size();
  std::vector<std::size_t> image_of(family.offsets.size() - 1, body_count);
  for (std::size_t d = 0; d < ties.size(); ++d) {
    const std::size_t t = ties.offsets[d];
    if (ties.offsets[d + 1] == t + 1 && std::abs(ties.coefficient[t]) == 1.0 &&
        ties.source[t] < body_count) {
      image_of[ties.particle[d]] = ties.source[t];
    }
  }
  const auto ghost_factor = [&](std::size_t i, std::size_t g) {
    const double other = image_of[g] < body_count ? weight[image_of[g]] : weight[i];
    return (weight[i] + other) / (2 * share[i]);
  };
  for (std::size_t i = 0; i + 1 < family.offsets.size(); ++i) {
    for (std::size_t k = family.offsets[i]; k < family.offsets[i + 1]; ++k) {
      const std::size_t j = family.neighbour[k];
      if (i < body_count && j < body_count) {
        correction[k] *= (weight[i] + weight[j]) / (2 * share[i] * share[j]);
      } else if (i < body_count) {
        correction[k] *= ghost_factor(i, j);
      } else if (j < body_count) {
        correction[k] *= ghost_factor(j, i);
      }
    }
  }
}

std::vector<std::uint8_t> images_of_body_particles(const ModelSpec& spec,
                                                   const ParticleSet& particles,
                                                   std::size_t body_count) {
  const std::vector<SymmetryPlane> planes = symmetry_planes(spec, particles, body_count);
  if (planes.empty() || particles.size() == body_count) {
    return {};
  }
  const int dim = spec.dimension.dim;
  std::set<std::array<long long, 3>> body_sites;
  for (std::size_t i = 0; i < body_count; ++i) {
    body_sites.insert(nearest_lattice_site(spec.lattice, dim, particles.position[i]));
  }
  std::vector<std::uint8_t> image(particles.size(), 0);
  for (std::size_t g = body_count; g < particles.size(); ++g) {
    for (unsigned mask = 1; mask < (1U << planes.size()) && image[g] == 0; ++mask) {
      const Vec3 x = mirrored(particles.position[g], planes, mask);
      image[g] = body_sites.contains(nearest_lattice_site(spec.lattice, dim, x)) ? 1 : 0;
    }
  }
  return image;
}

} // namespace pd::detail
