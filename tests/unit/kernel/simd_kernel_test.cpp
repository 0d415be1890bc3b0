// The vectorised bond loop (kernel/simd_bond_loop.hpp) against the retained scalar kernel, for
// every effect combination; and its reproducibility: bitwise identical for 1 and 2 threads and for
// every instruction set this CPU runs.
//
// (force_kernel_test.cpp checks the default — SIMD — path against a naive reference from the
// paper.)
#include "effect_combos.hpp"
#include "libpd/discretisation/model.hpp"
#include "libpd/kernel/force_kernel.hpp"
#include "libpd/kernel/simd_bond_loop.hpp"

#include <gtest/gtest.h>
#include <hwy/targets.h>

#ifdef _OPENMP
#include <omp.h>
#endif

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

namespace {

using pd::KernelPath;
using pd::StretchKind;
using pd::Vec3;

constexpr double lambda = 0.1;

using pd::test::all_combos;
using pd::test::Combo;

/// A box of nx × ny × nz cells; the per-bond variant has two materials, the linear partial-volume
/// correction and varying volumes (as in force_kernel_test.cpp). Strengths are chosen so that the
/// deformation below breaks some bonds and yields others.
pd::ModelSpec spec_for(const Combo& c, int nx, int ny, int nz, double m_factor) {
  pd::ModelSpec s;
  s.surface_correction = pd::SurfaceCorrection::none; // the bare model
  s.volume_correction = pd::VolumeCorrection::none;   // linear in the per-bond combos
  s.lattice.spacing = lambda;
  s.lattice.horizon_factor = m_factor;
  s.effects.stretch = c.stretch;
  s.effects.plasticity = c.plasticity;
  s.effects.damage = c.damage;
  pd::Material a;
  a.youngs_modulus = 30e9;
  a.density = 2400;
  a.critical_stretch = 0.004;
  a.yield_stretch = 0.002;
  s.materials.push_back(a);
  const Vec3 hi{nx * lambda, ny * lambda, nz * lambda};
  if (c.per_bond) {
    pd::Material b = a;
    b.stiffness_factor = 2.5;
    b.critical_stretch = 0.006;
    b.yield_stretch = 0.001;
    s.materials.push_back(b);
    pd::BodySpec left, right;
    left.region.boxes = {pd::Box{{0, 0, 0}, {0.5 * hi[0], hi[1], hi[2]}}};
    right.region.boxes = {pd::Box{{0.5 * hi[0], 0, 0}, hi}};
    right.material = 1;
    s.bodies = {left, right};
    s.volume_correction = pd::VolumeCorrection::linear;
    s.lattice.volume_variation = 0.2;
  } else {
    pd::BodySpec body;
    body.region.boxes = {pd::Box{{0, 0, 0}, hi}};
    s.bodies = {body};
  }
  return s;
}

/// A smooth strain of a few 10⁻³ plus a jump across the middle plane (bonds across it break).
std::vector<double> deformed(const pd::Model& model, double amplitude, double jump_at) {
  std::vector<double> y(3 * model.size());
  for (std::size_t i = 0; i < model.size(); ++i) {
    const Vec3& x = model.particles.position[i];
    const double ux = 0.004 * x[0] * (1 + 2 * x[1]) + (x[0] > jump_at ? 0.0009 : 0.0);
    const double uy = -0.002 * x[1] * std::sin(3 * x[0]) + 0.001 * x[2];
    const double uz = 0.003 * x[2] * std::cos(2 * x[1]) - 0.0015 * x[0] * x[0];
    y[3 * i] = x[0] + amplitude * ux;
    y[3 * i + 1] = x[1] + amplitude * uy;
    y[3 * i + 2] = x[2] + amplitude * uz;
  }
  return y;
}

const std::vector<double> history{1.0, 0.3, -0.8, 1.2};

bool bitwise_equal(const std::vector<double>& a, const std::vector<double>& b) {
  // memcmp of two empty vectors would pass it null pointers (undefined behaviour, UBSan).
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0);
}

/// Forces after each step of `history` and the final bond state, on a fresh model.
struct Trace {
  std::vector<double> forces;
  pd::BondState state;
  std::string description;
};

Trace run(const pd::ModelSpec& spec, KernelPath path, double jump_at) {
  pd::Model model = pd::build_model(spec);
  auto eval = pd::make_force_evaluator(model, path);
  Trace t;
  t.description = eval->description();
  std::vector<double> b(3 * model.size());
  for (double amplitude : history) {
    const auto y = deformed(model, amplitude, jump_at);
    eval->compute(y.data(), b.data());
    t.forces.insert(t.forces.end(), b.begin(), b.end());
  }
  t.state = model.state;
  return t;
}

TEST(SimdKernel, MatchesTheScalarKernelForEveryCombination) {
  // 7 × 6 × 5 cells with δ = 3.015 λ: rows of 30–120 bonds, so full blocks and every tail length.
  double worst_relative = 0, worst_scaled = 0;
  bool saw_breaking = false, saw_yielding = false;
  for (const Combo& combo : all_combos()) {
    SCOPED_TRACE(combo.label());
    const pd::ModelSpec spec = spec_for(combo, 7, 6, 5, 3.015);
    const Trace scalar = run(spec, KernelPath::scalar, 0.35);
    const Trace simd = run(spec, KernelPath::simd, 0.35);
    EXPECT_NE(scalar.description.find("path=scalar"), std::string::npos);
    EXPECT_NE(simd.description.find("path=simd/"), std::string::npos);
    // History decisions depend on one bond's stretch only, which both paths round alike.
    EXPECT_EQ(simd.state.broken, scalar.state.broken);
    EXPECT_TRUE(bitwise_equal(simd.state.plastic_stretch, scalar.state.plastic_stretch));
    EXPECT_TRUE(bitwise_equal(simd.state.damage, scalar.state.damage));
    if (combo.damage) {
      saw_breaking |= std::count(scalar.state.broken.begin(), scalar.state.broken.end(), 1) > 0;
    }
    if (combo.plasticity) {
      saw_yielding |=
          std::any_of(scalar.state.plastic_stretch.begin(), scalar.state.plastic_stretch.end(),
                      [](double p) { return p != 0.0; });
    }
    // The forces differ only by the order of each particle's sum. Bound: n ε Σ|terms| with
    // n ≤ 120 bonds, |term| = c·|f|·|Δy|/r ≤ c·|s|(1 + s), |s| ≤ 1e-2 here: < 3e-16·Σc.
    pd::Model model = pd::build_model(spec);
    const std::size_t n = model.size();
    ASSERT_EQ(simd.forces.size(), history.size() * 3 * n);
    for (std::size_t step = 0; step < history.size(); ++step) {
      for (std::size_t i = 0; i < n; ++i) {
        double scale = 0; // Σ c V over the row: the force density of a unit stretch
        for (std::size_t k = model.family.offsets[i]; k < model.family.offsets[i + 1]; ++k) {
          scale += pd::bond_stiffness(model, k);
        }
        const std::size_t at = 3 * (step * n + i);
        const double norm =
            std::hypot(scalar.forces[at], scalar.forces[at + 1], scalar.forces[at + 2]);
        for (std::size_t c = 0; c < 3; ++c) {
          const double diff = std::abs(simd.forces[at + c] - scalar.forces[at + c]);
          ASSERT_LE(diff, 1e-15 * scale) << "step " << step << " particle " << i;
          worst_scaled = std::max(worst_scaled, diff / scale);
          if (norm > 1e-6 * scale) { // relative to |b_i| where b_i is not a cancellation residue
            worst_relative = std::max(worst_relative, diff / norm);
          }
        }
      }
    }
  }
  EXPECT_TRUE(saw_breaking);
  EXPECT_TRUE(saw_yielding);
  std::printf("SIMD (%s) vs scalar: max |Δb|/|b| = %.3g, max |Δb|/Σc = %.3g\n",
              pd::kernel::simd_target_name().c_str(), worst_relative, worst_scaled);
  RecordProperty("max_relative_force_difference", std::to_string(worst_relative));
}

TEST(SimdKernel, BitwiseIdenticalWithOneAndTwoThreadsWithDamage) {
#ifndef _OPENMP
  GTEST_SKIP() << "built without OpenMP";
#else
  const int saved = omp_get_max_threads();
  for (const Combo& combo : {Combo{StretchKind::exact, false, true, false},
                             Combo{StretchKind::modified, true, true, true}}) {
    SCOPED_TRACE(combo.label());
    // 18 × 16 × 15 cells: 5,168 particles (> 4,096), above the parallel threshold in bonds.
    const pd::ModelSpec spec = spec_for(combo, 18, 16, 15, 3.015);
    std::vector<Trace> traces;
    for (int threads : {1, 2}) {
      omp_set_num_threads(threads);
      traces.push_back(run(spec, KernelPath::simd, 0.9));
    }
    omp_set_num_threads(saved);
    pd::Model model = pd::build_model(spec);
    ASSERT_GT(model.size(), 4096u);
    ASSERT_GE(model.family.directed_bond_count(), pd::kernel::simd_parallel_min_bonds)
        << "the model must be large enough for the kernel to use the second thread";
    ASSERT_GT(std::count(traces[0].state.broken.begin(), traces[0].state.broken.end(), 1), 0)
        << "no bond broke";
    EXPECT_TRUE(bitwise_equal(traces[0].forces, traces[1].forces));
    EXPECT_EQ(traces[0].state.broken, traces[1].state.broken);
    EXPECT_TRUE(bitwise_equal(traces[0].state.damage, traces[1].state.damage));
    EXPECT_TRUE(bitwise_equal(traces[0].state.plastic_stretch, traces[1].state.plastic_stretch));
  }
#endif
}

TEST(SimdKernel, BitwiseIdenticalOnEveryInstructionSet) {
  // Each target Highway compiled that this CPU supports (e.g. AVX3, AVX2, SSE4, EMU128).
  std::vector<std::int64_t> targets;
  for (std::int64_t bits = hwy::SupportedTargets() & HWY_TARGETS; bits != 0; bits &= bits - 1) {
    targets.push_back(bits & -bits);
  }
  ASSERT_FALSE(targets.empty());
  for (const Combo& combo : {Combo{StretchKind::exact, false, true, false},
                             Combo{StretchKind::fast, true, false, true}}) {
    SCOPED_TRACE(combo.label());
    const pd::ModelSpec spec = spec_for(combo, 7, 6, 5, 3.015);
    std::vector<Trace> traces;
    for (std::int64_t target : targets) {
      hwy::SetSupportedTargetsForTest(target);
      traces.push_back(run(spec, KernelPath::simd, 0.35));
      EXPECT_NE(traces.back().description.find(hwy::TargetName(target)), std::string::npos)
          << traces.back().description;
    }
    hwy::SetSupportedTargetsForTest(0);
    for (std::size_t t = 1; t < traces.size(); ++t) {
      SCOPED_TRACE(hwy::TargetName(targets[t]));
      EXPECT_TRUE(bitwise_equal(traces[t].forces, traces[0].forces));
      EXPECT_EQ(traces[t].state.broken, traces[0].state.broken);
      EXPECT_TRUE(bitwise_equal(traces[t].state.plastic_stretch, traces[0].state.plastic_stretch));
    }
  }
  std::string names;
  for (std::int64_t target : targets) {
    names += std::string(names.empty() ? "" : ", ") + hwy::TargetName(target);
  }
  std::printf("instruction sets compared: %s; dispatcher's choice: %s\n", names.c_str(),
              pd::kernel::simd_target_name().c_str());
}

} // namespace
