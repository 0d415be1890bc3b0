#include "libpd/stability.hpp"

#include "libpd/force_kernel.hpp"
#include "libpd/simulation.hpp"
#include "libpd/stable_time_step.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <complex>
#include <fmt/format.h>
#include <functional>
#include <limits>
#include <random>
#include <stdexcept>

namespace pd {

std::vector<double> stability_polynomial(const ButcherTableau& t) {
  // For an explicit table A is nilpotent, so R(z) = 1 + z bᵀ(I − zA)⁻¹1 = 1 + Σ_k z^k bᵀA^{k−1}1
  // (Hairer & Wanner, Solving ODE II, §IV.2), a polynomial of degree ≤ s.
  const auto s = static_cast<std::size_t>(t.stages);
  std::vector<double> gamma(s + 1, 0.0);
  gamma[0] = 1.0;
  std::vector<double> w(s, 1.0); // A^{k−1} 1
  for (std::size_t k = 1; k <= s; ++k) {
    double g = 0;
    for (std::size_t i = 0; i < s; ++i) {
      g += t.b[i] * w[i];
    }
    gamma[k] = g;
    std::vector<double> next(s, 0.0);
    for (std::size_t i = 0; i < s; ++i) {
      for (std::size_t j = 0; j < s; ++j) {
        next[i] += t.a[i * s + j] * w[j];
      }
    }
    w = next;
  }
  return gamma;
}

double stability_modulus_on_imaginary_axis(const std::vector<double>& gamma, double y) {
  std::complex<double> r = 0, zk = 1;
  const std::complex<double> z(0, y);
  for (double g : gamma) {
    r += g * zk;
    zk *= z;
  }
  return std::abs(r);
}

namespace {

/// Coefficients of Q(y) = |R(iy)|² − 1, a real polynomial with Q(0) = 0. Coefficients below
/// 1e-13 are round-off of order conditions that cancel them exactly (for order p the terms up to
/// y^p vanish), so the sign of Q near 0 is decided by the first true term.
std::vector<double> modulus_excess(const std::vector<double>& gamma) {
  const std::size_t n = gamma.size();
  std::vector<double> re(n, 0.0), im(n, 0.0); // R(iy) = Re(y) + i Im(y)
  for (std::size_t k = 0; k < n; ++k) {
    const double sign = (k / 2) % 2 == 0 ? 1.0 : -1.0; // i^k = ±1 or ±i
    (k % 2 == 0 ? re : im)[k] = sign * gamma[k];
  }
  std::vector<double> q(2 * n - 1, 0.0);
  for (std::size_t a = 0; a < n; ++a) {
    for (std::size_t b = 0; b < n; ++b) {
      q[a + b] += re[a] * re[b] + im[a] * im[b];
    }
  }
  q[0] -= 1.0;
  for (double& c : q) {
    if (std::abs(c) < 1e-13) {
      c = 0;
    }
  }
  return q;
}

double evaluate(const std::vector<double>& q, double y) {
  double v = 0;
  for (std::size_t k = q.size(); k-- > 0;) {
    v = v * y + q[k];
  }
  return v;
}

/// Largest y0 with |R(iy)|² ≤ 1 for all y ∈ [0, y0] (scan, then bisection), for q = |R(iy)|² − 1.
double interval_below(const std::vector<double>& q) {
  for (double c : q) {
    if (c > 0) {
      return 0; // |R(iy)| > 1 right from y = 0
    }
    if (c < 0) {
      break;
    }
  }
  const double h = 1e-3;
  double lo = 0, y = h;
  for (; y < 20; y += h) {
    if (evaluate(q, y) > 0) {
      break;
    }
    lo = y;
  }
  if (y >= 20) {
    return lo;
  }
  double hi = y;
  for (int it = 0; it < 60; ++it) {
    const double mid = 0.5 * (lo + hi);
    (evaluate(q, mid) > 0 ? hi : lo) = mid;
  }
  return lo;
}

} // namespace

double imaginary_stability_interval(const ButcherTableau& table) {
  return interval_below(modulus_excess(stability_polynomial(table)));
}

namespace {

/// (K u) per unit volume for the linearised bond operator (Miranda eq. 30 with C = c ξ⊗ξ/|ξ|³):
/// (Ku)_i = Σ_j k_ij n (n·(u_i − u_j)), k_ij = c_ij V_j/|ξ|, broken bonds left out.
void apply_stiffness(const Model& m, const double* u, double* out) {
  const auto n = static_cast<std::ptrdiff_t>(m.size());
  const bool damage = !m.state.broken.empty();
#pragma omp parallel for schedule(static) if (m.size() >= parallel_min_particles)
  for (std::ptrdiff_t ii = 0; ii < n; ++ii) {
    const auto i = static_cast<std::size_t>(ii);
    double acc[3] = {0, 0, 0};
    for (std::size_t k = m.family.offsets[i]; k < m.family.offsets[i + 1]; ++k) {
      if (damage && m.state.broken[k]) {
        continue;
      }
      const std::size_t j = m.family.neighbour[k];
      const double inv = m.family.inverse_length[k];
      const double kij = bond_stiffness(m, k) * inv;
      double nv[3];
      double proj = 0;
      for (std::size_t c = 0; c < 3; ++c) {
        nv[c] = (m.particles.position[j][c] - m.particles.position[i][c]) * inv;
        proj += nv[c] * (u[3 * i + c] - u[3 * j + c]);
      }
      for (std::size_t c = 0; c < 3; ++c) {
        acc[c] += kij * proj * nv[c];
      }
    }
    for (std::size_t c = 0; c < 3; ++c) {
      out[3 * i + c] = acc[c];
    }
  }
}

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
    // Mirror supports move with their source particles (apply_constraints). On a regular lattice
    // the bond (i, image of k) is the reflection of (k, image of i), so the operator stays
    // symmetric.
    for (const Constraint& c : m_.constraints) {
      if (c.mirror_of != Constraint::no_mirror) {
        u_[3 * c.particle + c.component] = c.mirror_sign * u_[3 * c.mirror_of + c.component];
      }
    }
    apply_stiffness(m_, u_.data(), ku_.data());
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

double bounded_run_limit(const PerturbationSpectrum& spectrum,
                         const std::function<double(double)>& log_amplification, std::size_t steps,
                         double growth) {
  double total = 0, theta_max = 0;
  for (std::size_t k = 0; k < spectrum.energy.size(); ++k) {
    total += spectrum.energy[k];
    theta_max = std::max(theta_max, spectrum.omega_squared[k]);
  }
  if (!(total > 0) || !(theta_max > 0)) {
    return 0;
  }
  const double n2 = 2.0 * static_cast<double>(steps);
  // log(E_N / E_0) with E_N = Σ_k e_k |a(ω_k Δt)|^{2N}, in logs because |a|^{2N} overflows.
  auto log_growth = [&](double dt) {
    double top = -std::numeric_limits<double>::infinity();
    std::vector<double> terms(spectrum.energy.size());
    for (std::size_t k = 0; k < terms.size(); ++k) {
      const double y = std::sqrt(spectrum.omega_squared[k]) * dt;
      terms[k] = spectrum.energy[k] > 0 ? std::log(spectrum.energy[k]) + n2 * log_amplification(y)
                                        : -std::numeric_limits<double>::infinity();
      top = std::max(top, terms[k]);
    }
    double sum = 0;
    for (double v : terms) {
      sum += std::exp(v - top);
    }
    return top + std::log(sum) - std::log(total);
  };
  const double limit = std::log(growth);
  const double omega_max = std::sqrt(theta_max);
  // Scan ω_max Δt upwards, then bisect the first crossing.
  double lo = 0, y = 0.01;
  for (; y < 20; y *= 1.01) {
    if (!(log_growth(y / omega_max) <= limit)) {
      break;
    }
    lo = y;
  }
  double hi = y;
  for (int it = 0; it < 60; ++it) {
    const double mid = 0.5 * (lo + hi);
    (log_growth(mid / omega_max) <= limit ? lo : hi) = mid;
  }
  return lo / omega_max;
}

double central_difference_log_amplification(double y) {
  // μ² − (2 − y²)μ + 1 = 0: |μ| = 1 up to y = 2, then the larger root grows.
  if (y <= 2) {
    return 0;
  }
  const double b = y * y - 2.0;
  return std::log(0.5 * (b + std::sqrt(b * b - 4.0)));
}

std::string StabilityTarget::label() const {
  return kind == IntegratorKind::arkode ? "arkode:" + to_string(table) : to_string(kind);
}

Scene stability_scene(const Scene& scene) {
  Scene s = scene;
  s.model.loads.clear();
  s.model.effects.damping = false;
  s.model.effects.body_force = false;
  s.solver.damping = 0;
  s.solver.ramp_time = 0;
  s.solver.steady.enabled = false;
  s.solver.end_time.reset();
  return s;
}

StabilityResult measure_stability(const Scene& scene, const StabilityTarget& target,
                                  const StabilityOptions& opt, double omega_max) {
  const auto start = std::chrono::steady_clock::now();
  const Scene s = stability_scene(scene);
  Model model = build_model(s.model);
  StabilityResult r;
  r.integrator = target.label();
  r.eq31 = stable_time_step(model);
  if (!(omega_max > 0)) {
    omega_max = max_frequency(model).omega_max;
  }
  r.omega_max = omega_max;
  double scale = 1.0; // prediction / eq. 31 guess: β/2 for RK tables
  if (target.kind == IntegratorKind::arkode) {
    r.interval = imaginary_stability_interval(butcher_tableau(target.table));
    scale = r.interval > 0 ? 0.5 * r.interval : 0.5;
  } else if (target.kind == IntegratorKind::adr) {
    throw std::invalid_argument("ADR has no time step to measure (its Δt = 1 is fictitious)");
  } else {
    r.interval = 2.0;
  }
  r.sharp = r.interval / omega_max;
  // The same random perturbation for every trial, on the free components within the dimension.
  std::vector<double> du(3 * model.size(), 0.0);
  {
    std::mt19937_64 rng(opt.seed);
    std::uniform_real_distribution<double> dist(-1.0, 1.0);
    const double amp = opt.perturbation * s.model.lattice.spacing;
    for (std::size_t d = 0; d < du.size(); ++d) {
      if (static_cast<int>(d % 3) < s.model.dimension.dim) {
        du[d] = amp * dist(rng);
      }
    }
  }
  // The bounded run's own criterion, predicted: the perturbation's energy, spread over the modes
  // by its spectral measure, grows by |a(ω Δt)|^{2N} per mode (a = R(iy) for an RK table, the
  // larger root of central differences); unstable once the sum exceeds `growth`. Tables with
  // |R(iy)| barely above 1 (Dormand–Prince past β, Heun–Euler, Cash–Karp and Fehlberg near 0)
  // have a finite limit here although their infinite-horizon interval is smaller or zero.
  const PerturbationSpectrum spectrum = perturbation_spectrum(model, du);
  if (target.kind == IntegratorKind::arkode) {
    const std::vector<double> gamma = stability_polynomial(butcher_tableau(target.table));
    r.sharp_finite = bounded_run_limit(
        spectrum, [&](double y) { return std::log(stability_modulus_on_imaginary_axis(gamma, y)); },
        opt.steps, opt.growth);
  } else {
    r.sharp_finite =
        bounded_run_limit(spectrum, central_difference_log_amplification, opt.steps, opt.growth);
  }
  r.interval_finite = r.sharp_finite * omega_max;

  auto stable_at = [&](double dt) {
    ++r.runs;
    SolverSpec solver = s.solver;
    solver.integrator = target.kind;
    solver.arkode.table = target.table;
    solver.arkode.adaptive = false;
    solver.dt = dt;
    solver.max_steps = opt.steps;
    solver.blowup_displacement = 1e30; // the energy test below decides
    Simulation sim(model, solver, InitialSpec{});
    sim.perturb(du);
    const double e0 = sim.kinetic_energy() + sim.strain_energy();
    const RunResult res = sim.run([&](const Simulation& x) {
      if (x.state().step % 20 != 0) {
        return true;
      }
      const double e = x.kinetic_energy() + x.strain_energy();
      return e <= opt.growth * e0; // false for NaN too
    });
    if (res.status != RunStatus::max_steps) {
      return false;
    }
    const double e = sim.kinetic_energy() + sim.strain_energy();
    return e <= opt.growth * e0;
  };

  // Bracket around the eq. 31 guess, then bisect geometrically.
  const double guess = r.eq31 * scale;
  double lo = 0.5 * guess, hi = 2.0 * guess;
  for (int i = 0; i < 20 && !stable_at(lo); ++i) {
    hi = lo;
    lo *= 0.5;
  }
  for (int i = 0; i < 20 && stable_at(hi); ++i) {
    lo = hi;
    hi *= 2.0;
  }
  while (hi / lo > 1 + opt.relative_tolerance) {
    const double mid = std::sqrt(lo * hi);
    (stable_at(mid) ? lo : hi) = mid;
  }
  r.measured = lo;
  r.unstable = hi;
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

} // namespace pd
