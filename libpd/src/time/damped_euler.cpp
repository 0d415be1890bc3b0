// Damped Euler (Miranda §3.2) and, as its undamped case, Euler–Cromer: semi-implicit Euler with
// kinematic damping, v ← ψ [v + Δt a], y ← y + Δt v, ψ = (1 + Δt c_v/ρ)⁻¹ (eq. 32). Euler–Cromer
// is the same scheme with c_v = 0 (ψ = 1 exactly), so both kinds share this one class and loop.
#include "libpd/time/integrator.hpp"

namespace pd {

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

  double round_off_amplification(double dt) const override {
    return kinematic_damping_amplification(model_, damping_, dt);
  }

private:
  Model& model_;
  ForceEvaluator& forces_;
  double damping_;
  LoadRamp ramp_;
  std::string name_;
};

} // namespace

std::unique_ptr<Integrator> make_damped_euler_integrator(const IntegratorSettings& s, Model& model,
                                                         ForceEvaluator& forces) {
  IntegratorSettings settings = s;
  if (s.kind == IntegratorKind::euler_cromer) {
    settings.damping = 0;
  }
  return std::make_unique<DampedEuler>(model, forces, settings);
}

} // namespace pd
