#include "stability_support.hpp"

#include "libpd/kernel/force_kernel.hpp"
#include "libpd/time/stability.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <numbers>
#include <stdexcept>

namespace stab {

pd::Scene load(const std::string& file) {
  return pd::load_scene(std::string(PD_STABILITY_SCENES_DIR) + "/" + file);
}

bool fields_finite(const pd::Simulation& sim) {
  const pd::State& s = sim.state();
  auto finite = [](const std::vector<double>& v) {
    return std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
  };
  return finite(s.position) && finite(s.velocity) && finite(s.force);
}

Trace run_traced(pd::Model& model, const pd::Scene& scene, std::size_t every) {
  Trace tr;
  pd::Simulation sim(model, scene.solver, scene.initial);
  const std::size_t ndof = 3 * model.size();
  std::vector<std::uint8_t> constrained(ndof, 0);
  for (const pd::Constraint& c : model.constraints) {
    constrained[3 * c.particle + c.component] = 1;
  }
  const bool loads = !model.external_force_density.empty();

  // The force at the initial positions, from a copy of the model so the run's bond history is not
  // touched (the run's own first force evaluation sees the same positions).
  std::vector<double> b_prev(ndof, 0.0);
  {
    pd::Model copy = model;
    auto f = pd::make_force_evaluator(copy);
    f->compute(sim.state().position.data(), b_prev.data());
  }
  std::vector<double> y_prev = sim.state().position;
  double t_prev = 0;
  const pd::LoadRamp ramp{scene.solver.ramp_time};

  tr.e0 = sim.kinetic_energy() + sim.strain_energy();
  tr.max_energy = tr.e0;
  auto sample = [&](const pd::Simulation& s) {
    const double e = s.kinetic_energy() + s.strain_energy();
    const double bal = e - tr.e0 - tr.work;
    tr.time.push_back(s.state().time);
    tr.balance.push_back(bal);
    tr.max_excess = std::max(tr.max_excess, bal);
    tr.max_deviation = std::max(tr.max_deviation, std::abs(bal));
    tr.max_energy = std::max(tr.max_energy, e);
    tr.finite = tr.finite && fields_finite(s) && std::isfinite(e);
    tr.energy = e;
  };
  sample(sim);

  const auto start = std::chrono::steady_clock::now();
  tr.result = sim.run([&](const pd::Simulation& s) {
    const pd::State& st = s.state();
    const double f_prev = ramp.factor(t_prev), f_now = ramp.factor(st.time);
    double dw = 0;
    for (std::size_t d = 0; d < ndof; ++d) {
      const double du = st.position[d] - y_prev[d];
      const double vol = model.particles.volume[d / 3];
      if (constrained[d]) {
        dw -= 0.5 * (b_prev[d] + st.force[d]) * vol * du;
      } else if (loads) {
        dw += 0.5 * (f_prev + f_now) * model.external_force_density[d] * vol * du;
      }
    }
    tr.work += dw;
    b_prev = st.force;
    y_prev = st.position;
    t_prev = st.time;
    if (st.step % every == 0) {
      sample(s);
    }
    return true;
  });
  tr.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (tr.result.status != pd::RunStatus::unstable) {
    sample(sim);
  } else {
    tr.finite = tr.finite && fields_finite(sim);
  }
  return tr;
}

std::string EnergyCheck::summary() const {
  return fmt::format("{} particles, {} steps of {:.4g} s = {:.3f} x eq31 (w_max dt = {:.3f}), "
                     "max (E-E0)/E0 = {:.2e}, max dip (E0-E)/E0 = {:.3e} (bound {:.3e}), at dt/2 "
                     "{:.3e} (ratio {:.2f}), run {:.2f} s",
                     particles, steps, dt, dt / dt_stable, omega_dt, excess, dip,
                     0.25 * omega_dt * omega_dt, dip_half, dip / dip_half, seconds);
}

EnergyCheck check_verlet_energy(const pd::Scene& scene, std::size_t steps) {
  EnergyCheck ec;
  pd::Scene s = scene;
  s.solver.max_steps = steps;
  pd::Model model = pd::build_model(s.model);
  const double omega_max = pd::max_frequency(model).omega_max;
  const Trace tr = run_traced(model, s, 10);
  EXPECT_EQ(tr.result.status, pd::RunStatus::max_steps) << tr.result.message;
  EXPECT_TRUE(tr.finite);
  EXPECT_EQ(tr.work, 0.0) << "this check is for runs without loads or moving supports";
  ec.dt = tr.result.dt;
  ec.dt_stable = tr.result.dt_stable;
  ec.omega_dt = omega_max * ec.dt;
  ec.particles = model.size();
  ec.steps = tr.result.steps;
  ec.seconds = tr.seconds;
  ec.excess = tr.max_excess / tr.e0;
  ec.dip = 0;
  for (double b : tr.balance) {
    ec.dip = std::max(ec.dip, -b / tr.e0);
  }
  EXPECT_GT(tr.e0, 0.0);
  EXPECT_LE(ec.excess, 1e-5) << "energy grew";
  EXPECT_LE(ec.dip, 0.25 * ec.omega_dt * ec.omega_dt) << "dip beyond Verlet's bound";

  pd::Scene h = s;
  if (h.solver.dt) {
    *h.solver.dt *= 0.5;
  } else {
    h.solver.safety *= 0.5;
  }
  h.solver.max_steps = 2 * steps;
  pd::Model half_model = pd::build_model(h.model);
  const Trace th = run_traced(half_model, h, 20);
  EXPECT_EQ(th.result.status, pd::RunStatus::max_steps) << th.result.message;
  EXPECT_TRUE(th.finite);
  for (double b : th.balance) {
    ec.dip_half = std::max(ec.dip_half, -b / th.e0);
  }
  EXPECT_GT(ec.dip / ec.dip_half, 3.0) << "the energy error does not shrink as Δt²";
  EXPECT_LT(ec.dip / ec.dip_half, 5.0) << "the energy error does not shrink as Δt²";
  return ec;
}

std::size_t check_damage(const pd::Model& m) {
  if (!m.effects.damage) {
    return 0;
  }
  EXPECT_EQ(m.state.broken.size(), m.family.directed_bond_count());
  EXPECT_EQ(m.state.damage.size(), m.size());
  std::size_t broken_directed = 0, asymmetric = 0, out_of_range = 0, mismatch = 0;
  for (std::size_t i = 0; i < m.size(); ++i) {
    std::size_t broken = 0;
    const std::size_t begin = m.family.offsets[i], end = m.family.offsets[i + 1];
    for (std::size_t k = begin; k < end; ++k) {
      if (!m.state.broken[k]) {
        continue;
      }
      ++broken;
      // The reverse bond j→i: rows are sorted by neighbour index.
      const std::size_t j = m.family.neighbour[k];
      const auto* first = m.family.neighbour.data() + m.family.offsets[j];
      const auto* last = m.family.neighbour.data() + m.family.offsets[j + 1];
      const auto* it = std::lower_bound(first, last, static_cast<std::uint32_t>(i));
      if (it == last || *it != i ||
          !m.state.broken[static_cast<std::size_t>(it - m.family.neighbour.data())]) {
        ++asymmetric;
      }
    }
    broken_directed += broken;
    const double phi = m.state.damage[i];
    if (!(phi >= 0.0 && phi <= 1.0)) {
      ++out_of_range;
    }
    const double expected =
        end > begin ? static_cast<double>(broken) / static_cast<double>(end - begin) : 0.0;
    if (std::abs(phi - expected) > 1e-15) {
      ++mismatch;
    }
  }
  EXPECT_EQ(out_of_range, 0u) << "particles with damage outside [0, 1]";
  EXPECT_EQ(mismatch, 0u) << "particles whose damage is not their broken-bond fraction (eq. 13)";
  EXPECT_EQ(asymmetric, 0u) << "bonds broken in one direction only";
  return broken_directed / 2;
}

double eq31_from_scratch(const pd::Model& m) {
  const pd::ModelSpec& spec = m.spec;
  const double delta = spec.lattice.horizon();
  const int dim = spec.dimension.dim;
  std::vector<double> c(spec.materials.size());
  for (std::size_t k = 0; k < c.size(); ++k) {
    const double e = spec.materials[k].youngs_modulus * spec.materials[k].stiffness_factor;
    if (dim == 3) {
      c[k] = 12.0 * e / (std::numbers::pi * std::pow(delta, 4)); // Miranda eq. 8, ν = 1/4
    } else if (dim == 1) {
      c[k] = 2.0 * e / (spec.dimension.cross_section * delta * delta); // Bobaru et al. 2009
    } else {
      throw std::invalid_argument("eq31_from_scratch: 1D and 3D only");
    }
  }
  // Bonds of length ≤ δ (inclusive rule) with the library's guard band of 1e-9 δ.
  const double reach2 = std::pow(delta * (1.0 + 1e-9), 2);
  double dt = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < m.size(); ++i) {
    double sum = 0;
    const auto& xi = m.particles.position[i];
    for (std::size_t j = 0; j < m.size(); ++j) {
      if (j == i) {
        continue;
      }
      const auto& xj = m.particles.position[j];
      const double d2 = (xj[0] - xi[0]) * (xj[0] - xi[0]) + (xj[1] - xi[1]) * (xj[1] - xi[1]) +
                        (xj[2] - xi[2]) * (xj[2] - xi[2]);
      if (d2 <= reach2) {
        const double cij = std::min(c[m.particles.material[i]], c[m.particles.material[j]]);
        sum += cij * m.particles.volume[j] / std::sqrt(d2); // |C| = c/|ξ|
      }
    }
    if (sum > 0) {
      dt = std::min(dt, std::sqrt(2.0 * m.density[i] / sum)); // eq. 31
    }
  }
  return dt;
}

} // namespace stab
