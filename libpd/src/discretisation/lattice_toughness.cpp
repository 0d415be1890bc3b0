// The boundary-layer computation behind lattice_toughness_ratio (see the header for the method).
#include "libpd/discretisation/lattice_toughness.hpp"

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>
#include <numbers>
#include <stdexcept>
#include <tuple>
#include <vector>

namespace pd {

namespace {

/// Half-width of the square around the tip, in horizons; the factor moves by 0.4 % between 8 and
/// 14 horizons with the default weights.
constexpr double half_width_in_horizons = 10;
/// The factor is read over the tip's second and third lattice periods: the first, before the
/// bonds behind the tip have broken, needs less, and from the second on the breaks repeat (the
/// largest multiplier of periods 2 to 6 agree to 1e-4 with every documented weighting).
constexpr int periods = 3;
/// Breaks carried by the Woodbury identity before K is assembled and factorised again.
constexpr std::size_t refactor_every = 256;

struct Pair {
  std::uint32_t i = 0, j = 0;
  double stiffness = 0; ///< V_i c_ij V_j-weighted pair stiffness over |ξ| (force units / m)
  Vec3 n{0, 0, 0};      ///< unit bond vector i → j
  double length = 0;
};

/// Mode-I displacement of LEFM at (x, y) from the tip, for K, shear modulus μ and Kolosov κ.
std::array<double, 2> mode_one(double x, double y, double k, double mu, double kappa) {
  const double r = std::hypot(x, y);
  const double theta = std::atan2(y, x);
  const double f = k / (2 * mu) * std::sqrt(r / (2 * std::numbers::pi));
  const double s = std::sin(theta / 2), c = std::cos(theta / 2);
  return {f * c * (kappa - 1 + 2 * s * s), f * s * (kappa + 1 - 2 * c * c)};
}

} // namespace

double lattice_toughness_ratio_in(const ModelSpec& user) {
  const double lambda = 1;
  ModelSpec spec;
  spec.dimension.dim = 2;
  spec.dimension.plane = user.dimension.plane;
  spec.dimension.thickness = 1;
  spec.lattice.spacing = lambda;
  spec.lattice.horizon_factor = user.lattice.horizon_factor;
  spec.horizon_rule = user.horizon_rule;
  spec.surface_correction = user.surface_correction;
  spec.volume_correction = user.volume_correction;
  spec.mirror_coupling = user.mirror_coupling;
  const double delta = spec.lattice.horizon();
  const double r_box = std::ceil(half_width_in_horizons * delta);
  const double band = std::ceil(delta) + lambda;
  Material m;
  m.name = "calibration";
  m.youngs_modulus = 1;
  m.density = 1;
  spec.materials = {m};
  spec.bodies = {BodySpec{"square", Region{{Box{{-r_box, -r_box, 0}, {r_box, r_box, 0}}}}, 0, {}}};
  spec.cracks = {Crack{"tip", {{-r_box - lambda, 0, 0}, {0, 0, 0}}}};
  const Model model = build_model(spec);

  const double nu = *bond_based_poisson_ratio(spec.dimension);
  const bool plane_strain = spec.dimension.plane == PlaneMode::plane_strain;
  const double e_prime = plane_strain ? 1 / (1 - nu * nu) : 1.0;
  const double g0 = 1;
  const double k_ic = std::sqrt(e_prime * g0);
  const double mu = 1 / (2 * (1 + nu));
  const double kappa = plane_strain ? 3 - 4 * nu : (3 - nu) / (1 + nu);
  const double s0 = critical_stretch_from_fracture_energy(spec.dimension, 1, delta, g0);

  // Unknowns: x and y of every particle inside the band; the band is held at the K field.
  const std::size_t n_body = model.body_particle_count();
  const auto& x = model.particles.position;
  std::vector<int> unknown(n_body, -1);
  int n_free = 0;
  for (std::size_t p = 0; p < n_body; ++p) {
    if (std::max(std::abs(x[p][0]), std::abs(x[p][1])) < r_box - band) {
      unknown[p] = n_free++;
    }
  }
  std::vector<Pair> pairs;
  const auto& fam = model.family;
  const std::vector<std::size_t> reverse = reverse_bond_index(fam);
  const auto stiffness_of = [&](std::size_t k) {
    return model.field.bond_stiffness.empty() ? model.field.stiffness
                                              : model.field.bond_stiffness[k];
  };
  for (std::size_t i = 0; i < n_body; ++i) {
    for (std::size_t k = fam.offsets[i]; k < fam.offsets[i + 1]; ++k) {
      const std::uint32_t j = fam.neighbour[k];
      const double c = stiffness_of(k);
      if (c == 0) {
        continue;
      }
      if (j >= n_body) {
        if (unknown[i] >= 0) {
          throw std::logic_error("lattice toughness: a free particle reaches a ghost");
        }
        continue;
      }
      if (j <= i) {
        continue; // each pair once, from its lower index
      }
      if (unknown[i] < 0 && unknown[j] < 0) {
        continue;
      }
      Pair b;
      b.i = static_cast<std::uint32_t>(i);
      b.j = j;
      const Vec3 xi{x[j][0] - x[i][0], x[j][1] - x[i][1], 0};
      b.length = std::hypot(xi[0], xi[1]);
      b.n = {xi[0] / b.length, xi[1] / b.length, 0};
      // Force on i per unit stretch is V_i C_ij n (the kernel's force density times V_i); the
      // mean of the two directions keeps K symmetric where a correction is not.
      b.stiffness =
          0.5 *
          (model.particles.volume[i] * c + model.particles.volume[j] * stiffness_of(reverse[k])) /
          b.length;
      pairs.push_back(b);
    }
  }

  // K on the unknowns and the coupling to the band, in V-scaled (symmetric) form.
  using Triplet = Eigen::Triplet<double>;
  std::vector<Triplet> kff;
  std::vector<std::tuple<int, std::uint32_t, int, double>> kfp; // (row, band particle, comp, k)
  auto block = [&](const Pair& b) {
    std::array<double, 4> v{-b.n[0], -b.n[1], b.n[0], b.n[1]};
    std::array<std::uint32_t, 4> particle{b.i, b.i, b.j, b.j};
    for (int r = 0; r < 4; ++r) {
      const int ur = unknown[particle[r]];
      if (ur < 0) {
        continue;
      }
      for (int c = 0; c < 4; ++c) {
        const double value = b.stiffness * v[r] * v[c];
        const int uc = unknown[particle[c]];
        if (uc >= 0) {
          kff.emplace_back(2 * ur + r % 2, 2 * uc + c % 2, value);
        } else {
          kfp.emplace_back(2 * ur + r % 2, particle[c], c % 2, value);
        }
      }
    }
  };
  const Eigen::Index n = 2 * n_free;
  std::vector<std::uint8_t> broken(pairs.size(), 0);
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> factor;
  const auto refactor = [&] {
    kff.clear();
    kfp.clear();
    for (std::size_t q = 0; q < pairs.size(); ++q) {
      if (!broken[q]) {
        block(pairs[q]);
      }
    }
    Eigen::SparseMatrix<double> k(n, n);
    k.setFromTriplets(kff.begin(), kff.end());
    factor.compute(k);
    if (factor.info() != Eigen::Success) {
      throw std::runtime_error("lattice toughness: the boundary-layer stiffness is singular");
    }
  };
  refactor();

  // Candidates: pairs of unknowns that cross the crack's line ahead of the tip.
  std::vector<std::size_t> crossing;
  for (std::size_t q = 0; q < pairs.size(); ++q) {
    const Pair& b = pairs[q];
    if (unknown[b.i] >= 0 && unknown[b.j] >= 0 && x[b.i][1] * x[b.j][1] < 0) {
      crossing.push_back(q);
    }
  }
  // Woodbury: K_n = K0 − V D Vᵀ over the broken pairs; Z = K0⁻¹ V.
  // A broken pair's column of V: −n at i, +n at j (four entries).
  struct PairVector {
    std::array<Eigen::Index, 4> index;
    std::array<double, 4> value;
    double dot(const Eigen::VectorXd& a) const {
      return value[0] * a[index[0]] + value[1] * a[index[1]] + value[2] * a[index[2]] +
             value[3] * a[index[3]];
    }
  };
  std::vector<PairVector> vcols;
  std::vector<Eigen::VectorXd> zcols;
  std::vector<double> d;
  auto pair_vector = [&](const Pair& b) {
    const Eigen::Index i = 2 * unknown[b.i], j = 2 * unknown[b.j];
    return PairVector{{i, i + 1, j, j + 1}, {-b.n[0], -b.n[1], b.n[0], b.n[1]}};
  };
  auto dense = [&](const PairVector& v) {
    Eigen::VectorXd a = Eigen::VectorXd::Zero(n);
    for (std::size_t e = 0; e < 4; ++e) {
      a[v.index[e]] = v.value[e];
    }
    return a;
  };
  std::vector<double> largest(periods + 1, 0.0);
  Eigen::VectorXd u_unbroken;
  double solved_tip = std::numeric_limits<double>::quiet_NaN();
  int generation = 0, solved_generation = -1;
  for (std::size_t event = 0; event < 4 * crossing.size() + 16; ++event) {
    double first_crossing = std::numeric_limits<double>::infinity();
    for (const std::size_t q : crossing) {
      if (!broken[q]) {
        const Pair& b = pairs[q];
        const double t = -x[b.i][1] / (x[b.j][1] - x[b.i][1]);
        first_crossing = std::min(first_crossing, x[b.i][0] + t * (x[b.j][0] - x[b.i][0]));
      }
    }
    const double tip = std::floor(first_crossing / lambda + 1e-9) * lambda;
    const int period = static_cast<int>(std::lround(tip / lambda));
    if (period >= periods) {
      break;
    }
    if (tip != solved_tip || solved_generation != generation) {
      // The band's values for a tip here; K0⁻¹ f changes only when the tip or K0 does.
      Eigen::VectorXd f = Eigen::VectorXd::Zero(n);
      for (const auto& [row, p, comp, value] : kfp) {
        const auto u = mode_one(x[p][0] - tip, x[p][1], k_ic, mu, kappa);
        f[row] -= value * u[static_cast<std::size_t>(comp)];
      }
      u_unbroken = factor.solve(f);
      solved_tip = tip;
      solved_generation = generation;
    }
    Eigen::VectorXd u = u_unbroken;
    if (!vcols.empty()) {
      const auto m_broken = static_cast<Eigen::Index>(vcols.size());
      Eigen::MatrixXd s(m_broken, m_broken);
      Eigen::VectorXd w(m_broken);
      for (Eigen::Index a = 0; a < m_broken; ++a) {
        w[a] = vcols[static_cast<std::size_t>(a)].dot(u);
        for (Eigen::Index c = 0; c < m_broken; ++c) {
          s(a, c) = (a == c ? 1 / d[static_cast<std::size_t>(a)] : 0.0) -
                    vcols[static_cast<std::size_t>(a)].dot(zcols[static_cast<std::size_t>(c)]);
        }
      }
      const Eigen::VectorXd y = s.partialPivLu().solve(w);
      for (Eigen::Index c = 0; c < m_broken; ++c) {
        u += y[c] * zcols[static_cast<std::size_t>(c)];
      }
    }
    double worst = 0;
    std::size_t next = 0;
    for (const std::size_t q : crossing) {
      if (broken[q]) {
        continue;
      }
      const Pair& b = pairs[q];
      const auto ui = 2 * static_cast<Eigen::Index>(unknown[b.i]);
      const auto uj = 2 * static_cast<Eigen::Index>(unknown[b.j]);
      const double stretch =
          (b.n[0] * (u[uj] - u[ui]) + b.n[1] * (u[uj + 1] - u[ui + 1])) / b.length;
      if (stretch / s0 > worst) {
        worst = stretch / s0;
        next = q;
      }
    }
    if (worst <= 0) {
      throw std::logic_error("lattice toughness: no crossing bond is stretched");
    }
    if (period >= 0) {
      largest[static_cast<std::size_t>(period)] =
          std::max(largest[static_cast<std::size_t>(period)], 1 / worst);
    }
    broken[next] = 1;
    if (vcols.size() + 1 >= refactor_every) {
      refactor(); // K without every broken pair: the Woodbury terms start again
      ++generation;
      vcols.clear();
      zcols.clear();
      d.clear();
      continue;
    }
    vcols.push_back(pair_vector(pairs[next]));
    zcols.push_back(factor.solve(dense(vcols.back())));
    d.push_back(pairs[next].stiffness);
  }
  return std::max(largest[periods - 1], largest[periods - 2]);
}

std::optional<double> lattice_toughness_ratio(const ModelSpec& spec) {
  if (spec.dimension.dim != 2) {
    return std::nullopt;
  }
  using Key = std::tuple<double, int, int, int>;
  const Key key{spec.lattice.horizon_factor, static_cast<int>(spec.horizon_rule),
                static_cast<int>(spec.surface_correction),
                static_cast<int>(spec.volume_correction)};
  static std::mutex mutex;
  static std::map<Key, double> cache;
  {
    const std::lock_guard lock(mutex);
    if (const auto found = cache.find(key); found != cache.end()) {
      return found->second;
    }
  }
  // Plane stress whatever the scene's plane: the factor is the same in plane strain (a unit test
  // holds them to 1e-3), and one computation per lattice keeps the cache independent of order.
  ModelSpec plane_stress = spec;
  plane_stress.dimension.plane = PlaneMode::plane_stress;
  const double ratio = lattice_toughness_ratio_in(plane_stress);
  const std::lock_guard lock(mutex);
  cache.emplace(key, ratio);
  return ratio;
}

} // namespace pd
