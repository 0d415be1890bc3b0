// The force kernel: internal force density of every particle,
//   b_i = Σ_j f(y_j − y_i, ξ_ij) V_j          (Miranda eq. 27)
// gathered per particle over its CSR row.
//
// The loop is a template over independent policies — stretch measure, bond law, damage on/off and
// uniform/per-bond field — and `make_force_evaluator` picks the one instantiation that matches the
// scene's effect set once per run. An effect that is off is not a branch in the loop; its state is
// not even allocated (see BondState).
//
// Threads split the particle loop statically; each particle's sum runs in the same order whatever
// the thread count, so forces (and whole runs) are bitwise identical for any number of threads.
#pragma once

#include "libpd/core/names.hpp"
#include "libpd/discretisation/model.hpp"
#include "libpd/kernel/kernel_data.hpp"
#include "libpd/physics/bond_laws.hpp"
#include "libpd/physics/stretch.hpp"

#include <memory>
#include <string>

namespace pd {

/// Below this many particles a parallel region costs more than it saves (and on a busy machine
/// an oversubscribed barrier per step can cost 10× the work), so small models run serially.
inline constexpr std::size_t parallel_min_particles = 4096;

/// Views of `model`'s arrays (KernelData lives in kernel_data.hpp, shared with the SIMD loop).
KernelData kernel_data(Model& model);

/// The bond loop for one effect combination. `y` holds current positions (3 per particle),
/// `b` receives the internal force density (3 per particle). Damage and plastic history are
/// updated in place (the decision for bond i→j and j→i is bitwise identical since both see the
/// same r², so no synchronisation is needed).
template <StretchMeasure Stretch, BondLaw Law, bool Damage, class Field>
void accumulate_bond_forces(const KernelData& d, const double* y, double* b) {
  const auto n = static_cast<std::ptrdiff_t>(d.particles);
#pragma omp parallel for schedule(static) if (d.particles >= parallel_min_particles)
  for (std::ptrdiff_t ii = 0; ii < n; ++ii) {
    const auto i = static_cast<std::size_t>(ii);
    const double yi0 = y[3 * i], yi1 = y[3 * i + 1], yi2 = y[3 * i + 2];
    double b0 = 0, b1 = 0, b2 = 0;
    std::size_t broken_count = 0;
    const std::size_t begin = d.offsets[i], end = d.offsets[i + 1];
    for (std::size_t k = begin; k < end; ++k) {
      if constexpr (Damage) {
        if (d.broken[k]) {
          ++broken_count;
          continue;
        }
      }
      const std::size_t j = d.neighbour[k];
      const double dy0 = y[3 * j] - yi0, dy1 = y[3 * j + 1] - yi1, dy2 = y[3 * j + 2] - yi2;
      const double r2 = dy0 * dy0 + dy1 * dy1 + dy2 * dy2;
      const StretchResult sr = Stretch::evaluate(r2, d.inverse_length[k]);
      if constexpr (Damage) {
        const double s0 = Field::per_bond ? d.bond_critical_stretch[k] : d.critical_stretch;
        if (sr.stretch >= s0) { // eq. 10: once broken, never restored
          d.broken[k] = 1;
          ++broken_count;
          continue;
        }
      }
      // Only plastic laws read or write the history; others get a scratch slot.
      double scratch = 0;
      double* plastic = &scratch;
      double yield = 0;
      if constexpr (Law::has_history) {
        plastic = &d.plastic_stretch[k];
        yield = Field::per_bond ? d.bond_yield_stretch[k] : d.yield_stretch;
      }
      const double c = Field::per_bond ? d.bond_stiffness[k] : d.stiffness;
      const double g = c * Law::force(sr.stretch, yield, *plastic) * sr.direction_scale;
      b0 += g * dy0;
      b1 += g * dy1;
      b2 += g * dy2;
    }
    b[3 * i] = b0;
    b[3 * i + 1] = b1;
    b[3 * i + 2] = b2;
    if constexpr (Damage) {
      const std::size_t family = end - begin;
      d.damage[i] = family > 0 ? static_cast<double>(broken_count) / static_cast<double>(family)
                               : 0.0; // eq. 13
    }
  }
}

/// One run-time dispatch per run: an object that applies the matching kernel instantiation.
class ForceEvaluator {
public:
  virtual ~ForceEvaluator() = default;
  /// Internal force density b (3N) at positions y (3N); updates bond history.
  virtual void compute(const double* y, double* b) = 0;
  /// Stored elastic energy Σ_i V_i · ½ Σ_j w_ij V_j [J] at positions y; history is not changed.
  /// (For plastic bonds: the energy of the elastic part, measured from the plastic length.)
  virtual double strain_energy(const double* y) const = 0;
  /// The instantiation in use, e.g. "stretch=fast law=elastic damage=off field=uniform".
  virtual std::string description() const = 0;
};

/// Which implementation of the bond loop runs. `simd` (kernel/simd_bond_loop.hpp) is the default;
/// `scalar` is the template above, kept as the reference the SIMD kernel is tested against.
enum class KernelPath { simd, scalar };

template <>
struct EnumName<KernelPath> {
  static constexpr NameTable<KernelPath, 2> table{{
      {"simd", KernelPath::simd, "the vectorised bond loop (kernel/simd_bond_loop.hpp)"},
      {"scalar", KernelPath::scalar, "the scalar template, the reference of the SIMD loop"},
  }};
};

/// The kernel of the virtual-fibre model (src/kernel/fibre_kernel.cpp: two passes, the mean
/// strain of eq. 73 then the arm tensions of eqs. 70 and 77). Needs model.fibre_arms, which
/// build_model fills when model.effects.bond_model is virtual_fibres; damage needs plasticity
/// (std::logic_error). Elastic arms take `path`; plastic arms run the scalar loops.
/// make_force_evaluator hands such models to it.
std::unique_ptr<ForceEvaluator> make_fibre_evaluator(Model& model,
                                                     KernelPath path = KernelPath::simd);

/// Pick the kernel for `model.effects`. The model must outlive the evaluator.
std::unique_ptr<ForceEvaluator> make_force_evaluator(Model& model,
                                                     KernelPath path = KernelPath::simd);

} // namespace pd
