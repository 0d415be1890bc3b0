#include "libpd/corrections.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace pd {

/// Partial-volume factor of a bond of length r (δ the horizon, λ the spacing).
/// `linear`: the fraction of the neighbour's cell inside the horizon when the cell is treated as a
/// slab of thickness λ centred on the neighbour: f = (δ + λ/2 − r)/λ on δ − λ/2 < r ≤ δ + λ/2
/// (common since Parks et al. 2008, e.g. Madenci & Oterkus 2014 §7).
double volume_fraction(VolumeCorrection vc, double r, double horizon, double spacing) {
  if (vc == VolumeCorrection::linear && r > horizon - 0.5 * spacing) {
    return std::clamp((horizon + 0.5 * spacing - r) / spacing, 0.0, 1.0);
  }
  return 1.0;
}

/// Family volume of a particle in the bulk of the same lattice: Σ over lattice offsets within the
/// horizon of V·(volume fraction). Used as V0 by the `volume` surface correction.
double bulk_family_volume(const ModelSpec& spec) {
  const double lambda = spec.lattice.spacing;
  const double delta = spec.lattice.horizon();
  const double reach = delta * (1.0 + horizon_guard_band);
  const auto m = static_cast<long long>(std::ceil(spec.lattice.horizon_factor)) + 1;
  const int dim = spec.dimension.dim;
  const double v = cell_volume(spec.dimension, lambda);
  double sum = 0;
  for (long long k = (dim > 2 ? -m : 0); k <= (dim > 2 ? m : 0); ++k) {
    for (long long j = (dim > 1 ? -m : 0); j <= (dim > 1 ? m : 0); ++j) {
      for (long long i = -m; i <= m; ++i) {
        if (i == 0 && j == 0 && k == 0) {
          continue;
        }
        const double r = lambda * std::sqrt(static_cast<double>(i * i + j * j + k * k));
        const bool inside = spec.horizon_rule == HorizonRule::inclusive
                                ? r <= reach
                                : r < delta * (1.0 - horizon_guard_band);
        if (inside) {
          sum += v * volume_fraction(spec.volume_correction, r, delta, lambda);
        }
      }
    }
  }
  return sum;
}

std::vector<double> bond_correction_factors(const ModelSpec& spec, const ParticleSet& particles,
                                            const BondFamily& family) {
  const double delta = spec.lattice.horizon();
  const double lambda = spec.lattice.spacing;
  const std::size_t n = particles.size();
  std::vector<double> factor(family.directed_bond_count(), 1.0);
  for (std::size_t k = 0; k < factor.size(); ++k) {
    factor[k] =
        volume_fraction(spec.volume_correction, 1.0 / family.inverse_length[k], delta, lambda);
  }
  switch (spec.surface_correction) {
  case SurfaceCorrection::none:
    break;
  case SurfaceCorrection::volume: {
    // λ_ij = 2V0/(V_i + V_j) with V_i the (volume-corrected) family volume of particle i.
    const double bulk = bulk_family_volume(spec);
    std::vector<double> family_volume(n, 0.0);
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t k = family.offsets[i]; k < family.offsets[i + 1]; ++k) {
        family_volume[i] += particles.volume[family.neighbour[k]] * factor[k];
      }
    }
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t k = family.offsets[i]; k < family.offsets[i + 1]; ++k) {
        factor[k] *= 2.0 * bulk / (family_volume[i] + family_volume[family.neighbour[k]]);
      }
    }
    break;
  }
  case SurfaceCorrection::energy:
  case SurfaceCorrection::macek_silling:
    throw std::runtime_error("surface_correction energy and macek-silling are not available yet: "
                             "use none or volume");
  }
  if (spec.volume_correction == VolumeCorrection::exact) {
    throw std::runtime_error("volume_correction: exact is not available yet: use none or linear");
  }
  return factor;
}

} // namespace pd
