// The vectorised passes of the virtual-fibre kernel (kernel/simd_fibre_loop.hpp) against the
// retained scalar loops of fibre_kernel.cpp, and their reproducibility: bitwise identical for 1
// and 2 threads and for every instruction set this CPU runs. (fibre_kernel_test.cpp checks the
// default path's physics.)
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
constexpr double lambda = 0.01;

/// A block of n³ cells with two materials, varying volumes and the linear partial-volume
/// correction, so that arm weights differ from arm to arm and particle to particle.
pd::ModelSpec fibre_block(int n) {
  pd::ModelSpec s;
  s.lattice.spacing = lambda;
  s.lattice.horizon_factor = 3.015;
  s.lattice.volume_variation = 0.2;
  s.effects.bond_model = pd::BondModel::virtual_fibres;
  s.surface_correction = pd::SurfaceCorrection::none;
  s.volume_correction = pd::VolumeCorrection::linear;
  pd::Material a;
  a.youngs_modulus = 200e9;
  a.poisson_ratio = 0.3;
  a.density = 7800;
  pd::Material b = a;
  b.youngs_modulus = 70e9;
  b.poisson_ratio = 0.35;
  s.materials = {a, b};
  const double h = n * lambda;
  pd::BodySpec left, right;
  left.region.boxes = {pd::Box{{0, 0, 0}, {0.5 * h, h, h}}};
  right.region.boxes = {pd::Box{{0.5 * h, 0, 0}, {h, h, h}}};
  right.material = 1;
  s.bodies = {left, right};
  return s;
}

/// A smooth, inhomogeneous deformation with strains of a few 10⁻³.
std::vector<double> deformed(const pd::Model& m, double amplitude) {
  std::vector<double> y(3 * m.size());
  for (std::size_t i = 0; i < m.size(); ++i) {
    const auto& x = m.particles.position[i];
    y[3 * i] = x[0] + amplitude * (0.004 * x[0] * (1 + 20 * x[1]) + 0.001 * std::sin(90 * x[2]));
    y[3 * i + 1] = x[1] + amplitude * (-0.002 * x[1] * std::sin(40 * x[0]) + 0.001 * x[2]);
    y[3 * i + 2] = x[2] + amplitude * (0.003 * x[2] * std::cos(30 * x[1]) - 0.15 * x[0] * x[0]);
  }
  return y;
}

const std::vector<double> amplitudes{1.0, -0.6, 2.0};

bool bitwise_equal(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0);
}

struct Trace {
  std::vector<double> forces;
  std::string description;
};

Trace run(const pd::ModelSpec& spec, KernelPath path) {
  pd::Model m = pd::build_model(spec);
  auto eval = pd::make_force_evaluator(m, path);
  Trace t;
  t.description = eval->description();
  std::vector<double> b(3 * m.size());
  for (double amplitude : amplitudes) {
    const auto y = deformed(m, amplitude);
    eval->compute(y.data(), b.data());
    t.forces.insert(t.forces.end(), b.begin(), b.end());
  }
  return t;
}

TEST(SimdFibre, MatchesTheScalarKernel) {
  const pd::ModelSpec spec = fibre_block(6);
  const Trace simd = run(spec, KernelPath::simd);
  const Trace scalar = run(spec, KernelPath::scalar);
  EXPECT_NE(simd.description.find("path=simd/"), std::string::npos) << simd.description;
  EXPECT_NE(scalar.description.find("path=scalar"), std::string::npos) << scalar.description;
  const pd::Model m = pd::build_model(spec);
  const pd::FibreArms& a = m.fibre_arms;
  const double moduli = std::max(
      *std::max_element(a.shear.begin(), a.shear.end()),
      std::abs(*std::max_element(a.volumetric.begin(), a.volumetric.end(),
                                 [](double p, double q) { return std::abs(p) < std::abs(q); })));
  const std::size_t n = m.size();
  ASSERT_EQ(simd.forces.size(), amplitudes.size() * 3 * n);
  double worst = 0;
  bool differ = false;
  for (std::size_t step = 0; step < amplitudes.size(); ++step) {
    for (std::size_t i = 0; i < n; ++i) {
      // The passes differ from the scalar loops only in the order of each particle's sums: a
      // few ulps of Σ|terms|, |term| ≤ (A + B)·moduli·|ε| with |ε| < 2e-2 here.
      double weights = 0;
      for (std::size_t k = m.family.offsets[i]; k < m.family.offsets[i + 1]; ++k) {
        weights += std::abs(a.own[k]) + std::abs(a.other[k]);
      }
      const double bound = 1e-15 * weights * moduli;
      for (std::size_t c = 0; c < 3; ++c) {
        const std::size_t at = 3 * (step * n + i) + c;
        const double diff = std::abs(simd.forces[at] - scalar.forces[at]);
        ASSERT_LE(diff, bound) << "step " << step << " particle " << i;
        worst = std::max(worst, diff / (weights * moduli));
        differ |= diff != 0;
      }
    }
  }
  std::printf("SIMD (%s) vs scalar fibre kernel: max |Δb|/(Σ(A+B)·modulus) = %.3g\n",
              pd::kernel::simd_target_name().c_str(), worst);
  EXPECT_TRUE(differ) << "the two paths should differ in summation order somewhere";
}

TEST(SimdFibre, PlasticArmsRunTheScalarKernel) {
  pd::ModelSpec spec = fibre_block(3);
  spec.effects.plasticity = true;
  for (auto& mat : spec.materials) {
    mat.yield_stretch = 1e-3;
  }
  pd::Model m = pd::build_model(spec);
  EXPECT_NE(pd::make_force_evaluator(m)->description().find("path=scalar"), std::string::npos);
}

TEST(SimdFibre, BitwiseIdenticalWithOneAndTwoThreads) {
#ifndef _OPENMP
  GTEST_SKIP() << "built without OpenMP";
#else
  const pd::ModelSpec spec = fibre_block(8);
  {
    const pd::Model m = pd::build_model(spec);
    ASSERT_GE(m.family.directed_bond_count(), pd::kernel::simd_parallel_min_bonds)
        << "the model must be large enough for the kernel to use the second thread";
  }
  const int saved = omp_get_max_threads();
  std::vector<Trace> traces;
  for (int threads : {1, 2}) {
    omp_set_num_threads(threads);
    traces.push_back(run(spec, KernelPath::simd));
  }
  omp_set_num_threads(saved);
  EXPECT_TRUE(bitwise_equal(traces[0].forces, traces[1].forces));
#endif
}

TEST(SimdFibre, BitwiseIdenticalOnEveryInstructionSet) {
  std::vector<std::int64_t> targets;
  for (std::int64_t bits = hwy::SupportedTargets() & HWY_TARGETS; bits != 0; bits &= bits - 1) {
    targets.push_back(bits & -bits);
  }
  ASSERT_FALSE(targets.empty());
  const pd::ModelSpec spec = fibre_block(5);
  std::vector<Trace> traces;
  for (std::int64_t target : targets) {
    hwy::SetSupportedTargetsForTest(target);
    traces.push_back(run(spec, KernelPath::simd));
    EXPECT_NE(traces.back().description.find(hwy::TargetName(target)), std::string::npos)
        << traces.back().description;
  }
  hwy::SetSupportedTargetsForTest(0);
  for (std::size_t t = 1; t < traces.size(); ++t) {
    SCOPED_TRACE(hwy::TargetName(targets[t]));
    EXPECT_TRUE(bitwise_equal(traces[t].forces, traces[0].forces));
  }
  std::printf("instruction sets compared: %zu\n", targets.size());
}

/// One material: every particle has the same shear constant, and pass 2 takes it as a constant
/// instead of gathering it (simd_fibre_loop.hpp) — the same forces on every instruction set and
/// thread count, within the scalar kernel's summation-order bound.
TEST(SimdFibre, OneMaterialIsBitwiseIdenticalOnEveryInstructionSetAndThreadCount) {
  pd::ModelSpec spec = fibre_block(8);
  spec.materials.resize(1);
  for (auto& body : spec.bodies) {
    body.material = 0;
  }
  std::vector<std::int64_t> targets;
  for (std::int64_t bits = hwy::SupportedTargets() & HWY_TARGETS; bits != 0; bits &= bits - 1) {
    targets.push_back(bits & -bits);
  }
  ASSERT_FALSE(targets.empty());
  std::vector<Trace> traces;
  for (std::int64_t target : targets) {
    hwy::SetSupportedTargetsForTest(target);
    traces.push_back(run(spec, KernelPath::simd));
  }
  hwy::SetSupportedTargetsForTest(0);
  for (std::size_t t = 1; t < traces.size(); ++t) {
    SCOPED_TRACE(hwy::TargetName(targets[t]));
    EXPECT_TRUE(bitwise_equal(traces[t].forces, traces[0].forces));
  }
#ifdef _OPENMP
  const int saved = omp_get_max_threads();
  omp_set_num_threads(saved == 1 ? 2 : 1);
  const Trace other_threads = run(spec, KernelPath::simd);
  omp_set_num_threads(saved);
  EXPECT_TRUE(bitwise_equal(other_threads.forces, traces.back().forces));
#endif
  const Trace scalar = run(spec, KernelPath::scalar);
  double worst = 0, largest = 0;
  for (std::size_t at = 0; at < scalar.forces.size(); ++at) {
    worst = std::max(worst, std::abs(scalar.forces[at] - traces[0].forces[at]));
    largest = std::max(largest, std::abs(scalar.forces[at]));
  }
  EXPECT_LE(worst, 1e-12 * largest) << "the SIMD and scalar kernels differ beyond summation order";
}

} // namespace
