#include "libpd/time/integrator.hpp"

#include "libpd/core/binary_state.hpp"

#include <cmath>
#include <fmt/format.h>
#include <limits>
#include <stdexcept>

namespace pd {

std::string to_string(IntegratorKind kind) {
  return std::string(name_of(kind));
}

std::string to_string(ArkodeTable table) {
  return std::string(name_of(table));
}

bool ButcherTableau::hit_by_issue_311() const {
  if (stages < 1 || std::abs(c[static_cast<std::size_t>(stages - 1)] - 1.0) > 1e-12) {
    return false;
  }
  const auto s = static_cast<std::size_t>(stages);
  for (std::size_t j = 0; j < s; ++j) {
    if (std::abs(a[(s - 1) * s + j] - b[j]) > 1e-14) {
      return true; // c_s = 1 but not first-same-as-last
    }
  }
  return false;
}

void Integrator::save(CheckpointWriter& w) const {
  w.section("INTG");
  w.string(name());
  w.u64(force_evaluations_);
  w.u64(calls_);
  save_state(w);
}

void Integrator::restore(CheckpointReader& r) {
  r.section("INTG");
  const std::string saved = r.string();
  if (saved != name()) {
    r.fail(fmt::format("written by integrator '{}', this run uses '{}'", saved, name()));
  }
  force_evaluations_ = r.u64();
  calls_ = r.u64();
  restore_state(r);
}

void apply_constraints(const Model& model, const LoadRamp& ramp, double t, double* position,
                       double* velocity) {
  const double factor = ramp.factor(t);
  const double rate = ramp.rate(t);
  const auto& x = model.particles.position;
  for (const Constraint& c : model.constraints) {
    const std::size_t dof = 3 * c.particle + c.component;
    if (c.mirror_of != Constraint::no_mirror) { // sources are free particles, already updated
      const std::size_t src = 3 * c.mirror_of + c.component;
      position[dof] = x[c.particle][c.component] +
                      c.mirror_sign * (position[src] - x[c.mirror_of][c.component]);
      if (velocity != nullptr) {
        velocity[dof] = c.mirror_sign * velocity[src];
      }
      continue;
    }
    position[dof] = x[c.particle][c.component] + factor * c.value;
    if (velocity != nullptr) {
      velocity[dof] = rate * c.value;
    }
  }
}

StepReport displacement_report(const Model& m, const double* y) {
  const auto n = static_cast<std::ptrdiff_t>(m.size());
  double worst = 0;
  bool finite = true;
#pragma omp parallel for schedule(static) reduction(max : worst) reduction(&& : finite) \
    if (m.size() >= parallel_min_particles)
  for (std::ptrdiff_t ii = 0; ii < n; ++ii) {
    const auto i = static_cast<std::size_t>(ii);
    double u2 = 0;
    for (int c = 0; c < 3; ++c) {
      const double u = y[3 * i + c] - m.particles.position[i][c];
      finite = finite && std::isfinite(u); // u² may overflow while u is still finite
      u2 += u * u;
    }
    worst = std::max(worst, u2);
  }
  StepReport r;
  r.max_displacement_squared = finite ? worst : std::numeric_limits<double>::quiet_NaN();
  return r;
}

namespace {

/// Miranda §3.2, steps (2)–(19): forces at the current positions, then
/// v ← ψ [v + Δt (b + F b_ext)/ρ], y ← y + Δt v. With c_v = 0 this is Euler–Cromer.
class DampedEuler final : public Integrator {
public:
  DampedEuler(Model& m, ForceEvaluator& f, const IntegratorSettings& s)
      : model_(m), forces_(f), damping_(s.damping), ramp_(s.ramp),
        name_(s.kind == IntegratorKind::euler_cromer ? "euler-cromer" : "damped-euler") {}

  StepReport step(State& st, double dt) override {
    ++calls_;
    forces_.compute(st.position.data(), st.force.data());
    ++force_evaluations_;
    const double t_new = st.time + dt;
    const double load = ramp_.factor(t_new);
    const double* ext =
        model_.external_force_density.empty() ? nullptr : model_.external_force_density.data();
    const auto n = static_cast<std::ptrdiff_t>(model_.size());
    double* y = st.position.data();
    double* v = st.velocity.data();
    const double* b = st.force.data();
#pragma omp parallel for schedule(static) if (model_.size() >= parallel_min_particles)
    for (std::ptrdiff_t ii = 0; ii < n; ++ii) {
      const auto i = static_cast<std::size_t>(ii);
      const double rho = model_.density[i];
      const double psi = 1.0 / (1.0 + dt * damping_ / rho); // eq. 32
      for (std::size_t c = 0; c < 3; ++c) {
        const std::size_t dof = 3 * i + c;
        const double f = ext != nullptr ? b[dof] + load * ext[dof] : b[dof];
        v[dof] = psi * (v[dof] + dt * f / rho);
        y[dof] += dt * v[dof];
      }
    }
    apply_constraints(model_, ramp_, t_new, y, v);
    st.time = t_new;
    ++st.step;
    return displacement_report(model_, y);
  }

  std::string name() const override {
    return name_;
  }

private:
  Model& model_;
  ForceEvaluator& forces_;
  double damping_;
  LoadRamp ramp_;
  std::string name_;
};

/// Velocity Verlet: half kick, drift, force, half kick. One force evaluation per step after the
/// first.
class VelocityVerlet final : public Integrator {
public:
  VelocityVerlet(Model& m, ForceEvaluator& f, const IntegratorSettings& s)
      : model_(m), forces_(f), ramp_(s.ramp) {}

  StepReport step(State& st, double dt) override {
    ++calls_;
    if (!primed_) {
      forces_.compute(st.position.data(), st.force.data());
      ++force_evaluations_;
      primed_ = true;
    }
    kick(st, 0.5 * dt, ramp_.factor(st.time));
    const auto ndof = static_cast<std::ptrdiff_t>(st.position.size());
    double* y = st.position.data();
    const double* v = st.velocity.data();
#pragma omp parallel for schedule(static) if (model_.size() >= parallel_min_particles)
    for (std::ptrdiff_t d = 0; d < ndof; ++d) {
      y[d] += dt * v[d];
    }
    st.time += dt;
    apply_constraints(model_, ramp_, st.time, y, nullptr);
    forces_.compute(st.position.data(), st.force.data());
    ++force_evaluations_;
    kick(st, 0.5 * dt, ramp_.factor(st.time));
    apply_constraints(model_, ramp_, st.time, y, st.velocity.data());
    ++st.step;
    return displacement_report(model_, y);
  }

  std::string name() const override {
    return "verlet";
  }

protected:
  // The first step computes the force at the initial positions; later steps reuse State::force,
  // which the checkpoint holds.
  void save_state(CheckpointWriter& w) const override {
    w.boolean(primed_);
  }
  void restore_state(CheckpointReader& r) override {
    primed_ = r.boolean();
  }

private:
  void kick(State& st, double h, double load) {
    const double* ext =
        model_.external_force_density.empty() ? nullptr : model_.external_force_density.data();
    const auto n = static_cast<std::ptrdiff_t>(model_.size());
    double* v = st.velocity.data();
    const double* b = st.force.data();
#pragma omp parallel for schedule(static) if (model_.size() >= parallel_min_particles)
    for (std::ptrdiff_t ii = 0; ii < n; ++ii) {
      const auto i = static_cast<std::size_t>(ii);
      const double scale = h / model_.density[i];
      for (std::size_t c = 0; c < 3; ++c) {
        const std::size_t dof = 3 * i + c;
        v[dof] += scale * (ext != nullptr ? b[dof] + load * ext[dof] : b[dof]);
      }
    }
  }

  Model& model_;
  ForceEvaluator& forces_;
  LoadRamp ramp_;
  bool primed_ = false;
};

} // namespace

std::unique_ptr<Integrator> make_integrator(const IntegratorSettings& s, Model& model,
                                            ForceEvaluator& forces) {
  switch (s.kind) {
  case IntegratorKind::damped_euler:
  case IntegratorKind::euler_cromer: {
    IntegratorSettings settings = s;
    if (s.kind == IntegratorKind::euler_cromer) {
      settings.damping = 0;
    }
    return std::make_unique<DampedEuler>(model, forces, settings);
  }
  case IntegratorKind::verlet:
    return std::make_unique<VelocityVerlet>(model, forces, s);
  case IntegratorKind::adr:
    return make_adr_integrator(s, model, forces);
  case IntegratorKind::arkode:
    return make_arkode_integrator(s, model, forces);
  }
  throw std::logic_error("unknown integrator");
}

} // namespace pd
