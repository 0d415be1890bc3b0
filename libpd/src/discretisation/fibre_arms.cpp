#include "libpd/discretisation/fibre_arms.hpp"

#include "libpd/discretisation/point_cloud.hpp"

#include <Eigen/Dense>
#include <Eigen/Sparse>
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

/// Exponents (a, b, c) of the monomials q_x^a q_y^b q_z^c of degree `degree` in `dim`
/// dimensions, and each one's mean over the unit circle or sphere (for degree 4; odd monomials
/// have mean 0, the only means degree 3 needs).
struct Quartic {
  std::array<int, 3> power;
  double mean;
};
std::vector<Quartic> monomials(int dim, int degree) {
  std::vector<Quartic> out;
  for (int a = degree; a >= 0; --a) {
    for (int b = degree - a; b >= 0; --b) {
      const int c = degree - a - b;
      if (dim == 2 && c != 0) {
        continue;
      }
      const bool even = a % 2 == 0 && b % 2 == 0 && c % 2 == 0;
      const bool single = a == degree || b == degree || c == degree;
      const double mean = !even      ? 0.0
                          : dim == 2 ? (single ? 3.0 / 8 : 1.0 / 8)
                                     : (single ? 1.0 / 5 : 1.0 / 15);
      out.push_back({{a, b, c}, mean});
    }
  }
  return out;
}
std::vector<Quartic> quartics(int dim) {
  return monomials(dim, 4);
}

double monomial(const std::array<int, 3>& p, const std::array<double, 3>& q) {
  return std::pow(q[0], p[0]) * std::pow(q[1], p[1]) * std::pow(q[2], p[2]);
}

/// Unit vector from particle i to the neighbour of directed bond k.
std::array<double, 3> arm_direction(const ParticleSet& particles, const BondFamily& family,
                                    std::size_t i, std::size_t k) {
  const Vec3& pi = particles.position[i];
  const Vec3& pj = particles.position[family.neighbour[k]];
  const double inv = family.inverse_length[k];
  return {(pj[0] - pi[0]) * inv, (pj[1] - pi[1]) * inv, (pj[2] - pi[2]) * inv};
}

/// Per-particle moment weights off the lattice: the own weights of particle i's arms
/// (`own[k]`, unnormalised) times p(q) = Σ_m c_m φ_m(q) over the quartic monomials φ, with c
/// such that the weighted fourth moments Σ own |ξ| φ_n(q) are the isotropic ones (the sum times
/// ⟨φ_n⟩). The second moments, their traces, follow. A homogeneous strain then gives particle i
/// the continuum's stress whatever its neighbours' arrangement (eq. 36 with an isotropic
/// arrangement is what the paper assumes). Left unchanged where the system is singular or a
/// factor would fall below 0.1 (too few or too lopsided neighbours).
bool match_fourth_moments(int dim, const ParticleSet& particles, const BondFamily& family,
                          std::size_t i, std::vector<double>& own) {
  const auto basis = quartics(dim);
  const auto m = static_cast<Eigen::Index>(basis.size());
  const std::size_t begin = family.offsets[i], end = family.offsets[i + 1];
  Eigen::MatrixXd phi(static_cast<Eigen::Index>(end - begin), m);
  Eigen::VectorXd w(static_cast<Eigen::Index>(end - begin));
  double total = 0;
  for (std::size_t k = begin; k < end; ++k) {
    const auto q = arm_direction(particles, family, i, k);
    const auto row = static_cast<Eigen::Index>(k - begin);
    for (Eigen::Index n = 0; n < m; ++n) {
      phi(row, n) = monomial(basis[static_cast<std::size_t>(n)].power, q);
    }
    w(row) = own[k] / family.inverse_length[k];
    total += w(row);
  }
  const Eigen::MatrixXd gram = phi.transpose() * w.asDiagonal() * phi;
  Eigen::VectorXd target(m);
  for (Eigen::Index n = 0; n < m; ++n) {
    target(n) = total * basis[static_cast<std::size_t>(n)].mean;
  }
  const Eigen::FullPivLU<Eigen::MatrixXd> lu(gram);
  if (!lu.isInvertible()) {
    return false;
  }
  const Eigen::VectorXd factor = phi * lu.solve(target);
  if (!(factor.minCoeff() >= 0.1)) {
    return false;
  }
  for (std::size_t k = begin; k < end; ++k) {
    own[k] *= factor(static_cast<Eigen::Index>(k - begin));
  }
  return true;
}

/// Odd moments of a particle's arms, relative to their total weight: |Σ_j A_k |ξ_k| q_k| / N.
/// Near 0 where the horizon is full, of order 1/2 on a free surface.
double first_moment(int dim, const ParticleSet& particles, const BondFamily& family, std::size_t i,
                    const std::vector<double>& own) {
  std::array<double, 3> m{0, 0, 0};
  for (std::size_t k = family.offsets[i]; k < family.offsets[i + 1]; ++k) {
    const auto q = arm_direction(particles, family, i, k);
    for (std::size_t c = 0; c < 3; ++c) {
      m[c] += own[k] / family.inverse_length[k] * q[c];
    }
  }
  return std::sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]) / dim;
}

/// The pair stiffness of arm k (i→j) under a homogeneous strain, α = V_i A_k + V_j A_k':
/// the arm's tension is α S(q) (eqs. 64, 70) once every particle has the continuum's S.
double pair_weight(const ParticleSet& particles, const BondFamily& family,
                   const std::vector<std::size_t>& reverse, const std::vector<double>& own,
                   std::size_t i, std::size_t k) {
  return particles.volume[i] * own[k] + particles.volume[family.neighbour[k]] * own[reverse[k]];
}

/// The least change x (in the metric Σ x²/g) with C x = r: x = G Cᵀλ, C G Cᵀ λ = r, by
/// conjugate gradients with an incomplete Cholesky factor (C G Cᵀ is a block graph Laplacian,
/// 9 rows per particle in 2D, 25 in 3D). Returns x and the relative residual ‖Cx − r‖/‖r‖.
std::pair<Eigen::VectorXd, double> least_change(const std::vector<Eigen::Triplet<double>>& entries,
                                                const std::vector<double>& rhs,
                                                const std::vector<double>& g) {
  Eigen::SparseMatrix<double> c(static_cast<Eigen::Index>(rhs.size()),
                                static_cast<Eigen::Index>(g.size()));
  c.setFromTriplets(entries.begin(), entries.end());
  const Eigen::Map<const Eigen::VectorXd> metric(g.data(), static_cast<Eigen::Index>(g.size()));
  const Eigen::Map<const Eigen::VectorXd> r(rhs.data(), static_cast<Eigen::Index>(rhs.size()));
  const Eigen::SparseMatrix<double> cg_t = c * metric.asDiagonal();
  const Eigen::SparseMatrix<double> normal = cg_t * c.transpose();
  Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower | Eigen::Upper,
                           Eigen::IncompleteCholesky<double>>
      cg(normal);
  // 1e-9 leaves interior forces of about 1e-7 σ/h (tests/unit/discretisation/point_cloud_test).
  cg.setTolerance(1e-9);
  cg.setMaxIterations(5000);
  const Eigen::VectorXd x = cg_t.transpose() * cg.solve(r);
  return {x, (c * x - r).norm() / std::max(r.norm(), 1e-300)};
}

/// Make the arm forces at the `balanced` particles cancel under every homogeneous strain.
///
/// Under a homogeneous strain every particle has the continuum's force flux density S(q), a
/// quadratic form in q (eq. 77), and the arm a–b carries α_ab S(q_ab) with the pair weight
/// α_ab = V_a A_ab + V_b A_ba (eqs. 64, 70). The net force on a, Σ_b α_ab S(q_ab) q_ab, vanishes
/// for every strain iff the third moment Σ_b α_ab q⊗q⊗q is zero (its trace, the first moment,
/// then is too). Even-moment weights cannot give that on an irregular set, and no per-particle
/// rule can: α_ab holds b's weight as well as a's (Newton's third law couples the particles).
/// Two least-change solves over the pairs do it:
///  1. the pair weights α_ab(1 + t_ab), least Σ α t², zero the third moments of the balanced
///     particles;
///  2. each pair's change d = α t is split between its ends, A_ab += (d/2 + e_ab)/V_a and
///     A_ba += (d/2 − e_ab)/V_b, with e (least Σ e²/β, β the smaller end's V A) such that every
///     particle keeps its fourth moments Σ_b A_ab |ξ| q⊗q⊗q⊗q: its stress under a homogeneous
///     strain and, by their trace, the mean strain ε̄ of eq. 73.
/// Each arm's tension stays equal and opposite at its ends and the model keeps its energy. This
/// is the discrete form of the integration constraint of SPH and meshfree methods (a homogeneous
/// stress has no divergence), which the paper takes for granted when it replaces sums by
/// integrals (eq. 59). Particles left out (near free surfaces) take up what the body's arms
/// leave, as a surface traction does. Nothing is changed if a weight would not stay positive.
struct Balance {
  std::size_t non_positive = 0;
  double residual = 0;
  std::vector<std::size_t> losing; ///< particles with an arm that would lose its weight
};
Balance balance_odd_moments(int dim, const ParticleSet& particles, const BondFamily& family,
                            const std::vector<std::uint8_t>& balanced,
                            const std::vector<std::uint8_t>& matched, std::vector<double>& own) {
  const auto odd = monomials(dim, 3);
  const auto even = monomials(dim, 4);
  const std::size_t n = particles.size();
  const auto reverse = reverse_bond_index(family);
  const auto& v = particles.volume;
  constexpr std::size_t none = static_cast<std::size_t>(-1);
  // One unknown per pair whose ends both carry energy; side +1 at its lower-index end.
  std::vector<std::size_t> pair(family.directed_bond_count(), none);
  std::vector<double> alpha, beta;
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t k = family.offsets[i]; k < family.offsets[i + 1]; ++k) {
      const std::size_t j = family.neighbour[k];
      if (i < j && own[k] > 0 && own[reverse[k]] > 0) {
        pair[k] = pair[reverse[k]] = alpha.size();
        alpha.push_back(pair_weight(particles, family, reverse, own, i, k));
        beta.push_back(std::min(v[i] * own[k], v[j] * own[reverse[k]]));
      }
    }
  }
  if (alpha.empty()) {
    return {};
  }
  // Unknowns [t, e], least Σ α t² + Σ e²/β. Third-moment rows (balanced particles) in units of
  // the particle's total pair weight, fourth-moment rows (matched particles) of Σ V A|ξ|.
  const std::size_t np = alpha.size();
  std::vector<Eigen::Triplet<double>> entries;
  std::vector<double> rhs;
  for (std::size_t i = 0; i < n; ++i) {
    if (!matched[i]) {
      continue;
    }
    double pair_scale = 0, own_scale = 0;
    for (std::size_t k = family.offsets[i]; k < family.offsets[i + 1]; ++k) {
      pair_scale += pair_weight(particles, family, reverse, own, i, k);
      own_scale += v[i] * own[k] / family.inverse_length[k];
    }
    const std::size_t row = rhs.size();
    const std::size_t odd_rows = balanced[i] ? odd.size() : 0;
    rhs.resize(row + odd_rows + even.size(), 0.0);
    for (std::size_t k = family.offsets[i]; k < family.offsets[i + 1]; ++k) {
      const auto q = arm_direction(particles, family, i, k);
      const auto col = static_cast<Eigen::Index>(pair[k]);
      const double a = pair_weight(particles, family, reverse, own, i, k) / pair_scale;
      for (std::size_t o = 0; o < odd_rows; ++o) {
        const double phi = a * monomial(odd[o].power, q);
        rhs[row + o] -= phi;
        if (pair[k] != none) {
          entries.emplace_back(static_cast<Eigen::Index>(row + o), col, phi);
        }
      }
      if (pair[k] == none) {
        continue;
      }
      const double side = i < family.neighbour[k] ? 1.0 : -1.0;
      const double length = 1.0 / family.inverse_length[k] / own_scale;
      for (std::size_t e = 0; e < even.size(); ++e) {
        const double psi = length * monomial(even[e].power, q);
        const auto r = static_cast<Eigen::Index>(row + odd_rows + e);
        entries.emplace_back(r, col, v[i] * own[k] * psi);
        entries.emplace_back(r, col + static_cast<Eigen::Index>(np), side * psi);
      }
    }
  }
  std::vector<double> metric(2 * np);
  for (std::size_t p = 0; p < np; ++p) {
    metric[p] = 1.0 / alpha[p];
    metric[np + p] = beta[p];
  }
  const auto [x, residual] = least_change(entries, rhs, metric);
  const Eigen::VectorXd t = x.head(static_cast<Eigen::Index>(np));
  const Eigen::VectorXd split = x.tail(static_cast<Eigen::Index>(np));
  Balance out;
  out.residual = residual;
  std::vector<double> corrected = own;
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t k = family.offsets[i]; k < family.offsets[i + 1]; ++k) {
      if (pair[k] != none) {
        const double side = i < family.neighbour[k] ? 1.0 : -1.0;
        corrected[k] = own[k] * (1.0 + t(static_cast<Eigen::Index>(pair[k]))) +
                       side * split(static_cast<Eigen::Index>(pair[k])) / v[i];
        if (corrected[k] <= 0) {
          ++out.non_positive;
          out.losing.push_back(i);
        }
      }
    }
  }
  if (out.non_positive == 0) {
    own = std::move(corrected);
  }
  return out;
}

/// The particles to balance: those whose horizon the body fills. A particle is on a free surface
/// if its fourth moments could not be matched or its weighted first moment exceeds 0.2 (measured
/// on the graded plate of point_cloud_test: at most 0.11 with a full horizon, at least 0.23 within
/// half a horizon of the edge); it and every particle with an arm to it are left out.
std::vector<std::uint8_t> full_horizons(int dim, const ParticleSet& particles,
                                        const BondFamily& family,
                                        const std::vector<std::uint8_t>& matched,
                                        const std::vector<double>& own) {
  const std::size_t n = particles.size();
  std::vector<std::uint8_t> surface(n, 0), full(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    surface[i] = !matched[i] || first_moment(dim, particles, family, i, own) > 0.2 ? 1 : 0;
  }
  for (std::size_t i = 0; i < n; ++i) {
    bool near = surface[i] != 0;
    for (std::size_t k = family.offsets[i]; k < family.offsets[i + 1] && !near; ++k) {
      near = surface[family.neighbour[k]] != 0;
    }
    full[i] = near ? 0 : 1;
  }
  return full;
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
  std::vector<std::uint8_t> matched(n, 0);
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
      matched[i] = match_fourth_moments(dim, particles, family, i, arms.own) ? 1 : 0;
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
  if (particle_factor) {
    // Where the least change would take an arm's weight to zero or below, that arm's ends and
    // their neighbours are left out and the balance solved again (up to three times).
    auto balanced = full_horizons(dim, particles, family, matched, arms.own);
    Balance b;
    for (int attempt = 0; attempt < 4; ++attempt) {
      b = balance_odd_moments(dim, particles, family, balanced, matched, arms.own);
      for (const std::size_t i : b.losing) {
        balanced[i] = 0;
        for (std::size_t k = family.offsets[i]; k < family.offsets[i + 1]; ++k) {
          balanced[family.neighbour[k]] = 0;
        }
      }
      if (b.non_positive == 0) {
        break;
      }
    }
    arms.balanced = static_cast<std::size_t>(std::count(balanced.begin(), balanced.end(), 1));
    arms.balance_residual = b.residual;
    arms.balance_refused = b.non_positive;
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
