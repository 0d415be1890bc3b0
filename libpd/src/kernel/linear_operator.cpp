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

bool folds_dependants(const Model& model) {
  return consistent_mirror_coupling(model) || !model.extrapolated.empty();
}

std::vector<std::uint8_t> massless_dependants(const Model& model) {
  return energy_dependants(model.size(), model.spec.mirror_coupling, model.constraints,
                           model.extrapolated);
}

std::vector<double> constraint_row_norms(const Model& model) {
  std::vector<double> norm(model.size(), 1.0);
  const ExtrapolatedParticles& e = model.extrapolated;
  for (std::size_t d = 0; d < e.size(); ++d) {
    double sum = 0;
    for (std::size_t t = e.offsets[d]; t < e.offsets[d + 1]; ++t) {
      sum += std::abs(e.coefficient[t]);
    }
    norm[e.particle[d]] = sum;
  }
  return norm;
}

namespace {

template <class Sign>
void fold(const Model& model, double* v, Sign sign) {
  const auto& volume = model.particles.volume;
  // Sources are never dependants themselves (support_constraints, extrapolated_particles), so one
  // pass is the whole transpose and its order does not matter.
  if (model.spec.mirror_coupling == MirrorCoupling::consistent) {
    for (const Constraint& c : model.constraints) { // copy coupling: reactions that go nowhere
      if (c.mirror_of == Constraint::no_mirror) {
        continue;
      }
      v[3 * c.mirror_of + c.component] += sign(c.mirror_sign) * v[3 * c.particle + c.component] *
                                          volume[c.particle] / volume[c.mirror_of];
    }
  }
  const ExtrapolatedParticles& e = model.extrapolated;
  for (std::size_t d = 0; d < e.size(); ++d) {
    const std::size_t p = e.particle[d];
    for (std::size_t t = e.offsets[d]; t < e.offsets[d + 1]; ++t) {
      const std::size_t s = e.source[t];
      const double a = sign(e.coefficient[t]) * volume[p] / volume[s];
      for (std::size_t c = 0; c < 3; ++c) {
        v[3 * s + c] += sign(e.sign(d, c)) * a * v[3 * p + c];
      }
    }
  }
}

} // namespace

void fold_mirror_forces(const Model& model, double* force_density) {
  fold(model, force_density, [](double s) { return s; });
}

void fold_mirror_bounds(const Model& model, double* bound) {
  fold(model, bound, [](double s) { return std::abs(s); });
}

void set_extrapolated(const Model& model, double* v) {
  const ExtrapolatedParticles& e = model.extrapolated;
  for (std::size_t d = 0; d < e.size(); ++d) {
    const std::size_t p = e.particle[d];
    double acc[3] = {0, 0, 0};
    for (std::size_t t = e.offsets[d]; t < e.offsets[d + 1]; ++t) {
      for (std::size_t c = 0; c < 3; ++c) {
        acc[c] += e.coefficient[t] * v[3 * e.source[t] + c];
      }
    }
    for (std::size_t c = 0; c < 3; ++c) {
      v[3 * p + c] = e.sign(d, c) * acc[c];
    }
  }
}

void apply_constrained_operator(const Model& m, double* u, double* ku) {
  for (const Constraint& c : m.constraints) {
    if (c.mirror_of != Constraint::no_mirror) {
      u[3 * c.particle + c.component] = c.mirror_sign * u[3 * c.mirror_of + c.component];
    }
  }
  set_extrapolated(m, u);
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
  if (!folds_dependants(model)) {
    return inner;
  }
  return std::make_unique<ConstrainedForces>(model, std::move(inner));
}

} // namespace pd
