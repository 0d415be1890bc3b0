// `volume_correction: gradient`: lattice weights per offset orbit that match the continuum's
// fourth moments and a cell's strain-gradient energy (declared in corrections.hpp; a file of its
// own only to keep corrections.cpp within the layout's size limit).
#include "libpd/discretisation/corrections.hpp"
#include "moment_components.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <optional>
#include <stdexcept>
#include <utility>

namespace pd {

// ---- `gradient` weights ------------------------------------------------------------------------
//
// Unknowns: one weight w_o per orbit o of lattice offsets under the cube's symmetry group (signs
// and permutations of the components). Equations over a bulk family (V the cell volume, U the
// uniaxial moment ∫_H n_x⁴ |ξ| dV):
//  * 4th moments, as `moment`: Σ w V |ξ| n_x⁴ = U and (2D, 3D) Σ w V |ξ| n_x²n_y² = U/3.
//  * strain gradient: for a quadratic displacement the stretch of bond ξ is n·ε(x + ξ/2)·n, so the
//    particle's energy density ¼ c Σ w V |ξ| s² holds, beyond its centre value (the odd terms
//    cancel), (c/16) Σ w V |ξ|³ P(n)² with P(n) = Σ_abc n_a n_b n_c G_cab, G_cab = ∂_c ε_ab. The
//    particle's own cell, over which ε varies linearly, holds (λ²/24) Σ_c G_c : C : G_c beyond
//    its centre value. C is the bond-based model's isotropic tensor, (c/2) ∫ |ξ| n⊗n⊗n⊗n dV =
//    (M/3)(δδ + δδ + δδ) with M = cU/2 (1D: C = E = M), so G:C:G = (M/3)((tr G)² + 2 G:G) and
//    the equation reads Σ w V |ξ|³ P(n)² = (λ²U/9)((tr G)² + 2 G:G), free of c and E.
//    Fields, only G_d non-zero for the depth axis d = dim − 1 (so P(n) = n_d (n·G_d·n)):
//      3D (ν = 1/4): beam bending diag(1, −ν, −ν), plate bending diag(1, 0, −ν/(1−ν)), twist
//                    xy = yx = 1 (the three independent sixth moments of a cubic lattice);
//      2D: bending diag(1, −1/3) (the in-plane Poisson ratio of the model, plane stress and
//          plane strain alike: C_xxyy/C_yyyy = 1/3). The shear gradient xy = yx = 1 cannot be
//          matched as well: it needs Σ w|ξ|³n_x²n_y² = (2/3)λ² Σ w|ξ|n_x²n_y², but every bond
//          with n_x n_y ≠ 0 has |ξ|² ≥ 2λ²;
//      1D: none. Any non-negative weights give Σ w|ξ|³ ≥ λ² Σ w|ξ| where the cell needs a third
//          of that: a bar cannot be made exact for a varying strain, so `gradient` is the
//          4th-moment fit closest to uniform there.
//    A field left out keeps the lattice's own response to its gradient (stiffer than the cell).
// Plane stress and plane strain thus get the same weights (their C differ by a factor only).
// Among the non-negative solutions we take the one closest to uniform weights in the sense of
// min Σ_o N_o (w_o − w̄)²: a Lawson–Hanson NNLS first proves that one exists (least residual of
// A w = b over w ≥ 0), a second NNLS on the penalised system [√big·A; diag(√N)] finds the zero
// set, and the exact equality-constrained problem on the remaining orbits (KKT: w_F = w̄ +
// A_Fᵀν/N) gives weights that satisfy the equations to round-off; the zero set is corrected
// until the KKT conditions hold (w_F ≥ 0, multipliers of the zero weights ≥ 0).

namespace {

/// Bond vector λ·o of a lattice offset o.
Vec3 offset_vector(const std::array<long long, 3>& o, double lambda) {
  return {lambda * static_cast<double>(o[0]), lambda * static_cast<double>(o[1]),
          lambda * static_cast<double>(o[2])};
}

using Matrix = Eigen::MatrixXd;
using Vector = Eigen::VectorXd;

std::array<long long, 3> orbit_representative(std::array<long long, 3> o) {
  for (auto& v : o) {
    v = v < 0 ? -v : v;
  }
  std::sort(o.begin(), o.end());
  return o;
}

/// Lawson–Hanson non-negative least squares: argmin ||a x − b|| over x ≥ 0.
Vector nnls(const Matrix& a, const Vector& b) {
  const Eigen::Index n = a.cols();
  Vector x = Vector::Zero(n);
  std::vector<bool> passive(static_cast<std::size_t>(n), false);
  const double tol = 1e-14 * a.norm() * std::max(1.0, b.norm());
  for (Eigen::Index outer = 0; outer < 3 * n + 10; ++outer) {
    const Vector grad = a.transpose() * (b - a * x);
    Eigen::Index add = -1;
    for (Eigen::Index i = 0; i < n; ++i) {
      if (!passive[static_cast<std::size_t>(i)] && grad[i] > tol &&
          (add < 0 || grad[i] > grad[add])) {
        add = i;
      }
    }
    if (add < 0) {
      break;
    }
    passive[static_cast<std::size_t>(add)] = true;
    for (Eigen::Index inner = 0; inner < 3 * n + 10; ++inner) {
      std::vector<Eigen::Index> cols;
      for (Eigen::Index i = 0; i < n; ++i) {
        if (passive[static_cast<std::size_t>(i)]) {
          cols.push_back(i);
        }
      }
      Matrix ap(a.rows(), static_cast<Eigen::Index>(cols.size()));
      for (std::size_t c = 0; c < cols.size(); ++c) {
        ap.col(static_cast<Eigen::Index>(c)) = a.col(cols[c]);
      }
      const Vector zp = ap.colPivHouseholderQr().solve(b);
      Vector z = Vector::Zero(n);
      double step = 1.0;
      for (std::size_t c = 0; c < cols.size(); ++c) {
        const Eigen::Index i = cols[c];
        z[i] = zp[static_cast<Eigen::Index>(c)];
        if (z[i] <= 0) {
          step = std::min(step, x[i] / (x[i] - z[i]));
        }
      }
      x += step * (z - x);
      if (step >= 1.0) {
        break;
      }
      for (const Eigen::Index i : cols) {
        if (x[i] <= 1e-15 * x.lpNorm<Eigen::Infinity>()) {
          x[i] = 0;
          passive[static_cast<std::size_t>(i)] = false;
        }
      }
    }
  }
  return x;
}

using Tensor2 = std::array<std::array<double, 3>, 3>;

/// The strain-gradient fields G_d (d = dim − 1 the depth axis) of the `gradient` equations.
std::vector<Tensor2> gradient_fields(int dim) {
  if (dim == 1) {
    return {}; // no non-negative weights can: the 4th moment alone (see above)
  }
  if (dim == 2) {
    return {Tensor2{{{1, 0, 0}, {0, -1.0 / 3.0, 0}, {0, 0, 0}}}};
  }
  const double nu = 0.25;
  const Tensor2 twist{{{0, 1, 0}, {1, 0, 0}, {0, 0, 0}}};
  return {Tensor2{{{1, 0, 0}, {0, -nu, 0}, {0, 0, -nu}}},
          Tensor2{{{1, 0, 0}, {0, 0, 0}, {0, 0, -nu / (1 - nu)}}}, twist};
}

/// The equations A w = b of the `gradient` weights, one column per orbit, rows scaled to b = 1.
struct GradientSystem {
  std::vector<GradientWeights::Orbit> orbits;
  Matrix a;
  Vector count;
  double uniform = 1;
};

GradientSystem gradient_system(const CorrectionSpec& spec, bool with_gradient) {
  const double lambda = spec.lattice.spacing;
  const double delta = spec.lattice.horizon();
  const int dim = spec.dimension.dim;
  const auto depth = static_cast<std::size_t>(dim - 1);
  const double v = cell_volume(spec.dimension, lambda);
  const double u = uniaxial_energy_moment(spec.dimension, delta);
  const auto fields = with_gradient ? gradient_fields(dim) : std::vector<Tensor2>{};
  std::vector<double> rhs{u};
  if (dim > 1) {
    rhs.push_back(u / 3.0);
  }
  for (const Tensor2& g : fields) {
    double trace = 0, gg = 0;
    for (std::size_t a = 0; a < 3; ++a) {
      trace += g[a][a];
      for (std::size_t b = 0; b < 3; ++b) {
        gg += g[a][b] * g[a][b];
      }
    }
    rhs.push_back(lambda * lambda * u / 9.0 * (trace * trace + 2.0 * gg));
  }
  // Orbits and their column sums, in the order of |o|², then representative.
  std::map<std::pair<long long, std::array<long long, 3>>, std::vector<double>> columns;
  std::map<std::pair<long long, std::array<long long, 3>>, std::size_t> counts;
  for_each_offset_within(
      spec.lattice.horizon_factor, dim, spec.horizon_rule, [&](const std::array<long long, 3>& o) {
        const auto rep = orbit_representative(o);
        const std::pair key{rep[0] * rep[0] + rep[1] * rep[1] + rep[2] * rep[2], rep};
        auto& col = columns[key];
        col.resize(rhs.size(), 0.0);
        ++counts[key];
        const Vec3 xi = offset_vector(o, lambda);
        const double r = norm(xi);
        const Vec3 n{xi[0] / r, xi[1] / r, xi[2] / r};
        std::size_t row = 0;
        col[row++] += v * r * n[0] * n[0] * n[0] * n[0];
        if (dim > 1) {
          col[row++] += v * r * n[0] * n[0] * n[1] * n[1];
        }
        for (const Tensor2& g : fields) {
          double ngn = 0;
          for (std::size_t a = 0; a < 3; ++a) {
            for (std::size_t b = 0; b < 3; ++b) {
              ngn += n[a] * g[a][b] * n[b];
            }
          }
          const double p = n[depth] * ngn;
          col[row++] += v * r * r * r * p * p;
        }
      });
  GradientSystem s;
  const auto rows = static_cast<Eigen::Index>(rhs.size());
  s.a.resize(rows, static_cast<Eigen::Index>(columns.size()));
  s.count.resize(static_cast<Eigen::Index>(columns.size()));
  double moment = 0;
  Eigen::Index c = 0;
  for (const auto& [key, col] : columns) {
    s.orbits.push_back({key.second, counts[key], 0.0});
    s.count[c] = static_cast<double>(counts[key]);
    for (Eigen::Index r = 0; r < rows; ++r) {
      s.a(r, c) = col[static_cast<std::size_t>(r)] / rhs[static_cast<std::size_t>(r)];
    }
    moment += s.a(0, c);
    ++c;
  }
  s.uniform = 1.0 / moment;
  return s;
}

/// min Σ N_o (w_o − w̄)² subject to A w = b (b = 1), w ≥ 0, from the zero set `zero`: exact KKT
/// solve on the free orbits, moving one orbit at a time between the sets until KKT holds. Empty
/// if the sets cycle instead (3D at some long horizons, m = 11.5, 12 or 13.5).
std::optional<Vector> closest_to_uniform(const GradientSystem& s, std::vector<bool> zero) {
  const Eigen::Index n = s.a.cols();
  const Vector b = Vector::Ones(s.a.rows());
  const Vector wbar = Vector::Constant(n, s.uniform);
  for (int iteration = 0; iteration < 4 * n + 20; ++iteration) {
    Matrix af = s.a;
    Vector inv_n = s.count.cwiseInverse();
    for (Eigen::Index i = 0; i < n; ++i) {
      if (zero[static_cast<std::size_t>(i)]) {
        af.col(i).setZero();
        inv_n[i] = 0;
      }
    }
    const Matrix k = af * inv_n.asDiagonal() * af.transpose();
    const Vector nu = k.completeOrthogonalDecomposition().solve(b - af * wbar);
    const Vector atnu = s.a.transpose() * nu;
    Vector w = Vector::Zero(n);
    Eigen::Index worst_free = -1, worst_zero = -1;
    double most_negative = 0, lowest_multiplier = 0;
    for (Eigen::Index i = 0; i < n; ++i) {
      if (!zero[static_cast<std::size_t>(i)]) {
        w[i] = wbar[i] + atnu[i] / s.count[i];
        if (w[i] < most_negative) {
          most_negative = w[i];
          worst_free = i;
        }
      } else {
        const double multiplier = (-s.count[i] * wbar[i] - atnu[i]) / s.count[i];
        if (multiplier < lowest_multiplier) {
          lowest_multiplier = multiplier;
          worst_zero = i;
        }
      }
    }
    const double tol = 1e-12 * s.uniform;
    if (worst_free >= 0 && most_negative < -tol) {
      zero[static_cast<std::size_t>(worst_free)] = true;
    } else if (worst_zero >= 0 && lowest_multiplier < -tol) {
      zero[static_cast<std::size_t>(worst_zero)] = false;
    } else {
      return w.cwiseMax(0.0);
    }
  }
  return std::nullopt;
}

/// The same minimum through its dual, which cannot cycle: for multipliers ν of A w = b the
/// minimising weights are w(ν) = max(0, w̄ + Aᵀν/N), and the dual g(ν) = ½ Σ N (w − w̄)² −
/// νᵀ(A w − b) is concave and piecewise quadratic in one ν per matched row, with gradient
/// b − A w(ν). Semismooth Newton on it (curvature A_F N⁻¹ A_Fᵀ over the non-zero weights) with a
/// backtracking line search. Only a fallback, so that the weights the active set finds stay
/// bit for bit what they were. Also the solver of one particle's weights on an unstructured set,
/// whose equations include zero right-hand sides (b).
/// Empty if it has not converged within `iterations` steps (infeasible equations).
std::optional<Vector> closest_to_uniform_by_dual(const GradientSystem& s, const Vector& b,
                                                 int iterations, double tolerance) {
  const Eigen::Index n = s.a.cols();
  const Vector wbar = Vector::Constant(n, s.uniform);
  const auto weights = [&](const Vector& nu) -> Vector {
    return (wbar + (s.a.transpose() * nu).cwiseQuotient(s.count)).cwiseMax(0.0);
  };
  const auto dual = [&](const Vector& nu) {
    const Vector w = weights(nu);
    return 0.5 * (s.count.array() * (w - wbar).array().square()).sum() - nu.dot(s.a * w - b);
  };
  Vector nu = Vector::Zero(s.a.rows());
  for (int iteration = 0; iteration < iterations; ++iteration) {
    const Vector w = weights(nu);
    const Vector gradient = b - s.a * w;
    if (gradient.lpNorm<Eigen::Infinity>() <= tolerance) {
      return w;
    }
    Matrix active(s.a.rows(), n);
    Eigen::Index columns = 0;
    for (Eigen::Index i = 0; i < n; ++i) {
      if (w[i] > 0) {
        active.col(columns++) = s.a.col(i) / std::sqrt(s.count[i]);
      }
    }
    const Matrix curvature = active.leftCols(columns) * active.leftCols(columns).transpose();
    const Vector step = curvature.completeOrthogonalDecomposition().solve(gradient);
    const double g0 = dual(nu), slope = gradient.dot(step);
    double t = 1;
    while (t > 1e-10 && dual(nu + t * step) < g0 + 1e-4 * t * slope) {
      t *= 0.5;
    }
    const Vector next = nu + t * step;
    if (next == nu) {
      return w; // no further ascent at round-off: the caller reports the residual
    }
    nu = next;
  }
  return std::nullopt;
}

} // namespace

GradientWeights gradient_matched_weights(const CorrectionSpec& spec) {
  // Short horizons cannot match everything (below m = 2 the lattice has too few orbits): then
  // the fourth moments alone, and where even they cannot be met (m < √2 in 2D and 3D: no bond
  // has n_x n_y ≠ 0) the non-negative weights that come closest. `matched` says which.
  GradientSystem s = gradient_system(spec, true);
  Vector b = Vector::Ones(s.a.rows());
  Vector feasible = nnls(s.a, b);
  GradientWeights::Matched matched = GradientWeights::Matched::moments_and_gradient;
  if (!((s.a * feasible - b).lpNorm<Eigen::Infinity>() <= 1e-9)) {
    s = gradient_system(spec, false);
    b = Vector::Ones(s.a.rows());
    feasible = nnls(s.a, b);
    matched = GradientWeights::Matched::moments;
    if (!((s.a * feasible - b).lpNorm<Eigen::Infinity>() <= 1e-9)) {
      GradientWeights closest;
      closest.orbits = s.orbits;
      closest.uniform = s.uniform;
      for (std::size_t i = 0; i < closest.orbits.size(); ++i) {
        closest.orbits[i].weight = feasible[static_cast<Eigen::Index>(i)];
      }
      closest.residual = (s.a * feasible - b).lpNorm<Eigen::Infinity>();
      closest.matched = GradientWeights::Matched::closest;
      return closest;
    }
  }
  const Eigen::Index n = s.a.cols();
  const double big = 1e8;
  Matrix stacked(s.a.rows() + n, n);
  Vector target(s.a.rows() + n);
  stacked << std::sqrt(big) * s.a, Matrix(s.count.cwiseSqrt().asDiagonal());
  target << std::sqrt(big) * b, s.count.cwiseSqrt() * s.uniform;
  const Vector guess = nnls(stacked, target);
  std::vector<bool> zero(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) {
    zero[static_cast<std::size_t>(i)] = !(guess[i] > 0);
  }
  const std::optional<Vector> active_set = closest_to_uniform(s, zero);
  const std::optional<Vector> solved =
      active_set ? active_set : closest_to_uniform_by_dual(s, b, 500, 1e-14);
  if (!solved) {
    throw std::logic_error("gradient weights: neither the active set nor its dual converged");
  }
  Vector w = *solved;
  // Weights at round-off of the largest (4e-15 on (0,1,2) at m = 2√3) are zeros the KKT solve
  // did not land on exactly: made exact, their bonds leave the family (model.cpp) instead of
  // costing kernel time for nothing. The residual below is measured after.
  const double largest = w.maxCoeff();
  for (Eigen::Index i = 0; i < n; ++i) {
    if (w[i] < 1e-12 * largest) {
      w[i] = 0;
    }
  }
  GradientWeights out;
  out.orbits = s.orbits;
  out.uniform = s.uniform;
  for (Eigen::Index i = 0; i < n; ++i) {
    out.orbits[static_cast<std::size_t>(i)].weight = w[i];
  }
  out.residual = (s.a * w - b).lpNorm<Eigen::Infinity>();
  out.matched = matched;
  return out;
}

double GradientWeights::weight(const Vec3& xi, double spacing) const {
  const std::array<long long, 3> o =
      orbit_representative({std::llround(xi[0] / spacing), std::llround(xi[1] / spacing),
                            std::llround(xi[2] / spacing)});
  for (const Orbit& orbit : orbits) {
    if (orbit.offset == o) {
      return orbit.weight;
    }
  }
  // Outside the table: the shell of orbits whose length is nearest to |ξ|/λ.
  const double r = norm(xi) / spacing;
  double best = -1, sum = 0, total = 0;
  for (const Orbit& orbit : orbits) {
    const auto& p = orbit.offset;
    const double d =
        std::abs(std::sqrt(static_cast<double>(p[0] * p[0] + p[1] * p[1] + p[2] * p[2])) - r);
    if (best < 0 || d < best - 1e-12) {
      best = d;
      sum = total = 0;
    }
    if (d <= best + 1e-12) {
      sum += static_cast<double>(orbit.count) * orbit.weight;
      total += static_cast<double>(orbit.count);
    }
  }
  return total > 0 ? sum / total : 0.0;
}

double GradientWeights::reach() const {
  double reach2 = 0;
  for (const Orbit& o : orbits) {
    if (o.weight > 0) {
      reach2 = std::max(reach2,
                        static_cast<double>(o.offset[0] * o.offset[0] + o.offset[1] * o.offset[1] +
                                            o.offset[2] * o.offset[2]));
    }
  }
  return std::sqrt(reach2);
}

double stiff_bond_reach(const CorrectionSpec& spec) {
  if (spec.volume_correction != VolumeCorrection::gradient) {
    return spec.lattice.horizon_factor;
  }
  return stiff_bond_reach(spec, gradient_matched_weights(spec));
}

double stiff_bond_reach(const CorrectionSpec& spec, const GradientWeights& weights) {
  // An unstructured set's particles solve their own weights (particle_gradient_weights) over
  // bonds one spacing longer than the lattice's: over the whole horizon cantilever-tet.yaml took
  // 2.3 times as long to set up, for a tip deflection 0.014 % different.
  const double extra = spec.unstructured ? 1.0 : 0.0;
  return std::min(weights.reach() + extra, spec.lattice.horizon_factor);
}

namespace {

GhostSiteReach shortened_to(const CorrectionSpec& spec, double reach) {
  GhostSiteReach r{spec.lattice, spec.horizon_rule};
  r.lattice.horizon_factor = reach;
  if (reach < spec.lattice.horizon_factor) {
    r.rule = HorizonRule::inclusive;
  }
  return r;
}

} // namespace

GhostSiteReach ghost_site_reach(const CorrectionSpec& spec) {
  return shortened_to(spec, stiff_bond_reach(spec));
}

GhostSiteReach ghost_site_reach(const CorrectionSpec& spec, const GradientWeights& weights) {
  return shortened_to(spec, stiff_bond_reach(spec, weights));
}

double fracture_energy_weight_ratio(const CorrectionSpec& spec) {
  const double lambda = spec.lattice.spacing;
  const double delta = spec.lattice.horizon();
  const int dim = spec.dimension.dim;
  const auto normal = static_cast<std::size_t>(dim - 1);
  MomentWeights moment;
  GradientWeights gradient;
  if (spec.volume_correction == VolumeCorrection::moment) {
    moment = moment_matched_weights(spec);
  } else if (spec.volume_correction == VolumeCorrection::gradient) {
    gradient = gradient_matched_weights(spec);
  }
  double weighted = 0, plain = 0;
  for_each_offset_within(spec.lattice.horizon_factor, dim, spec.horizon_rule,
                         [&](const std::array<long long, 3>& o) {
                           if (o[normal] <= 0) {
                             return;
                           }
                           const Vec3 xi = offset_vector(o, lambda);
                           double w = 1;
                           switch (spec.volume_correction) {
                           case VolumeCorrection::none:
                             break;
                           case VolumeCorrection::linear:
                             w = volume_fraction(spec.volume_correction, norm(xi), delta, lambda);
                             break;
                           case VolumeCorrection::exact:
                             w = exact_volume_fraction(dim, xi, delta, lambda);
                             break;
                           case VolumeCorrection::moment:
                             w = moment.weight(xi);
                             break;
                           case VolumeCorrection::gradient:
                             w = gradient.weight(xi, lambda);
                             break;
                           case VolumeCorrection::fitted:
                           case VolumeCorrection::tensor:
                             break; // around 1, per particle: not a lattice's weights
                           }
                           const double term = xi[normal] * norm(xi);
                           weighted += w * term;
                           plain += term;
                         });
  return weighted / plain;
}

} // namespace pd

namespace pd {

namespace {

/// A moment row of a particle's equations: Σ_j w_j V_j |ξ|^power n_a n_b ... (the `order`
/// indices), scaled so that its right-hand side is 1 (or 0).
struct MomentRow {
  std::array<std::size_t, 6> index{};
  std::size_t order = 4;
  int power = 1;
  double scale = 1;
  double target = 0;
};

using detail::symmetric_components;

double moment_term(const MomentRow& row, const Vec3& n, double len) {
  double value = std::pow(len, row.power);
  for (std::size_t k = 0; k < row.order; ++k) {
    value *= n[row.index[k]];
  }
  return value;
}

/// The rows every particle's equations share: the continuum's 4th moments and a zero 3rd moment
/// and, given the `lattice`'s `gradient` weights, their 6th moments (which give a bond
/// family its energy under every strain gradient) and a zero 5th moment (no energy coupling a
/// uniform strain to a gradient), as on the lattice by symmetry.
std::vector<MomentRow> particle_rows(const CorrectionSpec& spec, const GradientWeights* lattice) {
  const int dim = spec.dimension.dim;
  const double delta = spec.lattice.horizon();
  const double u = uniaxial_energy_moment(spec.dimension, delta);
  std::vector<MomentRow> rows;
  for (const auto& c : symmetric_components(dim, 3)) {
    rows.push_back({c, 3, 0, delta / u, 0.0});
  }
  for (const auto& c : symmetric_components(dim, 4)) {
    const double t = (u / 3.0) * ((c[0] == c[1] && c[2] == c[3]) + (c[0] == c[2] && c[1] == c[3]) +
                                  (c[0] == c[3] && c[1] == c[2]));
    rows.push_back({c, 4, 1, t > 0 ? 1.0 / t : 1.0 / u, t > 0 ? 1.0 : 0.0});
  }
  if (lattice == nullptr || dim == 1) {
    return rows;
  }
  const double lambda = spec.lattice.spacing;
  const double v = cell_volume(spec.dimension, lambda);
  std::vector<MomentRow> sixth;
  for (const auto& c : symmetric_components(dim, 6)) {
    sixth.push_back({c, 6, 3, 1.0, 0.0});
  }
  for_each_offset_within(spec.lattice.horizon_factor, dim, spec.horizon_rule,
                         [&](const std::array<long long, 3>& o) {
                           const Vec3 xi = offset_vector(o, lambda);
                           const double r = norm(xi);
                           const double w = lattice->weight(xi, lambda);
                           const Vec3 n{xi[0] / r, xi[1] / r, xi[2] / r};
                           for (MomentRow& row : sixth) {
                             row.target += w * v * moment_term(row, n, r);
                           }
                         });
  double largest = 0;
  for (const MomentRow& row : sixth) {
    largest = std::max(largest, std::abs(row.target));
  }
  for (MomentRow& row : sixth) {
    // A component the lattice's symmetry zeroes is zero to round-off of the largest.
    if (std::abs(row.target) <= 1e-12 * largest) {
      row.target = 0;
      row.scale = 1.0 / largest;
    } else {
      row.scale = 1.0 / row.target;
      row.target = 1.0;
    }
    rows.push_back(row);
  }
  for (const auto& c : symmetric_components(dim, 5)) {
    rows.push_back({c, 5, 2, delta / largest, 0.0});
  }
  return rows;
}

/// One body particle's equations A w = b over its bonds no longer than `reach` (`bond`: their
/// CSR indices; the others keep no stiffness).
struct ParticleSystem {
  GradientSystem s;
  Vector b;
  std::vector<std::size_t> bond;
};

ParticleSystem particle_system(const std::vector<MomentRow>& rows, const CorrectionSpec& spec,
                               const ParticleSet& particles, const BondFamily& family,
                               std::size_t i, double reach) {
  const double u = uniaxial_energy_moment(spec.dimension, spec.lattice.horizon());
  ParticleSystem p;
  for (std::size_t k = family.offsets[i]; k < family.offsets[i + 1]; ++k) {
    if (1.0 / family.inverse_length[k] <= reach) {
      p.bond.push_back(k);
    }
  }
  const auto columns = static_cast<Eigen::Index>(p.bond.size());
  p.s.a = Matrix::Zero(static_cast<Eigen::Index>(rows.size()), columns);
  p.s.count = Vector::Ones(columns);
  p.b.resize(static_cast<Eigen::Index>(rows.size()));
  for (std::size_t r = 0; r < rows.size(); ++r) {
    p.b[static_cast<Eigen::Index>(r)] = rows[r].target;
  }
  double xxxx = 0;
  for (Eigen::Index c = 0; c < columns; ++c) {
    const std::size_t k = p.bond[static_cast<std::size_t>(c)];
    const std::size_t j = family.neighbour[k];
    const double len = 1.0 / family.inverse_length[k];
    Vec3 n{};
    for (std::size_t a = 0; a < 3; ++a) {
      n[a] = (particles.position[j][a] - particles.position[i][a]) / len;
    }
    const double v = particles.volume[j];
    for (std::size_t r = 0; r < rows.size(); ++r) {
      p.s.a(static_cast<Eigen::Index>(r), c) = v * moment_term(rows[r], n, len) * rows[r].scale;
    }
    xxxx += v * len * n[0] * n[0] * n[0] * n[0];
  }
  p.s.uniform = xxxx > 0 ? u / xxxx : 1.0;
  return p;
}

} // namespace

ParticleGradientWeights particle_gradient_weights(const CorrectionSpec& spec,
                                                  const ParticleSet& particles,
                                                  const BondFamily& family,
                                                  std::size_t body_count) {
  // Each particle's own weights ω_i (closest to its uniform weight, non-negative: the dual of
  // closest_to_uniform_by_dual), then a pair's weight is the mean of its two ends'; a bond into a
  // ghost (no equations of its own) takes its body particle's. Particles are independent, so the
  // loop is parallel and its result does not depend on the thread count.
  const auto start = std::chrono::steady_clock::now();
  const std::size_t bonds = family.directed_bond_count();
  std::vector<double> own(bonds, 1.0);
  std::vector<int> outcome(body_count, 0); // 2 everything, 1 moments only, 0 neither
  std::vector<double> residual(body_count, 0.0);
  constexpr double tolerance = 1e-10;
  const GradientWeights lattice = gradient_matched_weights(spec);
  const std::vector<MomentRow> gradient_rows = particle_rows(spec, &lattice);
  const std::vector<MomentRow> moment_rows = particle_rows(spec, nullptr);
  const double delta = spec.lattice.horizon();
  const double gradient_reach = stiff_bond_reach(spec, lattice) * spec.lattice.spacing;
#pragma omp parallel for schedule(dynamic, 16)
  for (std::size_t i = 0; i < body_count; ++i) {
    for (const bool with_gradient : {true, false}) {
      const auto [s, b, bond] =
          particle_system(with_gradient ? gradient_rows : moment_rows, spec, particles, family, i,
                          with_gradient ? gradient_reach : delta);
      // Semismooth Newton converges in a few steps where the equations can be met; where it
      // has not within 40, Lawson–Hanson's least residual over w ≥ 0 says whether they can be,
      // and only then does it go on (infeasible equations keep the dual climbing).
      std::optional<Vector> w = closest_to_uniform_by_dual(s, b, 40, tolerance);
      if (!w && (s.a * nnls(s.a, b) - b).lpNorm<Eigen::Infinity>() <= 1e-9) {
        w = closest_to_uniform_by_dual(s, b, 400, tolerance);
      }
      const double misfit = w ? (s.a * *w - b).lpNorm<Eigen::Infinity>() : 0.0;
      if (!w || !(misfit <= tolerance)) {
        continue;
      }
      // Weights at round-off of the largest are zeros (as for the lattice's): their bonds leave
      // the family (model.cpp).
      const double largest = w->maxCoeff();
      for (std::size_t k = family.offsets[i]; k < family.offsets[i + 1]; ++k) {
        own[k] = 0.0;
      }
      for (std::size_t c = 0; c < bond.size(); ++c) {
        const double value = (*w)[static_cast<Eigen::Index>(c)];
        own[bond[c]] = value < 1e-12 * largest ? 0.0 : value;
      }
      outcome[i] = with_gradient ? 2 : 1;
      residual[i] = misfit;
      break;
    }
  }
  ParticleGradientWeights out;
  out.factor.assign(bonds, 1.0);
  const auto reverse = reverse_bond_index(family);
  for (std::size_t i = 0; i < particles.size(); ++i) {
    for (std::size_t k = family.offsets[i]; k < family.offsets[i + 1]; ++k) {
      const std::size_t j = family.neighbour[k];
      if (i < body_count && j < body_count) {
        out.factor[k] = 0.5 * (own[k] + own[reverse[k]]);
      } else if (i < body_count) {
        out.factor[k] = own[k];
      } else if (j < body_count) {
        out.factor[k] = own[reverse[k]];
      }
    }
  }
  for (std::size_t i = 0; i < body_count; ++i) {
    out.matched += outcome[i] == 2;
    out.moments_only += outcome[i] == 1;
    out.unmatched += outcome[i] == 0;
    out.residual = std::max(out.residual, residual[i]);
  }
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

} // namespace pd
