#include "libpd/discretisation/fibre_arms.hpp"

#include "libpd/discretisation/point_cloud.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <fmt/format.h>
#include <stdexcept>

namespace pd {

namespace {

/// −f'(r/h)/h^(N+1) (eq. 57), the slope of particle i's kernel at distance r.
double kernel_weight(const FibreKernel& kernel, int dim, double r, double h) {
  return -kernel.slope(dim, r / h) / std::pow(h, dim + 1);
}

/// a, b of the lattice factor a + b Σ_d n_d⁴ that make the weighted fourth moments of a bulk
/// family isotropic: Σ w|ξ| n_x⁴ = 3 Σ w|ξ| n_x² n_y² (both 1/5 vs 1/15 over the sphere, 3/8 vs
/// 1/8 over the circle), at the integral's value of Σ w|ξ| n_x⁴ (any scale would do: A is
/// normalised per particle).
MomentWeights fibre_moment_weights(const CorrectionSpec& spec, const FibreKernel& kernel,
                                   double h) {
  const int dim = spec.dimension.dim;
  const double lambda = spec.lattice.spacing;
  const double v = std::pow(lambda, dim);
  double a00 = 0, a01 = 0, a10 = 0, a11 = 0;
  for_each_offset_within(
      spec.lattice.horizon_factor, dim, spec.horizon_rule, [&](const std::array<long long, 3>& o) {
        const Vec3 xi{static_cast<double>(o[0]) * lambda, static_cast<double>(o[1]) * lambda,
                      static_cast<double>(o[2]) * lambda};
        const double r = norm(xi);
        const double w = v * kernel_weight(kernel, dim, r, h) * r;
        const double nx = xi[0] / r, ny = xi[1] / r;
        const double q = MomentWeights::cubic_invariant(xi);
        a00 += w * nx * nx * nx * nx;
        a01 += w * nx * nx * nx * nx * q;
        a10 += w * nx * nx * ny * ny;
        a11 += w * nx * nx * ny * ny * q;
      });
  const double c4 = 3.0 / (dim + 2.0); // N <n_x⁴> with Σ V w |ξ| = N (eq. 59)
  const double c22 = c4 / 3.0;
  const double det = a00 * a11 - a01 * a10;
  MomentWeights m;
  m.alpha = (c4 * a11 - a01 * c22) / det;
  m.beta = (a00 * c22 - a10 * c4) / det;
  return m;
}

/// Exponents (a, b, c) of the monomials q_x^a q_y^b q_z^c of degree 4 in `dim` dimensions, and
/// each one's mean over the unit circle or sphere.
struct Quartic {
  std::array<int, 3> power;
  double mean;
};
std::vector<Quartic> quartics(int dim) {
  std::vector<Quartic> out;
  for (int a = 4; a >= 0; --a) {
    for (int b = 4 - a; b >= 0; --b) {
      const int c = 4 - a - b;
      if (dim == 2 && c != 0) {
        continue;
      }
      const bool even = a % 2 == 0 && b % 2 == 0 && c % 2 == 0;
      const bool single = a == 4 || b == 4 || c == 4;
      const double mean = !even      ? 0.0
                          : dim == 2 ? (single ? 3.0 / 8 : 1.0 / 8)
                                     : (single ? 1.0 / 5 : 1.0 / 15);
      out.push_back({{a, b, c}, mean});
    }
  }
  return out;
}

/// Per-particle moment weights off the lattice: the own weights of particle i's arms
/// (`own[k]`, unnormalised) times p(q) = Σ_m c_m φ_m(q) over the quartic monomials φ, with c
/// such that the weighted fourth moments Σ own |ξ| φ_n(q) are the isotropic ones (the sum times
/// ⟨φ_n⟩). The second moments, their traces, follow. A homogeneous strain then gives particle i
/// the continuum's stress whatever its neighbours' arrangement (eq. 36 with an isotropic
/// arrangement is what the paper assumes). Left unchanged where the system is singular or a
/// factor would fall below 0.1 (too few or too lopsided neighbours).
void match_fourth_moments(int dim, const ParticleSet& particles, const BondFamily& family,
                          std::size_t i, std::vector<double>& own) {
  const auto basis = quartics(dim);
  const auto m = static_cast<Eigen::Index>(basis.size());
  const std::size_t begin = family.offsets[i], end = family.offsets[i + 1];
  Eigen::MatrixXd phi(static_cast<Eigen::Index>(end - begin), m);
  Eigen::VectorXd w(static_cast<Eigen::Index>(end - begin));
  double total = 0;
  for (std::size_t k = begin; k < end; ++k) {
    const Vec3& pi = particles.position[i];
    const Vec3& pj = particles.position[family.neighbour[k]];
    const double inv = family.inverse_length[k];
    const std::array<double, 3> q{(pj[0] - pi[0]) * inv, (pj[1] - pi[1]) * inv,
                                  (pj[2] - pi[2]) * inv};
    const auto row = static_cast<Eigen::Index>(k - begin);
    for (Eigen::Index n = 0; n < m; ++n) {
      const auto& p = basis[static_cast<std::size_t>(n)].power;
      phi(row, n) = std::pow(q[0], p[0]) * std::pow(q[1], p[1]) * std::pow(q[2], p[2]);
    }
    w(row) = own[k] / inv;
    total += w(row);
  }
  const Eigen::MatrixXd gram = phi.transpose() * w.asDiagonal() * phi;
  Eigen::VectorXd target(m);
  for (Eigen::Index n = 0; n < m; ++n) {
    target(n) = total * basis[static_cast<std::size_t>(n)].mean;
  }
  const Eigen::FullPivLU<Eigen::MatrixXd> lu(gram);
  if (!lu.isInvertible()) {
    return;
  }
  const Eigen::VectorXd factor = phi * lu.solve(target);
  if (!(factor.minCoeff() >= 0.1)) {
    return;
  }
  for (std::size_t k = begin; k < end; ++k) {
    own[k] *= factor(static_cast<Eigen::Index>(k - begin));
  }
}

} // namespace

std::vector<double> fibre_particle_sizes(const LatticeSpec& lattice, const FibreKernel& kernel,
                                         const ParticleSet& particles, int dim) {
  const double lattice_size = lattice.horizon() / kernel.alpha;
  std::vector<double> h(particles.size(), lattice_size);
  if (particles.particle_size.empty()) {
    return h;
  }
  const bool derive = std::any_of(particles.particle_size.begin(), particles.particle_size.end(),
                                  [](double s) { return std::isnan(s); });
  const std::vector<double> derived =
      derive ? sizes_from_neighbours(particles.position, dim, kernel.size_neighbours)
             : std::vector<double>{};
  for (std::size_t i = 0; i < h.size(); ++i) {
    const double given = particles.particle_size[i];
    h[i] = std::isnan(given) ? derived[i] : given > 0 ? given : lattice_size;
  }
  return h;
}

FibreArms fibre_arms(const CorrectionSpec& spec, const FibreKernel& kernel,
                     const std::vector<Material>& materials, const ParticleSet& particles,
                     const BondFamily& family, const std::vector<double>& size,
                     const std::vector<std::uint8_t>& owns_energy) {
  const int dim = spec.dimension.dim;
  const std::size_t n = particles.size();
  FibreArms arms;
  arms.dim = dim;
  arms.shear.resize(n);
  arms.volumetric.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Material& mat = materials.at(particles.material[i]);
    const FibreModuli k =
        fibre_moduli(spec.dimension, mat.youngs_modulus * mat.stiffness_factor, mat.poisson_ratio);
    arms.shear[i] = k.shear;
    arms.volumetric[i] = k.volumetric;
  }
  // The moment factor needs one size for the whole lattice (the lattice's own h = δ/α).
  const bool lattice_factor = particles.particle_size.empty() &&
                              spec.volume_correction != VolumeCorrection::none &&
                              spec.lattice.spacing > 0 && dim >= 2;
  const MomentWeights moment =
      lattice_factor ? fibre_moment_weights(spec, kernel, spec.lattice.horizon() / kernel.alpha)
                     : MomentWeights{};
  // Off the lattice, each particle's own moments instead (match_fourth_moments).
  const bool particle_factor = !particles.particle_size.empty() &&
                               spec.volume_correction != VolumeCorrection::none && dim >= 2;
  const std::size_t nb = family.directed_bond_count();
  arms.own.assign(nb, 0.0);
  arms.other.assign(nb, 0.0);
  // Unnormalised own weights V_j w_ij (times the lattice factor), then the per-particle sum.
  std::vector<double> total(n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    if (!owns_energy[i]) {
      continue;
    }
    for (std::size_t k = family.offsets[i]; k < family.offsets[i + 1]; ++k) {
      const std::size_t j = family.neighbour[k];
      const double r = 1.0 / family.inverse_length[k];
      const Vec3& pi = particles.position[i];
      const Vec3& pj = particles.position[j];
      const Vec3 xi{pj[0] - pi[0], pj[1] - pi[1], pj[2] - pi[2]};
      const double factor = lattice_factor ? moment.weight(xi) : 1.0;
      arms.own[k] = particles.volume[j] * kernel_weight(kernel, dim, r, size[i]) * factor;
    }
    if (particle_factor) {
      match_fourth_moments(dim, particles, family, i, arms.own);
    }
    for (std::size_t k = family.offsets[i]; k < family.offsets[i + 1]; ++k) {
      total[i] += arms.own[k] / family.inverse_length[k];
    }
    if (!(total[i] > 0)) {
      throw std::runtime_error(fmt::format(
          "virtual fibres: the particle at ({:.6g}, {:.6g}, {:.6g}) has no arm of positive "
          "weight within its horizon",
          particles.position[i][0], particles.position[i][1], particles.position[i][2]));
    }
    for (std::size_t k = family.offsets[i]; k < family.offsets[i + 1]; ++k) {
      arms.own[k] *= dim / total[i];
    }
  }
  const auto reverse = reverse_bond_index(family);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t k = family.offsets[i]; k < family.offsets[i + 1]; ++k) {
      const std::size_t j = family.neighbour[k];
      arms.other[k] = arms.own[reverse[k]] * particles.volume[j] / particles.volume[i];
    }
  }
  return arms;
}

std::vector<double> fibre_stiffness_bound(const FibreArms& arms, const BondFamily& family) {
  std::vector<double> c(family.directed_bond_count(), 0.0);
  const auto stiffest = [&](std::size_t p) {
    return arms.shear[p] + std::max(arms.volumetric[p], 0.0);
  };
  for (std::size_t i = 0; i + 1 < family.offsets.size(); ++i) {
    for (std::size_t k = family.offsets[i]; k < family.offsets[i + 1]; ++k) {
      c[k] = stiffest(i) * arms.own[k] + stiffest(family.neighbour[k]) * arms.other[k];
    }
  }
  return c;
}

} // namespace pd
