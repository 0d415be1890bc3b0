// Cost of each effect in the bond loop, and proof that dispatch is free.
//
// All benchmarks use Miranda's Model A lattice (node-based 83 × 9 × 7, λ = 0.05 m, δ = 2√3 λ,
// 5229 particles, 319,533 bonds with the inclusive horizon rule) at a small smooth deformation.
//  * HandWrittenElastic: a plain CSR gather loop written out by hand (exact stretch, uniform c).
//  * Dispatched/<effects>: the kernel picked by make_force_evaluator for that effect set.
// Elastic-exact through the dispatcher should match the hand-written loop within noise; the
// other rows show what each effect costs when it is switched on.
#include "libpd/kernel/force_kernel.hpp"
#include "libpd/discretisation/model.hpp"

#include <benchmark/benchmark.h>
#include <cmath>
#include <string>

namespace {

pd::ModelSpec model_a(pd::StretchKind stretch, bool damage, bool plasticity, bool per_bond) {
  pd::ModelSpec s;
  s.lattice.spacing = 0.05;
  s.lattice.horizon_factor = 2.0 * std::sqrt(3.0);
  s.lattice.convention = pd::LatticeConvention::node_based;
  pd::Material m;
  m.name = "concrete";
  m.youngs_modulus = 20e9;
  m.density = 2500;
  m.critical_stretch = 1.0; // never reached: the cost of checking, not of breaking
  m.yield_stretch = 1.0;
  s.materials = {m};
  pd::BodySpec b;
  b.name = "beam";
  b.region.boxes = {pd::Box{{0, 0, 0}, {4.1, 0.4, 0.3}}};
  s.bodies = {b};
  s.effects.stretch = stretch;
  s.effects.damage = damage;
  s.effects.plasticity = plasticity;
  if (per_bond) {
    s.volume_correction = pd::VolumeCorrection::linear;
  }
  return s;
}

std::vector<double> deformed(const pd::Model& m) {
  std::vector<double> y(3 * m.size());
  for (std::size_t i = 0; i < m.size(); ++i) {
    for (int c = 0; c < 3; ++c) {
      const double x = m.particles.position[i][c];
      y[3 * i + c] = x + 1e-4 * std::sin(3.0 * x + c);
    }
  }
  return y;
}

void report(benchmark::State& state, const pd::Model& m) {
  state.counters["bond_updates_per_second"] = benchmark::Counter(
      static_cast<double>(m.family.bond_count()) * static_cast<double>(state.iterations()),
      benchmark::Counter::kIsRate);
}

void HandWrittenElastic(benchmark::State& state) {
  pd::Model m = pd::build_model(model_a(pd::StretchKind::exact, false, false, false));
  const auto y = deformed(m);
  std::vector<double> b(y.size());
  const std::size_t n = m.size();
  const std::size_t* off = m.family.offsets.data();
  const std::uint32_t* nb = m.family.neighbour.data();
  const double* inv = m.family.inverse_length.data();
  const double c = m.field.stiffness;
  for (auto _ : state) {
#pragma omp parallel for schedule(static)
    for (std::ptrdiff_t ii = 0; ii < static_cast<std::ptrdiff_t>(n); ++ii) {
      const auto i = static_cast<std::size_t>(ii);
      double f0 = 0, f1 = 0, f2 = 0;
      for (std::size_t k = off[i]; k < off[i + 1]; ++k) {
        const std::size_t j = nb[k];
        const double d0 = y[3 * j] - y[3 * i], d1 = y[3 * j + 1] - y[3 * i + 1],
                     d2 = y[3 * j + 2] - y[3 * i + 2];
        const double r = std::sqrt(d0 * d0 + d1 * d1 + d2 * d2);
        const double g = c * (r * inv[k] - 1.0) / r;
        f0 += g * d0;
        f1 += g * d1;
        f2 += g * d2;
      }
      b[3 * i] = f0;
      b[3 * i + 1] = f1;
      b[3 * i + 2] = f2;
    }
    benchmark::DoNotOptimize(b.data());
    benchmark::ClobberMemory();
  }
  report(state, m);
}

void Dispatched(benchmark::State& state, pd::StretchKind stretch, bool damage, bool plasticity,
                bool per_bond) {
  pd::Model m = pd::build_model(model_a(stretch, damage, plasticity, per_bond));
  auto forces = pd::make_force_evaluator(m);
  const auto y = deformed(m);
  std::vector<double> b(y.size());
  for (auto _ : state) {
    forces->compute(y.data(), b.data());
    benchmark::DoNotOptimize(b.data());
    benchmark::ClobberMemory();
  }
  state.SetLabel(forces->description());
  report(state, m);
}

using K = pd::StretchKind;
BENCHMARK(HandWrittenElastic)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(Dispatched, elastic_exact, K::exact, false, false, false)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(Dispatched, elastic_modified, K::modified, false, false, false)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(Dispatched, elastic_fast, K::fast, false, false, false)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(Dispatched, damage_exact, K::exact, true, false, false)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(Dispatched, plasticity_exact, K::exact, false, true, false)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(Dispatched, per_bond_field_exact, K::exact, false, false, true)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(Dispatched, all_effects_exact, K::exact, true, true, true)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

} // namespace

BENCHMARK_MAIN();
