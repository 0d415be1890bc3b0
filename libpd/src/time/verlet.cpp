// Velocity Verlet: second order and symplectic, for dynamics and energy checks.
#include "libpd/core/binary_state.hpp"
#include "libpd/time/integrator.hpp"

namespace pd {

namespace {

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

std::unique_ptr<Integrator> make_verlet_integrator(const IntegratorSettings& s, Model& model,
                                                   ForceEvaluator& forces) {
  return std::make_unique<VelocityVerlet>(model, forces, s);
}

} // namespace pd
