#include "libpd/kernel/force_kernel.hpp"

#include "libpd/kernel/simd_bond_loop.hpp"

#include <cstdint>
#include <fmt/format.h>
#include <limits>

namespace pd {

KernelData kernel_data(Model& m) {
  KernelData d;
  d.particles = m.size();
  d.offsets = m.family.offsets.data();
  d.neighbour = m.family.neighbour.data();
  d.inverse_length = m.family.inverse_length.data();
  d.stiffness = m.field.stiffness;
  d.critical_stretch = m.field.critical_stretch;
  d.yield_stretch = m.field.yield_stretch;
  d.bond_stiffness = m.field.bond_stiffness.empty() ? nullptr : m.field.bond_stiffness.data();
  d.bond_critical_stretch =
      m.field.bond_critical_stretch.empty() ? nullptr : m.field.bond_critical_stretch.data();
  d.bond_yield_stretch =
      m.field.bond_yield_stretch.empty() ? nullptr : m.field.bond_yield_stretch.data();
  d.broken = m.state.broken.empty() ? nullptr : m.state.broken.data();
  d.plastic_stretch = m.state.plastic_stretch.empty() ? nullptr : m.state.plastic_stretch.data();
  d.damage = m.state.damage.empty() ? nullptr : m.state.damage.data();
  return d;
}

namespace {

template <StretchMeasure Stretch, BondLaw Law, bool Damage, class Field>
class KernelEvaluator final : public ForceEvaluator {
public:
  /// `simd` null: the scalar template; otherwise that row kernel of the SIMD path.
  KernelEvaluator(Model& model, kernel::RowKernel simd)
      : model_(model), simd_(simd),
        path_(simd == nullptr ? "scalar" : "simd/" + kernel::simd_target_name()) {}

  void compute(const double* y, double* b) override {
    if (simd_ == nullptr) {
      accumulate_bond_forces<Stretch, Law, Damage, Field>(kernel_data(model_), y, b);
      return;
    }
    const KernelData d = kernel_data(model_);
    kernel::for_row_ranges(d.offsets, d.particles, [&](std::size_t first, std::size_t last) {
      simd_(d, y, b, first, last);
    });
  }

  double strain_energy(const double* y) const override {
    const KernelData d = kernel_data(model_);
    const auto& volume = model_.particles.volume;
    const auto n = static_cast<std::ptrdiff_t>(d.particles);
    double total = 0;
    // Static schedule + ordered reduction tree is not guaranteed by OpenMP, so sum per particle
    // into an array and add sequentially: the energy is then thread-count independent too.
    std::vector<double> per_particle(d.particles, 0.0);
#pragma omp parallel for schedule(static) if (d.particles >= parallel_min_particles)
    for (std::ptrdiff_t ii = 0; ii < n; ++ii) {
      const auto i = static_cast<std::size_t>(ii);
      double w = 0;
      for (std::size_t k = d.offsets[i]; k < d.offsets[i + 1]; ++k) {
        if constexpr (Damage) {
          if (d.broken[k]) {
            continue;
          }
        }
        const std::size_t j = d.neighbour[k];
        double r2 = 0;
        for (int c = 0; c < 3; ++c) {
          const double dy = y[3 * j + c] - y[3 * i + c];
          r2 += dy * dy;
        }
        const double c = Field::per_bond ? d.bond_stiffness[k] : d.stiffness;
        const double plastic = Law::has_history ? d.plastic_stretch[k] : 0.0;
        w += c * Stretch::bond_energy(r2, d.inverse_length[k], plastic);
      }
      per_particle[i] = 0.5 * w * volume[i];
    }
    // Exact, over the owned particles: the same energy for any thread or rank count.
    const Ownership& own = model_.ownership;
    ExactSum sum;
    for (std::size_t i = 0; i < per_particle.size(); ++i) {
      if (own.owns(i)) {
        sum.add(per_particle[i]);
      }
    }
    total = own.communicator().sum(sum);
    return total;
  }

  std::string description() const override {
    return fmt::format("stretch={} law={} damage={} field={} path={}", Stretch::name, Law::name,
                       Damage ? "on" : "off", Field::per_bond ? "per-bond" : "uniform", path_);
  }

private:
  Model& model_;
  kernel::RowKernel simd_;
  std::string path_; ///< "scalar" or "simd/<instruction set picked when the kernel was chosen>"
};

template <StretchMeasure S, BondLaw L, bool D>
std::unique_ptr<ForceEvaluator> pick_field(Model& m, kernel::RowKernel simd) {
  if (m.effects.per_bond_field) {
    return std::make_unique<KernelEvaluator<S, L, D, PerBondField>>(m, simd);
  }
  return std::make_unique<KernelEvaluator<S, L, D, UniformField>>(m, simd);
}

template <StretchMeasure S, BondLaw L>
std::unique_ptr<ForceEvaluator> pick_damage(Model& m, kernel::RowKernel simd) {
  return m.effects.damage ? pick_field<S, L, true>(m, simd) : pick_field<S, L, false>(m, simd);
}

template <StretchMeasure S>
std::unique_ptr<ForceEvaluator> pick_law(Model& m, kernel::RowKernel simd) {
  return m.effects.plasticity ? pick_damage<S, MicroPlastic>(m, simd)
                              : pick_damage<S, MicroElastic>(m, simd);
}

} // namespace

std::unique_ptr<ForceEvaluator> make_force_evaluator(Model& m, KernelPath path) {
  if (m.effects.bond_model == BondModel::virtual_fibres) {
    return make_fibre_evaluator(m, path); // its own kernel (src/kernel/fibre_kernel.cpp)
  }
  if (m.effects.damage && m.state.broken.size() != m.family.directed_bond_count()) {
    throw std::logic_error("damage effect without bond state: build the model with build_model");
  }
  if (m.effects.plasticity && m.state.plastic_stretch.size() != m.family.directed_bond_count()) {
    throw std::logic_error(
        "plasticity effect without bond state: build the model with build_model");
  }
  // Sized, not merely non-empty: a model whose bonds all lost their stiffness (a lone particle)
  // has a per-bond field of zero entries, which is allocated.
  if (m.effects.per_bond_field && m.field.bond_stiffness.size() != m.family.directed_bond_count()) {
    throw std::logic_error("per-bond field requested but not allocated");
  }
  // The SIMD kernel gathers with 32-bit signed indices.
  const bool simd = path == KernelPath::simd &&
                    m.size() <= static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max());
  const kernel::RowKernel rows =
      simd ? kernel::simd_row_kernel(m.effects.stretch, m.effects.plasticity, m.effects.damage,
                                     m.effects.per_bond_field)
           : nullptr;
  switch (m.effects.stretch) {
  case StretchKind::exact:
    return pick_law<ExactStretch>(m, rows);
  case StretchKind::modified:
    return pick_law<ModifiedStretch>(m, rows);
  case StretchKind::fast:
    return pick_law<FastStretch>(m, rows);
  }
  throw std::logic_error("unknown stretch measure");
}

} // namespace pd
