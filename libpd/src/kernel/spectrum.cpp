#include "libpd/kernel/spectrum.hpp"

#include "libpd/kernel/linear_operator.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <random>

namespace pd {

namespace {

/// Largest eigenvalue of the symmetric tridiagonal matrix (alpha, beta) by Sturm-count bisection.
double largest_tridiagonal_eigenvalue(const std::vector<double>& alpha,
                                      const std::vector<double>& beta) {
  const std::size_t k = alpha.size();
  double lo = 0, hi = 0;
  for (std::size_t i = 0; i < k; ++i) {
    const double r = (i > 0 ? std::abs(beta[i - 1]) : 0.0) + (i + 1 < k ? std::abs(beta[i]) : 0.0);
    lo = std::min(lo, alpha[i] - r);
    hi = std::max(hi, alpha[i] + r);
  }
  auto count_above = [&](double x) { // eigenvalues > x
    std::size_t count = 0;
    double d = 1;
    for (std::size_t i = 0; i < k; ++i) {
      const double b2 = i > 0 ? beta[i - 1] * beta[i - 1] : 0.0;
      d = alpha[i] - x - (i > 0 ? b2 / d : 0.0);
      if (d == 0) {
        d = 1e-300;
      }
      if (d > 0) {
        ++count;
      }
    }
    return count; // number of positive pivots = eigenvalues above x
  };
  for (int it = 0; it < 200 && hi - lo > 1e-15 * std::max(std::abs(hi), 1e-300); ++it) {
    const double mid = 0.5 * (lo + hi);
    (count_above(mid) >= 1 ? lo : hi) = mid;
  }
  return hi;
}

} // namespace

namespace {

/// The linearised bond operator in symmetric form on the free degrees of freedom: with
/// M = m_d V_i (mass per dof) and K_tot = V K (force, not force density),
/// A = M^{-1/2} K_tot M^{-1/2} has the eigenvalues ω² of M⁻¹K; A w = sqrt(V_i/m_d) (K u) with
/// u = w / sqrt(m_d V_i).
class SymmetricBondOperator {
public:
  SymmetricBondOperator(const Model& m, const std::vector<double>& mass)
      : m_(m), scale_(3 * m.size(), 0.0), u_(3 * m.size()), ku_(3 * m.size()) {
    std::vector<std::uint8_t> free(3 * m.size(), 1);
    for (const Constraint& c : m.constraints) {
      free[3 * c.particle + c.component] = 0;
    }
    const int dim = m.spec.dimension.dim;
    for (std::size_t d = 0; d < scale_.size(); ++d) {
      const double md = mass.empty() ? m.density[d / 3] : mass[d];
      if (free[d] && static_cast<int>(d % 3) < dim) {
        scale_[d] = 1.0 / std::sqrt(md * m.particles.volume[d / 3]);
      }
    }
  }
  std::size_t size() const { return scale_.size(); }
  bool is_free(std::size_t d) const { return scale_[d] > 0; }
  /// w = M^{1/2} u: the coordinates of a displacement in which A is symmetric.
  double to_symmetric(std::size_t d, double u) const { return is_free(d) ? u / scale_[d] : 0.0; }
  void apply(const std::vector<double>& q, std::vector<double>& out) {
    for (std::size_t d = 0; d < q.size(); ++d) {
      u_[d] = q[d] * scale_[d];
    }
    // Mirror supports move with their source particles and, under consistent coupling, send
    // their forces back: Rᵀ K R (discretisation/mirror_constraints.hpp).
    apply_constrained_operator(m_, u_.data(), ku_.data());
    for (std::size_t d = 0; d < q.size(); ++d) {
      out[d] = ku_[d] * m_.particles.volume[d / 3] * scale_[d];
    }
  }

private:
  const Model& m_;
  std::vector<double> scale_; // 1/sqrt(m_d V_i), 0 for constrained or absent dofs
  std::vector<double> u_, ku_;
};

struct Tridiagonal {
  std::vector<double> alpha, beta; ///< diagonal and off-diagonal of the Lanczos matrix T
};

/// Lanczos iteration (without reorthogonalisation) from q, which must be non-zero on free dofs
/// only. `stop(T)` is asked after every iteration; the iteration also stops at an invariant
/// subspace, where the Ritz values are exact.
template <class Stop>
Tridiagonal lanczos(SymmetricBondOperator& op, std::vector<double> q, int max_iterations,
                    Stop stop) {
  Tridiagonal t;
  double norm = 0;
  for (double x : q) {
    norm += x * x;
  }
  norm = std::sqrt(norm);
  if (norm == 0) {
    return t;
  }
  for (double& x : q) {
    x /= norm;
  }
  std::vector<double> q_prev(q.size(), 0.0), w(q.size());
  double b_prev = 0;
  for (int it = 0; it < max_iterations; ++it) {
    op.apply(q, w);
    double a = 0;
    for (std::size_t d = 0; d < q.size(); ++d) {
      a += w[d] * q[d];
    }
    double bnorm = 0;
    for (std::size_t d = 0; d < q.size(); ++d) {
      w[d] -= a * q[d] + b_prev * q_prev[d];
      bnorm += w[d] * w[d];
    }
    bnorm = std::sqrt(bnorm);
    t.alpha.push_back(a);
    if (stop(t) || bnorm < 1e-14 * std::max(std::abs(a), 1e-300)) {
      break;
    }
    t.beta.push_back(bnorm);
    q_prev = q;
    for (std::size_t d = 0; d < q.size(); ++d) {
      q[d] = w[d] / bnorm;
    }
    b_prev = bnorm;
  }
  t.beta.resize(t.alpha.empty() ? 0 : t.alpha.size() - 1);
  return t;
}

} // namespace

FrequencyEstimate max_frequency(const Model& m, const std::vector<double>& mass,
                                int max_iterations) {
  SymmetricBondOperator op(m, mass);
  std::vector<double> q(op.size(), 0.0);
  std::mt19937_64 rng(12345);
  std::uniform_real_distribution<double> dist(-1.0, 1.0);
  for (std::size_t d = 0; d < q.size(); ++d) {
    const double r = dist(rng); // drawn for every dof, so the start does not depend on the supports
    q[d] = op.is_free(d) ? r : 0.0;
  }
  FrequencyEstimate est;
  std::vector<double> history;
  lanczos(op, q, max_iterations, [&](const Tridiagonal& t) {
    const double top = largest_tridiagonal_eigenvalue(t.alpha, t.beta);
    history.push_back(top);
    est.iterations = static_cast<int>(history.size());
    est.omega_max = std::sqrt(std::max(top, 0.0));
    if (history.size() > 10) {
      const double old = history[history.size() - 11];
      est.change = std::abs(top - old) / std::max(top, 1e-300);
      return est.change < 1e-9;
    }
    return false;
  });
  return est;
}

PerturbationSpectrum perturbation_spectrum(const Model& m, const std::vector<double>& du,
                                           int iterations) {
  SymmetricBondOperator op(m, {});
  std::vector<double> x(op.size(), 0.0);
  double norm2 = 0;
  for (std::size_t d = 0; d < x.size(); ++d) {
    x[d] = op.to_symmetric(d, du[d]);
    norm2 += x[d] * x[d];
  }
  const Tridiagonal t = lanczos(op, x, iterations, [](const Tridiagonal&) { return false; });
  PerturbationSpectrum s;
  if (t.alpha.empty()) {
    return s;
  }
  // Gauss quadrature of the spectral measure of x (Golub & Meurant, Matrices, Moments and
  // Quadrature, ch. 6): nodes = eigenvalues θ_k of T, weights = |x|² (first component of its
  // k-th eigenvector)². The strain energy ½ xᵀAx splits into ½ |x|² w_k θ_k per node.
  const auto k = static_cast<Eigen::Index>(t.alpha.size());
  Eigen::MatrixXd tm = Eigen::MatrixXd::Zero(k, k);
  for (Eigen::Index i = 0; i < k; ++i) {
    tm(i, i) = t.alpha[static_cast<std::size_t>(i)];
    if (i + 1 < k) {
      tm(i, i + 1) = tm(i + 1, i) = t.beta[static_cast<std::size_t>(i)];
    }
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(tm);
  for (Eigen::Index i = 0; i < k; ++i) {
    const double theta = std::max(eig.eigenvalues()(i), 0.0);
    const double w = eig.eigenvectors()(0, i) * eig.eigenvectors()(0, i);
    s.omega_squared.push_back(theta);
    s.energy.push_back(0.5 * norm2 * w * theta);
  }
  return s;
}

} // namespace pd
