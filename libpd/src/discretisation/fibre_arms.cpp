#include "libpd/discretisation/fibre_arms.hpp"

#include "fibre_relaxation.hpp"
#include "libpd/core/blas.hpp"
#include "libpd/discretisation/point_cloud.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <fmt/format.h>
#include <stdexcept>

namespace pd {

namespace {

using fibre_detail::arm_direction;
using fibre_detail::kernel_weight;

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

/// Per-particle moment weights off the lattice: the own weights of particle i's arms
/// (`own[k]`, unnormalised) times p(q) = Σ_m c_m φ_m(q) over the quartic monomials φ, with c
/// such that the weighted fourth moments Σ own |ξ| φ_n(q) are the isotropic ones (the sum times
/// ⟨φ_n⟩). The second moments, their traces, follow. A homogeneous strain then gives particle i
/// the continuum's stress whatever its neighbours' arrangement (eq. 36 with an isotropic
/// arrangement is what the paper assumes). Left unchanged where the system is singular or a
/// factor would fall below 0.1 (too few or too lopsided neighbours: then balance_arms gives an
/// interior particle its isotropic moments).
void match_fourth_moments(int dim, const ParticleSet& particles, const BondFamily& family,
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

/// One term of a linear condition on the arms' weights: `value` times the change of V_i A_k of
/// directed arm `arm` (i its owner), in condition `row`.
struct Entry {
  std::size_t row;
  std::size_t arm;
  double value;
};

/// The conditions of the balance (balance_arms) on the changes y_k of V_i A_k, C y = r.
struct Conditions {
  std::vector<Entry> entries;
  std::vector<double> rhs;
};

/// Per particle i that owns energy, in units of its own sums:
///  * if i is interior, the third moments of its pair weights, Σ_k (α_k + y_k + y_k') q⊗q⊗q = 0
///    (one arm's pair weight α = V_i A_k + V_j A_k' changes with both ends' weights), over
///    Σ_k α_k;
///  * its fourth moments Σ_k (V_i A_k + y_k) |ξ_k| q⊗q⊗q⊗q over Σ_k V_i A_k |ξ_k|: the isotropic
///    ones (the mean of each monomial over the circle or sphere) if i is interior, else unchanged.
///    The monomials' sum with their multinomial weights is |q|⁴ = 1, so the total weighted length
///    (eq. 59's normalisation) is kept either way.
/// Only arms whose both ends carry energy (`free`) change.
Conditions balance_conditions(int dim, const ParticleSet& particles, const BondFamily& family,
                              const std::vector<std::size_t>& reverse,
                              const std::vector<std::uint8_t>& interior,
                              const std::vector<std::uint8_t>& free,
                              const std::vector<double>& own) {
  const auto odd = monomials(dim, 3);
  const auto even = monomials(dim, 4);
  Conditions c;
  for (std::size_t i = 0; i < particles.size(); ++i) {
    double pair_scale = 0, own_scale = 0;
    for (std::size_t k = family.offsets[i]; k < family.offsets[i + 1]; ++k) {
      pair_scale += pair_weight(particles, family, reverse, own, i, k);
      own_scale += particles.volume[i] * own[k] / family.inverse_length[k];
    }
    if (!(own_scale > 0)) {
      continue; // an extrapolated particle: no energy, no conditions
    }
    const std::size_t row = c.rhs.size();
    const std::size_t odd_rows = interior[i] ? odd.size() : 0;
    c.rhs.resize(row + odd_rows + even.size(), 0.0);
    std::vector<double> current(even.size(), 0.0);
    for (std::size_t k = family.offsets[i]; k < family.offsets[i + 1]; ++k) {
      const auto q = arm_direction(particles, family, i, k);
      for (std::size_t o = 0; o < odd_rows; ++o) {
        const double phi = monomial(odd[o].power, q) / pair_scale;
        c.rhs[row + o] -= pair_weight(particles, family, reverse, own, i, k) * phi;
        if (free[k]) {
          c.entries.push_back({row + o, k, phi});
          c.entries.push_back({row + o, reverse[k], phi});
        }
      }
      for (std::size_t e = 0; e < even.size(); ++e) {
        const double psi = monomial(even[e].power, q) / family.inverse_length[k] / own_scale;
        current[e] += particles.volume[i] * own[k] * psi;
        if (free[k]) {
          c.entries.push_back({row + odd_rows + e, k, psi});
        }
      }
    }
    for (std::size_t e = 0; e < even.size() && interior[i]; ++e) {
      c.rhs[row + odd_rows + e] = even[e].mean - current[e];
    }
  }
  return c;
}

/// The least change y (least Σ y_k²/g_k, g_k = V_i A_k: relative changes) with C y = r and the
/// arms in `fixed` held at `y`'s values: y = y_fixed + G Cᵀλ with C G Cᵀ λ = r − C y_fixed.
/// C G Cᵀ is a block graph Laplacian (9 rows per particle in 2D, 25 in 3D) and is factored
/// directly (CHOLMOD's supernodal Cholesky where libpd has it, else Eigen's LDLᵀ): the conjugate
/// gradients with an incomplete Cholesky factor used before needed thousands of iterations: the
/// regular disk of 7,200 particles set up in 16.5 s instead of 88 s (one thread, under load). A
/// particle whose arms are all held leaves its rows empty; a shift of 1e-12 of the largest diagonal
/// keeps the factor defined.
void least_change(const Conditions& c, const std::vector<double>& g,
                  const std::vector<std::uint8_t>& fixed, std::vector<double>& y) {
  const auto rows = static_cast<Eigen::Index>(c.rhs.size());
  const auto cols = static_cast<Eigen::Index>(g.size());
  Eigen::VectorXd r = Eigen::Map<const Eigen::VectorXd>(c.rhs.data(), rows);
  std::vector<Eigen::Triplet<double>> free_terms;
  free_terms.reserve(c.entries.size());
  for (const Entry& e : c.entries) {
    if (fixed[e.arm]) {
      r(static_cast<Eigen::Index>(e.row)) -= e.value * y[e.arm];
    } else {
      free_terms.emplace_back(static_cast<Eigen::Index>(e.row), static_cast<Eigen::Index>(e.arm),
                              e.value);
    }
  }
  Eigen::SparseMatrix<double> cm(rows, cols);
  cm.setFromTriplets(free_terms.begin(), free_terms.end());
  const Eigen::Map<const Eigen::VectorXd> metric(g.data(), cols);
  const Eigen::SparseMatrix<double> cg_t = cm * metric.asDiagonal();
  const Eigen::SparseMatrix<double> normal = cg_t * cm.transpose();
  double largest = 0;
  for (Eigen::Index d = 0; d < rows; ++d) {
    largest = std::max(largest, normal.coeff(d, d));
  }
  Eigen::SparseMatrix<double> shifted = normal;
  for (Eigen::Index d = 0; d < rows; ++d) {
    shifted.coeffRef(d, d) += 1e-12 * largest;
  }
  const fibre_detail::SparseCholesky factor(shifted);
  if (factor.info() != Eigen::Success) {
    throw std::runtime_error("virtual fibres: the arm balance's normal matrix could not be "
                             "factored");
  }
  // Two steps of iterative refinement against the unshifted matrix take the conditions' residual
  // from 2e-7 (the shift's) to round-off on the regular disk of 7,200 particles.
  Eigen::VectorXd lambda = factor.solve(r);
  for (int step = 0; step < 2; ++step) {
    lambda += factor.solve(r - normal * lambda);
  }
  const Eigen::VectorXd change = cg_t.transpose() * lambda;
  for (std::size_t k = 0; k < y.size(); ++k) {
    if (!fixed[k]) {
      y[k] = change(static_cast<Eigen::Index>(k));
    }
  }
}

/// ‖C y − r‖ / ‖r‖.
double relative_residual(const Conditions& c, const std::vector<double>& y) {
  std::vector<double> cy(c.rhs.size(), 0.0);
  for (const Entry& e : c.entries) {
    cy[e.row] += e.value * y[e.arm];
  }
  double d2 = 0, r2 = 0;
  for (std::size_t row = 0; row < c.rhs.size(); ++row) {
    d2 += (cy[row] - c.rhs[row]) * (cy[row] - c.rhs[row]);
    r2 += c.rhs[row] * c.rhs[row];
  }
  return std::sqrt(d2 / std::max(r2, 1e-300));
}

struct Balance {
  std::size_t interior = 0; ///< particles whose third and fourth moments were conditioned
  std::size_t floored = 0;  ///< arms held at their floor
  int passes = 0;           ///< least-change solves
  double residual = 0;      ///< relative residual of the conditions
  bool applied = false;     ///< the weights were changed (residual ≤ 1e-6)
};

/// Make the arm forces at the `interior` particles cancel under every homogeneous strain, and
/// give them the isotropic fourth moments.
///
/// Under a homogeneous strain every particle has the continuum's force flux density S(q), a
/// quadratic form in q (eq. 77), and the arm a–b carries α_ab S(q_ab) with the pair weight
/// α_ab = V_a A_ab + V_b A_ba (eqs. 64, 70). The net force on a, Σ_b α_ab S(q_ab) q_ab, vanishes
/// for every strain iff the third moment Σ_b α_ab q⊗q⊗q is zero (its trace, the first moment,
/// then is too). Even-moment weights cannot give that on an irregular set, and no per-particle
/// rule can: α_ab holds b's weight as well as a's (Newton's third law couples the particles).
/// So the weights V_a A_ab of all arms change together, by the least relative change, such that
/// every interior particle has zero third moment and the isotropic fourth moments (its stress
/// under a homogeneous strain is the continuum's, and by their trace the mean strain ε̄ of
/// eq. 73 is exact: match_fourth_moments gives that per particle only where a quartic factor
/// stays above 0.1, at about 90 % of the Monte Carlo disks' particles), and every
/// other particle keeps its fourth moments. Each arm's tension stays equal and opposite at its
/// ends and the model keeps its energy. This is the discrete form of the integration constraint
/// of SPH and meshfree methods (a homogeneous stress has no divergence), which the paper takes
/// for granted when it replaces sums by integrals (eq. 59). Particles left out (near free
/// surfaces) take up what the body's arms leave, as a surface traction does.
///
/// No weight may fall below `floor` times its start (an arm of zero or negative weight would
/// carry tension against its stretch): an active set, arms that the least change takes below
/// their floor are held there and the rest solved again, until none is (`max_passes` at most).
/// If the conditions are then not met (relative residual above 1e-6) nothing is changed: on the
/// Monte Carlo sets of Fig. 8 they cannot be met with positive weights. There the first least
/// change already asks relative changes of −8 to −11 of some arms, deep inside the body (disk
/// of 1,800 particles, every particle with a first moment up to 0.4 balanced: 724 of the 761
/// balanced particles farther than two horizons from any edge need an arm cut by more than
/// 90 %), and holding those arms at the floor only moves the demand on: the residual grows to
/// 0.7 after 8 passes (measured with the sub-cell volumes the graded sets had before d9bb363; with
/// their Voronoi areas 0.4–0.7 % of the arms still need cuts beyond 90 %). The balance then needs
/// more freedom than the weights of the arms (a larger neighbourhood: at α = 8, about 30 arms per
/// particle, it applies on the same disks; docs/theory/elliptic-disk.md), which this
/// function does not have. relax_moduli then corrects what the imbalance does to the body's
/// moduli.
Balance balance_arms(int dim, const ParticleSet& particles, const BondFamily& family,
                     const std::vector<std::uint8_t>& interior, std::vector<double>& own) {
  constexpr double floor = 0.1;
  constexpr int max_passes = 4;
  const auto reverse = reverse_bond_index(family);
  const std::size_t nb = family.directed_bond_count();
  std::vector<std::uint8_t> free(nb, 0), fixed(nb, 0);
  std::vector<double> g(nb, 0.0), y(nb, 0.0);
  for (std::size_t i = 0; i < particles.size(); ++i) {
    for (std::size_t k = family.offsets[i]; k < family.offsets[i + 1]; ++k) {
      free[k] = own[k] > 0 && own[reverse[k]] > 0 ? 1 : 0;
      fixed[k] = free[k] ? 0 : 1;
      g[k] = free[k] ? particles.volume[i] * own[k] : 0.0;
    }
  }
  const Conditions c = balance_conditions(dim, particles, family, reverse, interior, free, own);
  Balance out;
  out.interior = static_cast<std::size_t>(std::count(interior.begin(), interior.end(), 1));
  if (c.entries.empty()) {
    return out;
  }
  for (bool again = true; again && out.passes < max_passes;) {
    least_change(c, g, fixed, y);
    ++out.passes;
    again = false;
    for (std::size_t k = 0; k < nb; ++k) {
      if (!fixed[k] && g[k] + y[k] < floor * g[k]) {
        fixed[k] = 1;
        y[k] = (floor - 1.0) * g[k];
        g[k] = 0;
        again = true;
        ++out.floored;
      }
    }
  }
  std::vector<double> balanced = own;
  for (std::size_t i = 0; i < particles.size(); ++i) {
    for (std::size_t k = family.offsets[i]; k < family.offsets[i + 1]; ++k) {
      // After the last pass an arm still below its floor is held there.
      balanced[k] = std::max(own[k] + y[k] / particles.volume[i], floor * own[k]);
      y[k] = (balanced[k] - own[k]) * particles.volume[i];
    }
  }
  out.residual = relative_residual(c, y);
  out.applied = out.residual <= 1e-6;
  if (out.applied) {
    own = std::move(balanced);
  }
  return out;
}

/// The particles to balance: those whose horizon the body fills. A particle is on a free surface
/// if its weighted first moment exceeds 0.2 (measured on the graded plate of point_cloud_test: at
/// most 0.11 with a full horizon, at least 0.23 within half a horizon of the edge); it and every
/// particle with an arm to it are left out.
std::vector<std::uint8_t> full_horizons(int dim, const ParticleSet& particles,
                                        const BondFamily& family,
                                        const std::vector<std::uint8_t>& owns_energy,
                                        const std::vector<double>& own) {
  const std::size_t n = particles.size();
  std::vector<std::uint8_t> surface(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    surface[i] = !owns_energy[i] || first_moment(dim, particles, family, i, own) > 0.2 ? 1 : 0;
  }
  std::vector<std::uint8_t> full = fibre_detail::marked_or_next_to(family, surface);
  for (std::uint8_t& f : full) {
    f = f ? 0 : 1;
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
  if (particle_factor) {
    // The balance and the relaxation factor sparse matrices: on one BLAS thread their results do
    // not depend on the thread count (core/blas.hpp).
    const SerialBlas serial_blas;
    const auto interior = full_horizons(dim, particles, family, owns_energy, arms.own);
    const Balance b = balance_arms(dim, particles, family, interior, arms.own);
    arms.balanced = b.interior;
    arms.balance_residual = b.residual;
    arms.balance_floored = b.floored;
    arms.balance_passes = b.passes;
    arms.balance_applied = b.applied;
    if (!b.applied) {
      arms.relaxed = fibre_detail::relax_moduli(spec.dimension, kernel, particles, family, size,
                                                owns_energy, arms);
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
