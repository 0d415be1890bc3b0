#include "libpd/time/stability.hpp"

#include "libpd/kernel/force_kernel.hpp"
#include "libpd/kernel/stable_time_step.hpp"
#include "libpd/time/simulation.hpp"

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

namespace {

/// The largest Δt seen stable and the smallest seen unstable, bracketed around `guess` and
/// bisected geometrically to the relative tolerance. A bracket that cannot be closed is an
/// error, never a "measured" limit: lo must have been seen stable and hi unstable.
template <class StableAt>
std::pair<double, double> bracket_and_bisect(StableAt&& stable_at, double guess, double eq31,
                                             const std::string& integrator,
                                             const StabilityOptions& opt) {
  double lo = 0.5 * guess, hi = 2.0 * guess;
  constexpr int max_doublings = 20;
  int halvings = 0;
  while (!stable_at(lo)) {
    if (++halvings > max_doublings) {
      throw std::runtime_error(
          fmt::format("{}: unstable even at Δt = {:.3g} s (2^-{} of the guess {:.3g} s)",
                      integrator, lo, max_doublings, guess));
    }
    hi = lo;
    lo *= 0.5;
  }
  int doublings = 0;
  while (stable_at(hi)) {
    if (++doublings > max_doublings) {
      throw std::runtime_error(fmt::format(
          "{}: no instability within {} steps up to Δt = {:.3g} s ({}× eq. 31): the bounded "
          "runs are too short to measure a limit",
          integrator, opt.steps, hi, hi / eq31));
    }
    lo = hi;
    hi *= 2.0;
  }
  while (hi / lo > 1 + opt.relative_tolerance) {
    const double mid = std::sqrt(lo * hi);
    (stable_at(mid) ? lo : hi) = mid;
  }
  return {lo, hi};
}

} // namespace

ModelSpec stability_model(const ModelSpec& spec) {
  ModelSpec s = spec;
  s.loads.clear(); // build_model derives body_force from the loads, so it goes with them
  s.effects.damping = false;
  // The stable time step belongs to the elastic operator (eq. 31 and the spectrum are of it):
  // bonds that break or yield under the growing perturbation would absorb its energy and make
  // an unstable Δt look stable.
  s.effects.damage = false;
  s.effects.plasticity = false;
  return s;
}

StabilityResult measure_stability(const ModelSpec& spec, const SolverSpec& solver_spec,
                                  const StabilityTarget& target, const StabilityOptions& opt,
                                  double omega_max) {
  const auto start = std::chrono::steady_clock::now();
  if (!(opt.relative_tolerance > 0 && opt.relative_tolerance < 1)) {
    throw std::invalid_argument(
        fmt::format("the bisection tolerance must lie in (0, 1), not {}", opt.relative_tolerance));
  }
  if (opt.steps < min_stability_steps) {
    throw std::invalid_argument(
        fmt::format("a bounded run of {} steps cannot show a growing mode: use at least {} steps",
                    opt.steps, min_stability_steps));
  }
  const ModelSpec model_spec = stability_model(spec);
  SolverSpec unloaded = solver_spec;
  unloaded.damping = 0;
  unloaded.ramp_time = 0;
  unloaded.steady.enabled = false;
  unloaded.end_time.reset();
  Model model = build_model(model_spec);
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
    const double amp = opt.perturbation * model_spec.lattice.spacing;
    for (std::size_t d = 0; d < du.size(); ++d) {
      if (static_cast<int>(d % 3) < model_spec.dimension.dim) {
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
    SolverSpec solver = unloaded;
    solver.integrator = target.kind;
    solver.arkode.table = target.table;
    solver.arkode.adaptive = false;
    solver.dt = dt;
    solver.max_steps = opt.steps;
    solver.blowup_displacement = 1e30; // the energy test below decides
    solver.energy_check = false;
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

  const auto [lo, hi] = bracket_and_bisect(stable_at, r.eq31 * scale, r.eq31, r.integrator, opt);
  r.measured = lo;
  r.unstable = hi;
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

} // namespace pd
