#include "libpd/kernel/linear_operator.hpp"

#include "libpd/kernel/force_kernel.hpp"

#include <cmath>

namespace pd {

void apply_linearised_operator(const Model& m, const double* u, double* out) {
  const auto n = static_cast<std::ptrdiff_t>(m.size());
#pragma omp parallel for schedule(static) if (m.size() >= parallel_min_particles)
  for (std::ptrdiff_t ii = 0; ii < n; ++ii) {
    const auto i = static_cast<std::size_t>(ii);
    double acc[3] = {0, 0, 0};
    for_each_linearised_bond(m, i, BrokenBonds::left_out, [&](const LinearisedBond& b) {
      const std::size_t j = b.neighbour;
      double proj = 0;
      for (std::size_t c = 0; c < 3; ++c) {
        proj += b.direction[c] * (u[3 * i + c] - u[3 * j + c]);
      }
      for (std::size_t c = 0; c < 3; ++c) {
        acc[c] += b.stiffness * proj * b.direction[c];
      }
    });
    for (std::size_t c = 0; c < 3; ++c) {
      out[3 * i + c] = acc[c];
    }
  }
}

bool consistent_mirror_coupling(const Model& model) {
  return consistent_mirror_coupling(model.spec.mirror_coupling, model.constraints);
}

std::vector<std::uint8_t> massless_mirror_particles(const Model& model) {
  if (!consistent_mirror_coupling(model)) {
    return std::vector<std::uint8_t>(model.size(), 0);
  }
  return mirror_dependent_particles(model.size(), model.constraints);
}

namespace {

template <class Sign>
void fold(const Model& model, double* v, Sign sign) {
  if (model.spec.mirror_coupling != MirrorCoupling::consistent) {
    return; // copy coupling: the dependants' forces are reactions and go nowhere
  }
  const auto& volume = model.particles.volume;
  // Sources are never constrained themselves (support_constraints), so one pass is the whole
  // transpose and its order does not matter.
  for (const Constraint& c : model.constraints) {
    if (c.mirror_of == Constraint::no_mirror) {
      continue;
    }
    v[3 * c.mirror_of + c.component] += sign(c.mirror_sign) * v[3 * c.particle + c.component] *
                                        volume[c.particle] / volume[c.mirror_of];
  }
}

} // namespace

void fold_mirror_forces(const Model& model, double* force_density) {
  fold(model, force_density, [](double s) { return s; });
}

void fold_mirror_bounds(const Model& model, double* bound) {
  fold(model, bound, [](double s) { return std::abs(s); });
}

void apply_constrained_operator(const Model& m, double* u, double* ku) {
  for (const Constraint& c : m.constraints) {
    if (c.mirror_of != Constraint::no_mirror) {
      u[3 * c.particle + c.component] = c.mirror_sign * u[3 * c.mirror_of + c.component];
    }
  }
  apply_linearised_operator(m, u, ku);
  fold_mirror_forces(m, ku);
}

namespace {

/// Sends the mirror dependants' forces back to their images after the kernel (Rᵀ).
class ConstrainedForces final : public ForceEvaluator {
public:
  ConstrainedForces(Model& model, std::unique_ptr<ForceEvaluator> inner)
      : model_(model), inner_(std::move(inner)) {}
  void compute(const double* y, double* b) override {
    inner_->compute(y, b);
    fold_mirror_forces(model_, b);
  }
  double strain_energy(const double* y) const override { return inner_->strain_energy(y); }
  std::string description() const override {
    return inner_->description() + " constraints=mirror-transpose";
  }

private:
  Model& model_;
  std::unique_ptr<ForceEvaluator> inner_;
};

} // namespace

std::unique_ptr<ForceEvaluator> make_constrained_force_evaluator(Model& model) {
  auto inner = make_force_evaluator(model);
  if (!consistent_mirror_coupling(model)) {
    return inner;
  }
  return std::make_unique<ConstrainedForces>(model, std::move(inner));
}

} // namespace pd
