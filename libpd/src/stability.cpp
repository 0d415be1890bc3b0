#include "libpd/stability.hpp"

#include "libpd/force_kernel.hpp"
#include "libpd/simulation.hpp"
#include "libpd/stable_time_step.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <complex>
#include <fmt/format.h>
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

/// Largest y0 with |R(iy)|² ≤ 1 + excess for all y ∈ [0, y0] (scan, then bisection).
double interval_below(const std::vector<double>& q, double excess) {
  if (excess == 0) {
    for (double c : q) {
      if (c > 0) {
        return 0; // |R(iy)| > 1 right from y = 0
      }
      if (c < 0) {
        break;
      }
    }
  }
  const double h = 1e-3;
  double lo = 0, y = h;
  for (; y < 20; y += h) {
    if (evaluate(q, y) > excess) {
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
    (evaluate(q, mid) > excess ? hi : lo) = mid;
  }
  return lo;
}

} // namespace

double imaginary_stability_interval(const ButcherTableau& table) {
  return interval_below(modulus_excess(stability_polynomial(table)), 0.0);
}

double finite_horizon_interval(const ButcherTableau& table, std::size_t steps,
                               double amplification) {
  // |R(iy)|^N ≤ A  ⇔  |R(iy)|² ≤ A^{2/N}.
  const double excess = std::pow(amplification, 2.0 / static_cast<double>(steps)) - 1.0;
  return interval_below(modulus_excess(stability_polynomial(table)), excess);
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

FrequencyEstimate max_frequency(const Model& m, const std::vector<double>& mass,
                                int max_iterations) {
  // Symmetric form: with M = m_d V_i (mass per dof) and K_tot = V K (force, not force density),
  // A = M^{-1/2} K_tot M^{-1/2} has the eigenvalues ω² of M⁻¹K; A w = sqrt(V_i/m_d) (K u),
  // u = w / sqrt(m_d V_i).
  const std::size_t ndof = 3 * m.size();
  std::vector<double> scale(ndof, 0.0); // 1/sqrt(m_d V_i), 0 for constrained or absent dofs
  std::vector<std::uint8_t> free(ndof, 1);
  for (const Constraint& c : m.constraints) {
    free[3 * c.particle + c.component] = 0;
  }
  const int dim = m.spec.dimension.dim;
  for (std::size_t d = 0; d < ndof; ++d) {
    if (static_cast<int>(d % 3) >= dim) {
      free[d] = 0; // components outside the modelled space
    }
    const double md = mass.empty() ? m.density[d / 3] : mass[d];
    if (free[d]) {
      scale[d] = 1.0 / std::sqrt(md * m.particles.volume[d / 3]);
    }
  }
  std::vector<double> q(ndof, 0.0), q_prev(ndof, 0.0), u(ndof), ku(ndof), w(ndof);
  std::mt19937_64 rng(12345);
  std::uniform_real_distribution<double> dist(-1.0, 1.0);
  double norm = 0;
  for (std::size_t d = 0; d < ndof; ++d) {
    q[d] = free[d] ? dist(rng) : 0.0;
    norm += q[d] * q[d];
  }
  norm = std::sqrt(norm);
  if (norm == 0) {
    return {};
  }
  for (double& x : q) {
    x /= norm;
  }
  std::vector<double> alpha, beta;
  std::vector<double> history;
  FrequencyEstimate est;
  double b_prev = 0;
  for (int it = 0; it < max_iterations; ++it) {
    for (std::size_t d = 0; d < ndof; ++d) {
      u[d] = q[d] * scale[d];
    }
    apply_stiffness(m, u.data(), ku.data());
    double a = 0;
    for (std::size_t d = 0; d < ndof; ++d) {
      w[d] = free[d] ? ku[d] * m.particles.volume[d / 3] * scale[d] : 0.0;
      a += w[d] * q[d];
    }
    double bnorm = 0;
    for (std::size_t d = 0; d < ndof; ++d) {
      w[d] -= a * q[d] + b_prev * q_prev[d];
      bnorm += w[d] * w[d];
    }
    bnorm = std::sqrt(bnorm);
    alpha.push_back(a);
    const double top = largest_tridiagonal_eigenvalue(alpha, beta);
    history.push_back(top);
    est.iterations = it + 1;
    est.omega_max = std::sqrt(std::max(top, 0.0));
    if (history.size() > 10) {
      const double old = history[history.size() - 11];
      est.change = std::abs(top - old) / std::max(top, 1e-300);
      if (est.change < 1e-9) {
        break;
      }
    }
    if (bnorm < 1e-14 * std::max(std::abs(top), 1e-300)) {
      break; // invariant subspace: the Ritz values are exact
    }
    beta.push_back(bnorm);
    q_prev = q;
    for (std::size_t d = 0; d < ndof; ++d) {
      q[d] = w[d] / bnorm;
    }
    b_prev = bnorm;
  }
  return est;
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
  // The bounded run's own criterion: a mode must grow in amplitude by about sqrt(growth × free
  // dofs) to lift the total energy by `growth`, within N steps.
  std::size_t free_dofs = 0;
  for (std::size_t d = 0; d < 3 * model.size(); ++d) {
    free_dofs += static_cast<int>(d % 3) < s.model.dimension.dim ? 1 : 0;
  }
  free_dofs -= std::min(free_dofs, model.constraints.size());
  const double amplification = std::sqrt(opt.growth * static_cast<double>(free_dofs));
  if (target.kind == IntegratorKind::arkode) {
    r.interval_finite =
        finite_horizon_interval(butcher_tableau(target.table), opt.steps, amplification);
  } else {
    // Central differences: |μ| = 1 up to hω = 2, beyond it the larger root of
    // μ² − (2 − y²)μ + 1 = 0 grows as fast as an RK table's |R| grows past β.
    const double a = std::pow(amplification, 1.0 / static_cast<double>(opt.steps));
    r.interval_finite = std::sqrt(2.0 + a + 1.0 / a); // y² = 2 + μ + 1/μ at μ = −a
  }
  r.sharp_finite = r.interval_finite / omega_max;

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
