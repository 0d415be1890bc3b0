// The force kernel of the virtual-fibre model (physics/fibres.hpp, discretisation/fibre_arms.hpp):
// two passes over the CSR rows per evaluation,
//   1. each particle's mean strain ε̄_i = (1/N) Σ_j A_k |ξ_k| ε_k                  (eq. 73)
//   2. the force density b_i = Σ_j (A_k S_i + B_k S_j) (y_j − y_i)/|y_j − y_i|,
//      S_p = G(N+2) ε_k + (NK − G(N+2)) ε̄_p                    (eqs. 36, 64, 70, 77, 110)
// with the arm's engineering strain ε_k = |y_j − y_i|/|ξ_k| − 1.
//
// With `plasticity` the arms are elastic–perfectly plastic (eq. 111): the shear part acts on
// ε_k − ε^p_k, and ε^p_k follows the arm's strain wherever |ε_k − ε^p_k| would exceed the yield
// strain (the material's yield_stretch); ε̄ stays the mean of the total strains (eq. 110), so the
// plastic volumetric strain is zero. In a quasi-static increment (BondState::
// plastic_stretch_at_increment_start set) ε^p_k is recomputed at every evaluation from its value
// at the increment's start, so that it is a function of the current strain only: ADR's fictitious
// path to equilibrium leaves no plastic strain of its own (time/quasi_static.hpp). With `damage` an
// arm fails for good once its plastic elongation ε^p_k |ξ_k| exceeds the material's
// elongation_limit δ_e (eq. 118; stored per arm as the plastic strain δ_e/|ξ_k|); failed arms carry
// nothing and leave the mean strain, which is then the weighted mean over the intact arms. The
// damage index is the failed fraction, 1 − φ of eq. 119. `make_force_evaluator` hands a model whose
// effect set selects the fibre model to this kernel; the bond-based kernels are not touched, so
// runs of the default model are the same instructions as before.
//
// Threads split the particle loops statically; each particle's sum runs in CSR order whatever the
// thread count, so forces are bitwise identical for any number of threads. Elastic arms run on the
// vectorised passes of simd_fibre_loop.cpp by default (KernelPath::simd); the scalar loops below
// stay their reference and serve plasticity and damage.
#include "libpd/core/exact_sum.hpp"
#include "libpd/kernel/force_kernel.hpp"
#include "libpd/kernel/simd_bond_loop.hpp"
#include "libpd/kernel/simd_fibre_loop.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <vector>

namespace pd {

namespace {

template <bool Plastic, bool Damage>
class FibreEvaluator final : public ForceEvaluator {
public:
  /// `simd`: run the vectorised passes (elastic arms only; the caller checks).
  FibreEvaluator(Model& model, bool simd) : model_(model), simd_(simd) {
    const FibreArms& a = model.fibre_arms;
    const BondFamily& f = model.family;
    // (1/N) A_k |ξ_k|: the weight of arm k in its particle's mean strain.
    mean_weight_.resize(f.directed_bond_count());
    for (std::size_t k = 0; k < mean_weight_.size(); ++k) {
      mean_weight_[k] = a.own[k] / (f.inverse_length[k] * a.dim);
    }
    mean_strain_.assign(model.size(), 0.0);
    if (simd_) {
      mean_term_.assign(model.size(), 0.0);
      record_.assign(4 * model.size(), 0.0);
      state_.assign(4 * model.size(), 0.0);
      pack_rows_ = kernel::simd_fibre_pack_rows();
      mean_rows_ = kernel::simd_fibre_mean_rows();
      // Compared bit for bit: the broadcast value must be each particle's own.
      const bool uniform =
          !a.shear.empty() && std::all_of(a.shear.begin(), a.shear.end(), [&](double g) {
            return std::memcmp(&g, a.shear.data(), sizeof g) == 0;
          });
      force_rows_ = kernel::simd_fibre_force_rows(uniform);
      path_ = "simd/" + kernel::simd_target_name();
    }
  }

  void compute(const double* y, double* b) override {
    if (simd_) {
      const FibreArms& a = model_.fibre_arms;
      const BondFamily& f = model_.family;
      kernel::FibreData d;
      d.offsets = f.offsets.data();
      d.neighbour = f.neighbour.data();
      d.inverse_length = f.inverse_length.data();
      d.mean_weight = mean_weight_.data();
      d.own = a.own.data();
      d.other = a.other.data();
      d.shear = a.shear.data();
      d.volumetric = a.volumetric.data();
      d.record = record_.data();
      d.state = state_.data();
      d.mean_term = mean_term_.data();
      const auto rows = [&](kernel::FibreRows pass) {
        return [&, pass](std::size_t first, std::size_t last) { pass(d, y, b, first, last); };
      };
      kernel::for_row_phases(d.offsets, model_.size(), rows(pack_rows_), rows(mean_rows_),
                             rows(force_rows_));
    } else {
      const auto& start = model_.state.plastic_stretch_at_increment_start;
      plastic_start_ = start.size() == model_.family.directed_bond_count() ? start.data() : nullptr;
      mean_strains(y);
      const auto n = static_cast<std::ptrdiff_t>(model_.size());
#pragma omp parallel for schedule(static) if (model_.size() >= parallel_min_particles)
      for (std::ptrdiff_t ii = 0; ii < n; ++ii) {
        row(y, b, static_cast<std::size_t>(ii));
      }
    }
    // A split run's rows kept for their means (ownership.hpp): pass 2 ran on them too, because it
    // is where their arms yield and fail, but their force is the owner's to compute.
    const auto& mean_only = model_.ownership.row_for_mean_only;
    for (std::size_t i = 0; i < mean_only.size(); ++i) {
      if (mean_only[i] != 0) {
        b[3 * i] = b[3 * i + 1] = b[3 * i + 2] = 0.0;
      }
    }
  }

  double strain_energy(const double* y) const override {
    // E = Σ_i V_i [½ G(N+2) Σ_j A_k |ξ| (ε − ε^p)² + ½ (NK − G(N+2)) N ε̄_i²], in particle order.
    const FibreArms& a = model_.fibre_arms;
    const BondFamily& f = model_.family;
    const Ownership& own = model_.ownership;
    ExactSum total; // over the owned particles: the same energy on any number of ranks
    for (std::size_t i = 0; i < model_.size(); ++i) {
      if (!own.owns(i)) {
        continue;
      }
      double shear_sum = 0, mean = 0, weight = 0;
      for (std::size_t k = f.offsets[i]; k < f.offsets[i + 1]; ++k) {
        if (Damage && model_.state.broken[k]) {
          continue;
        }
        const double strain = arm_strain(y, i, k);
        const double elastic = Plastic ? strain - model_.state.plastic_stretch[k] : strain;
        shear_sum += a.own[k] / f.inverse_length[k] * elastic * elastic;
        mean += mean_weight_[k] * strain;
        weight += mean_weight_[k];
      }
      if (Damage) {
        mean = weight > 0 ? mean / weight : 0.0;
      }
      total.add(0.5 * model_.particles.volume[i] *
                (a.shear[i] * shear_sum + a.volumetric[i] * a.dim * mean * mean));
    }
    return own.communicator().sum(total);
  }

  std::string description() const override {
    return std::string("bond-model=virtual-fibres strain=exact plasticity=") +
           (Plastic ? "on" : "off") + " damage=" + (Damage ? "on" : "off") + " path=" + path_;
  }

private:
  /// Pass 2 for particle i: the arms' tensions (eq. 70) and, where they apply, eqs. 111, 118–119.
  void row(const double* y, double* b, std::size_t i) {
    const FibreArms& a = model_.fibre_arms;
    const BondFamily& f = model_.family;
    const double* eb = mean_strain_.data();
    const double yi0 = y[3 * i], yi1 = y[3 * i + 1], yi2 = y[3 * i + 2];
    const double shear_i = a.shear[i], mean_i = a.volumetric[i] * eb[i];
    double b0 = 0, b1 = 0, b2 = 0;
    std::size_t failed = 0;
    for (std::size_t k = f.offsets[i]; k < f.offsets[i + 1]; ++k) {
      if constexpr (Damage) {
        if (model_.state.broken[k]) {
          ++failed;
          continue;
        }
      }
      const std::size_t j = f.neighbour[k];
      const double dy0 = y[3 * j] - yi0, dy1 = y[3 * j + 1] - yi1, dy2 = y[3 * j + 2] - yi2;
      const double r = std::sqrt(dy0 * dy0 + dy1 * dy1 + dy2 * dy2);
      const double strain = r * f.inverse_length[k] - 1.0;
      double elastic = strain;
      if constexpr (Plastic) {
        // Eq. 111. Both directions of an arm see the same r², so their histories stay equal.
        double& plastic = model_.state.plastic_stretch[k];
        if (plastic_start_ != nullptr) {
          plastic = plastic_start_[k];
        }
        const double yield = model_.field.bond_yield_stretch[k];
        if (strain - plastic > yield) {
          plastic = strain - yield;
        } else if (strain - plastic < -yield) {
          plastic = strain + yield;
        }
        elastic = strain - plastic;
        if constexpr (Damage) {
          if (plastic > model_.field.bond_critical_stretch[k]) { // eq. 118: ε^p |ξ| > δ_e
            model_.state.broken[k] = 1;
            ++failed;
            continue;
          }
        }
      }
      // Eq. 70: each end's force flux density (eq. 77, eq. 110) weighted by that end's kernel.
      const double s_i = shear_i * elastic + mean_i;
      const double s_j = a.shear[j] * elastic + a.volumetric[j] * eb[j];
      const double g = (a.own[k] * s_i + a.other[k] * s_j) / r;
      b0 += g * dy0;
      b1 += g * dy1;
      b2 += g * dy2;
    }
    b[3 * i] = b0;
    b[3 * i + 1] = b1;
    b[3 * i + 2] = b2;
    if constexpr (Damage) {
      const std::size_t family = f.offsets[i + 1] - f.offsets[i];
      model_.state.damage[i] =
          family > 0 ? static_cast<double>(failed) / static_cast<double>(family) : 0.0;
    } else {
      (void)failed;
    }
  }

  double arm_strain(const double* y, std::size_t i, std::size_t k) const {
    const std::size_t j = model_.family.neighbour[k];
    double r2 = 0;
    for (std::size_t c = 0; c < 3; ++c) {
      const double d = y[3 * j + c] - y[3 * i + c];
      r2 += d * d;
    }
    return std::sqrt(r2) * model_.family.inverse_length[k] - 1.0;
  }

  /// Pass 1: ε̄_i of eq. 73 from the arms' total strains (over the intact arms under damage).
  void mean_strains(const double* y) {
    const BondFamily& f = model_.family;
    const auto n = static_cast<std::ptrdiff_t>(model_.size());
#pragma omp parallel for schedule(static) if (model_.size() >= parallel_min_particles)
    for (std::ptrdiff_t ii = 0; ii < n; ++ii) {
      const auto i = static_cast<std::size_t>(ii);
      const double yi0 = y[3 * i], yi1 = y[3 * i + 1], yi2 = y[3 * i + 2];
      double sum = 0, weight = 0;
      for (std::size_t k = f.offsets[i]; k < f.offsets[i + 1]; ++k) {
        if (Damage && model_.state.broken[k]) {
          continue;
        }
        const std::size_t j = f.neighbour[k];
        const double dy0 = y[3 * j] - yi0, dy1 = y[3 * j + 1] - yi1, dy2 = y[3 * j + 2] - yi2;
        const double r = std::sqrt(dy0 * dy0 + dy1 * dy1 + dy2 * dy2);
        sum += mean_weight_[k] * (r * f.inverse_length[k] - 1.0);
        weight += mean_weight_[k];
      }
      if constexpr (Damage) {
        sum = weight > 0 ? sum / weight : 0.0;
      } else {
        (void)weight;
      }
      mean_strain_[i] = sum;
    }
  }

  Model& model_;
  bool simd_;
  std::vector<double> mean_weight_; ///< A_k |ξ_k| / N per directed bond
  std::vector<double> mean_strain_; ///< ε̄ per particle, pass 1's result
  std::vector<double> mean_term_;   ///< (NK − G(N+2)) ε̄ per particle, the SIMD pass 1's
  std::vector<double> record_;      ///< (y, 0) per particle for the SIMD pass 1
  std::vector<double> state_;       ///< (y, mean term) per particle for the SIMD pass 2
  std::vector<double> length_;      ///< |y_j − y_i| per directed bond, the SIMD pass 1's
  kernel::FibreRows pack_rows_ = nullptr;
  kernel::FibreRows mean_rows_ = nullptr; ///< the SIMD passes, when simd_
  kernel::FibreRows force_rows_ = nullptr;
  std::string path_ = "scalar";
  const double* plastic_start_ = nullptr; ///< ε^p at the increment's start, in quasi-static runs
};

template <bool Plastic>
std::unique_ptr<ForceEvaluator> with_damage(Model& m) {
  if (m.effects.damage) {
    return std::make_unique<FibreEvaluator<Plastic, true>>(m, false);
  }
  return std::make_unique<FibreEvaluator<Plastic, false>>(m, false);
}

} // namespace

std::unique_ptr<ForceEvaluator> make_fibre_evaluator(Model& model, KernelPath path) {
  const std::size_t nb = model.family.directed_bond_count();
  if (model.fibre_arms.own.size() != nb) {
    throw std::logic_error("virtual fibres without arm weights: build the model with build_model");
  }
  if (model.effects.damage && !model.effects.plasticity) {
    throw std::logic_error("virtual fibres: arms fail by plastic elongation (eq. 118), so damage "
                           "needs plasticity");
  }
  if (model.effects.plasticity &&
      (model.state.plastic_stretch.size() != nb || model.field.bond_yield_stretch.size() != nb)) {
    throw std::logic_error("plasticity effect without bond state: build the model with "
                           "build_model");
  }
  if (model.effects.damage &&
      (model.state.broken.size() != nb || model.field.bond_critical_stretch.size() != nb)) {
    throw std::logic_error("damage effect without bond state: build the model with build_model");
  }
  if (model.effects.plasticity) {
    return with_damage<true>(model);
  }
  // The SIMD passes gather with 32-bit signed indices.
  const bool simd =
      path == KernelPath::simd &&
      model.size() <= static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max());
  return std::make_unique<FibreEvaluator<false, false>>(model, simd);
}

} // namespace pd
