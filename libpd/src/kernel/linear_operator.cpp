#include "libpd/kernel/linear_operator.hpp"

#include "libpd/kernel/force_kernel.hpp"

#include <cmath>
#include <span>
#include <vector>

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
        v[3 * s + c] += sign(e.sign(t, c)) * a * v[3 * p + c];
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
        acc[c] += e.sign(t, c) * e.coefficient[t] * v[3 * e.source[t] + c];
      }
    }
    for (std::size_t c = 0; c < 3; ++c) {
      v[3 * p + c] = acc[c];
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

/// u = y − X (3N values).
void displacement_of(const Model& m, const double* y, double* u) {
  for (std::size_t i = 0; i < m.size(); ++i) {
    for (std::size_t c = 0; c < 3; ++c) {
      u[3 * i + c] = y[3 * i + c] - m.particles.position[i][c];
    }
  }
}

/// b = −K u, u = y − X (make_linearised_force_evaluator).
class LinearisedForces final : public ForceEvaluator {
public:
  explicit LinearisedForces(Model& model) : model_(model), u_(3 * model.size()) {}
  void compute(const double* y, double* b) override {
    displacement_of(model_, y, u_.data());
    apply_constrained_operator(model_, u_.data(), b);
    for (double& v : std::span(b, u_.size())) {
      v = -v;
    }
  }
  /// Σ_i V_i Σ_j ¼ k_ij (n·(u_j − u_i))²: the kernel's Σ_i V_i ½ Σ_j w_ij V_j with w = ½ c s² |ξ|
  /// at the linearised stretch s = n·(u_j − u_i)/|ξ|.
  double strain_energy(const double* y) const override {
    std::vector<double> u(u_.size());
    displacement_of(model_, y, u.data());
    double energy = 0;
    for (std::size_t i = 0; i < model_.size(); ++i) {
      double row = 0;
      for_each_linearised_bond(model_, i, BrokenBonds::left_out, [&](const LinearisedBond& b) {
        double stretch = 0;
        for (std::size_t c = 0; c < 3; ++c) {
          stretch += b.direction[c] * (u[3 * b.neighbour + c] - u[3 * i + c]);
        }
        row += 0.25 * b.stiffness * stretch * stretch;
      });
      energy += model_.particles.volume[i] * row;
    }
    return energy;
  }
  std::string description() const override { return "linearised (small displacements)"; }

private:
  Model& model_;
  std::vector<double> u_; ///< compute()'s displacement, kept between calls
};

} // namespace

std::unique_ptr<ForceEvaluator> make_linearised_force_evaluator(Model& model) {
  return std::make_unique<LinearisedForces>(model);
}

std::unique_ptr<ForceEvaluator> make_constrained_force_evaluator(Model& model) {
  auto inner = make_force_evaluator(model);
  if (!folds_dependants(model)) {
    return inner;
  }
  return std::make_unique<ConstrainedForces>(model, std::move(inner));
}

} // namespace pd
