// `volume_correction: fitted`: per-pair bond weights that give every particle of an irregular set
// the continuum's moments over its own neighbourhood (declared in corrections.hpp).
#include "libpd/discretisation/corrections.hpp"
#include "moment_components.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <vector>

namespace pd {

// The lattice weights (`moment`, `gradient`) are solved once per orbit of offsets, which assumes
// that every bulk particle sees the same neighbourhood. On a jittered set, or one whose volumes
// vary, each particle's bond sums differ, and so do the stress and the energy a uniform strain
// gives it; worse, its odd moments no longer cancel, so a uniform strain leaves it a force.
//
// For the bond-based law (Pasupathy, eqs. for the bond force and its linearisation; Miranda, Orr &
// Williams 2019, §2: f = c s n V_j per bond) a uniform strain ε stretches a bond with direction n
// by s = n·ε·n, so particle i takes
//   force density  f_i = c Σ_j w_ij V_j (n⊗n⊗n) : ε,
//   stress         σ_i = ½ c Σ_j w_ij V_j |ξ| (n⊗n⊗n⊗n) : ε,
//   energy density W_i = ¼ c Σ_j w_ij V_j |ξ| (n·ε·n)².
// The continuum gives f = 0 and σ = C:ε, W = ½ ε:C:ε with C = (c/2) ∫_H |ξ| n⊗n⊗n⊗n dV, the
// isotropic tensor (c U/6)(δδ + δδ + δδ) (U = ∫_H |ξ| n_x⁴ dV): ν = 1/4 in 3D, 1/3 in 2D. All
// three hold for every ε exactly when, per particle, the 4th moment tensor is the continuum's and
// the 3rd vanishes: 5 + 4 equations in 2D, 15 + 10 in 3D, 1 + 1 in 1D (symmetric components).
//
// Each pair's weight is shared by its two ends (f_ij V_i = −f_ji V_j needs w_ij = w_ji), so the
// equations of all particles couple: one sparse system A w = b over the pairs. Among its solutions
// we take the one closest to uniform weights, min Σ_p (w_p − 1)²: w = 1 + Aᵀy with
// (A Aᵀ) y = b − A 1, by conjugate gradients preconditioned with the particles' own blocks of
// A Aᵀ (a pair couples two particles' blocks through one bond, so these blocks dominate).
// Non-negativity: weights the solve makes negative are held at zero and the rest re-solved, until
// none is negative. That gives non-negative weights that satisfy the equations, not always the
// closest such (a weight once held is not released).
//
// Only particles whose neighbourhood fills their horizon get equations: a particle near a free
// surface cannot have a zero 3rd moment with non-negative weights. Its bonds to fitted particles
// are shaped by theirs; the rest stay at 1. The test is the volume centroid of the particle's
// bonds: within 0.1 δ of it. A surface particle's is 3δ/8 away, that of a particle one spacing
// inside the surface about 0.07 δ at δ = 3λ; a jittered particle's own offset from its cell
// centre moves it by up to 0.1 δ (±0.3 λ, δ = 3λ), so some bulk particles go unfitted. A wider
// test (0.2 δ) took in particles near the surface whose equations cannot be met with
// non-negative weights, and the solve failed.

namespace {

using Matrix = Eigen::MatrixXd;
using Vector = Eigen::VectorXd;

/// The symmetric components of the 3rd and 4th moment tensors in `dim` dimensions: index tuples
/// a ≤ b ≤ c (≤ d).
struct Components {
  std::vector<std::array<std::size_t, 4>> fourth;
  std::vector<std::array<std::size_t, 3>> third;
  std::size_t rows() const { return fourth.size() + third.size(); }
};

Components components(int dim) {
  Components c;
  for (const auto& t : detail::symmetric_components(dim, 3)) {
    c.third.push_back({t[0], t[1], t[2]});
  }
  for (const auto& t : detail::symmetric_components(dim, 4)) {
    c.fourth.push_back({t[0], t[1], t[2], t[3]});
  }
  return c;
}

/// The equations of the fitted particles, rows scaled so that the 4th moments' right-hand side is
/// O(1): per fitted particle, one coefficient column per bond (its pair's unknown).
struct System {
  std::size_t rows = 0;                 ///< per particle
  std::vector<std::size_t> particle;    ///< the fitted particles
  std::vector<std::size_t> pair;        ///< per directed bond: its pair's unknown (min(k, rev k))
  std::vector<std::vector<double>> col; ///< per fitted particle: rows × bonds, column-major
  Vector target;                        ///< the rows' right-hand side, per particle (same for all)
  std::vector<Matrix> block_inverse;    ///< per fitted particle: (A_i A_iᵀ)⁻¹ (pseudo-inverse)
};

System build_system(const CorrectionSpec& spec, const ParticleSet& particles,
                    const BondFamily& family) {
  const int dim = spec.dimension.dim;
  const double delta = spec.lattice.horizon();
  const double u = uniaxial_energy_moment(spec.dimension, delta);
  const Components comp = components(dim);
  System s;
  s.rows = comp.rows();
  s.target = Vector::Zero(static_cast<Eigen::Index>(s.rows));
  for (std::size_t r = 0; r < comp.fourth.size(); ++r) {
    const auto& [a, b, c, d] = comp.fourth[r];
    const auto kd = [](std::size_t x, std::size_t y) { return x == y ? 1.0 : 0.0; };
    s.target[static_cast<Eigen::Index>(r)] =
        (kd(a, b) * kd(c, d) + kd(a, c) * kd(b, d) + kd(a, d) * kd(b, c)) / 3.0;
  }
  const std::vector<std::size_t> rev = reverse_bond_index(family);
  s.pair.resize(family.directed_bond_count());
  for (std::size_t k = 0; k < s.pair.size(); ++k) {
    s.pair[k] = std::min(k, rev[k]);
  }
  for (std::size_t i = 0; i < particles.size(); ++i) {
    const std::size_t begin = family.offsets[i], end = family.offsets[i + 1];
    Vec3 centroid{0, 0, 0};
    double volume = 0;
    for (std::size_t k = begin; k < end; ++k) {
      const std::size_t j = family.neighbour[k];
      for (std::size_t a = 0; a < 3; ++a) {
        centroid[a] += particles.volume[j] * (particles.position[j][a] - particles.position[i][a]);
      }
      volume += particles.volume[j];
    }
    if (!(volume > 0) || norm(centroid) > 0.1 * delta * volume) {
      continue;
    }
    const auto bonds = static_cast<Eigen::Index>(end - begin);
    const auto rows = static_cast<Eigen::Index>(s.rows);
    Matrix a(rows, bonds);
    for (std::size_t k = begin; k < end; ++k) {
      const std::size_t j = family.neighbour[k];
      const double inv = family.inverse_length[k];
      Vec3 n{0, 0, 0};
      for (std::size_t x = 0; x < 3; ++x) {
        n[x] = (particles.position[j][x] - particles.position[i][x]) * inv;
      }
      const auto col = static_cast<Eigen::Index>(k - begin);
      Eigen::Index r = 0;
      for (const auto& [p, q, t, v] : comp.fourth) {
        a(r++, col) = particles.volume[j] / (inv * u) * n[p] * n[q] * n[t] * n[v];
      }
      for (const auto& [p, q, t] : comp.third) {
        a(r++, col) = particles.volume[j] * delta / u * n[p] * n[q] * n[t];
      }
    }
    s.particle.push_back(i);
    s.col.emplace_back(a.data(), a.data() + a.size());
    s.block_inverse.push_back(
        (a * a.transpose()).completeOrthogonalDecomposition().pseudoInverse());
  }
  return s;
}

/// Column-major view of particle p's coefficients.
Eigen::Map<const Matrix> coefficients(const System& s, const BondFamily& family, std::size_t p) {
  const std::size_t i = s.particle[p];
  return {s.col[p].data(), static_cast<Eigen::Index>(s.rows),
          static_cast<Eigen::Index>(family.offsets[i + 1] - family.offsets[i])};
}

/// A w, stacked per fitted particle, for weights w per pair unknown (indexed by directed bond).
Vector apply(const System& s, const BondFamily& family, const std::vector<double>& w) {
  const auto rows = static_cast<Eigen::Index>(s.rows);
  Vector out(rows * static_cast<Eigen::Index>(s.particle.size()));
  for (std::size_t p = 0; p < s.particle.size(); ++p) {
    const auto a = coefficients(s, family, p);
    const std::size_t begin = family.offsets[s.particle[p]];
    Vector wi(a.cols());
    for (Eigen::Index c = 0; c < a.cols(); ++c) {
      wi[c] = w[s.pair[begin + static_cast<std::size_t>(c)]];
    }
    out.segment(static_cast<Eigen::Index>(p) * rows, rows) = a * wi;
  }
  return out;
}

/// Aᵀ y restricted to the free pairs (held ones get nothing), per pair unknown.
std::vector<double> apply_transpose(const System& s, const BondFamily& family, const Vector& y,
                                    const std::vector<char>& held) {
  std::vector<double> out(family.directed_bond_count(), 0.0);
  const auto rows = static_cast<Eigen::Index>(s.rows);
  for (std::size_t p = 0; p < s.particle.size(); ++p) {
    const auto a = coefficients(s, family, p);
    const std::size_t begin = family.offsets[s.particle[p]];
    const Vector c = a.transpose() * y.segment(static_cast<Eigen::Index>(p) * rows, rows);
    for (Eigen::Index b = 0; b < a.cols(); ++b) {
      const std::size_t pair = s.pair[begin + static_cast<std::size_t>(b)];
      if (!held[pair]) {
        out[pair] += c[b];
      }
    }
  }
  return out;
}

Vector precondition(const System& s, const Vector& r) {
  const auto rows = static_cast<Eigen::Index>(s.rows);
  Vector z(r.size());
  for (std::size_t p = 0; p < s.particle.size(); ++p) {
    const auto seg = static_cast<Eigen::Index>(p) * rows;
    z.segment(seg, rows) = s.block_inverse[p] * r.segment(seg, rows);
  }
  return z;
}

/// Weights closest to 1 on the free pairs (0 on the held ones) that satisfy A w = b, by
/// preconditioned conjugate gradients on (A_F A_Fᵀ) y = b − A w₀.
std::vector<double> solve(const System& s, const BondFamily& family,
                          const std::vector<char>& held) {
  std::vector<double> base(family.directed_bond_count(), 0.0);
  for (std::size_t k = 0; k < base.size(); ++k) {
    base[k] = held[s.pair[k]] ? 0.0 : 1.0;
  }
  const auto rows = static_cast<Eigen::Index>(s.rows);
  Vector b(rows * static_cast<Eigen::Index>(s.particle.size()));
  for (std::size_t p = 0; p < s.particle.size(); ++p) {
    b.segment(static_cast<Eigen::Index>(p) * rows, rows) = s.target;
  }
  const auto normal = [&](const Vector& y) {
    return apply(s, family, apply_transpose(s, family, y, held));
  };
  Vector r = b - apply(s, family, base);
  Vector y = Vector::Zero(r.size());
  Vector z = precondition(s, r);
  Vector d = z;
  double rz = r.dot(z);
  for (int iteration = 0; iteration < 5000 && r.lpNorm<Eigen::Infinity>() > 1e-14; ++iteration) {
    const Vector q = normal(d);
    const double dq = d.dot(q);
    if (!(dq > 0)) {
      break;
    }
    const double alpha = rz / dq;
    y += alpha * d;
    r -= alpha * q;
    z = precondition(s, r);
    const double next = r.dot(z);
    d = z + (next / rz) * d;
    rz = next;
  }
  const std::vector<double> correction = apply_transpose(s, family, y, held);
  for (std::size_t k = 0; k < base.size(); ++k) {
    base[k] += correction[s.pair[k]];
  }
  return base;
}

} // namespace

FittedWeights fitted_bond_weights(const CorrectionSpec& spec, const ParticleSet& particles,
                                  const BondFamily& family) {
  const System s = build_system(spec, particles, family);
  std::vector<char> held(family.directed_bond_count(), 0);
  std::vector<double> w;
  for (int pass = 0; pass < 50; ++pass) {
    w = solve(s, family, held);
    bool negative = false;
    for (std::size_t k = 0; k < w.size(); ++k) {
      if (w[k] < 0) {
        held[s.pair[k]] = 1;
        negative = true;
      }
    }
    if (!negative) {
      break;
    }
  }
  FittedWeights out;
  out.factor.resize(w.size());
  out.matched = s.particle.size();
  double smallest = 0, largest = 0;
  for (std::size_t k = 0; k < w.size(); ++k) {
    out.factor[k] = std::max(w[k], 0.0);
    if (out.factor[k] > 0 && (smallest == 0 || out.factor[k] < smallest)) {
      smallest = out.factor[k];
    }
    largest = std::max(largest, out.factor[k]);
    if (k == s.pair[k] && held[k]) {
      ++out.zero_weights;
    }
  }
  out.smallest_positive = smallest;
  out.largest = largest;
  std::vector<double> per_pair(w.size(), 0.0);
  for (std::size_t k = 0; k < w.size(); ++k) {
    per_pair[s.pair[k]] = out.factor[k];
  }
  const auto rows = static_cast<Eigen::Index>(s.rows);
  const Vector residual = apply(s, family, per_pair);
  for (std::size_t p = 0; p < s.particle.size(); ++p) {
    out.residual = std::max(out.residual,
                            (residual.segment(static_cast<Eigen::Index>(p) * rows, rows) - s.target)
                                .lpNorm<Eigen::Infinity>());
  }
  return out;
}

} // namespace pd
