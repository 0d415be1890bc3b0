// Cost of each effect in the bond loop, and proof that dispatch is free.
//
// All benchmarks use Miranda's Model A lattice (node-based 83 × 9 × 7, λ = 0.05 m, δ = 2√3 λ,
// 5229 particles, 319,533 bonds with the inclusive horizon rule) at a small smooth deformation.
//  * HandWrittenElastic: a plain scalar CSR gather loop written out by hand (exact, uniform c).
//  * HandWrittenSimd: the same loop vectorised by hand over Highway (handwritten_simd.cpp).
//  * Dispatched/<effects>: the kernel picked by make_force_evaluator for that effect set
//    (SIMD path); Dispatched/scalar_<effects>: the retained scalar kernel. fibres: the
//    virtual-fibre model's kernel on the same lattice (its own family: compare per bond).
//  * Target/<isa>: elastic exact on one instruction set (SSE4, AVX2, AVX3 = AVX-512).
//  * FibreVsBond/<nx>: the virtual-fibre kernel and the bond-based one (elastic, exact) on the
//    same bonds (one fibre model's family: Model A, or its cross-section nx cells long, whose arm
//    arrays stay in cache), alternated within each iteration; the counters are the
//    medians of each one's process CPU time and of their same-iteration ratio bond/fibre, the
//    fibre kernel's per-bond rate relative to the bond-based one's (issue 41 asks ≥ 0.6).
//  * Threshold/<nx>/<threads>: elastic exact on Model A's cross-section, nx cells long, on 1 or 2
//    threads with the parallel threshold bypassed: where the second thread starts to pay.
// Elastic-exact through the dispatcher should match HandWrittenSimd within ±3 %; the other rows
// show what each effect costs when it is switched on. Threads: OMP_NUM_THREADS.
#include "handwritten_simd.hpp"
#include "libpd/discretisation/model.hpp"
#include "libpd/kernel/force_kernel.hpp"
#include "libpd/kernel/simd_bond_loop.hpp"

#include <algorithm>
#include <benchmark/benchmark.h>
#include <cmath>
#include <ctime>
#include <hwy/targets.h>
#include <string>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace {

pd::ModelSpec model_a(pd::StretchKind stretch, bool damage, bool plasticity, bool per_bond,
                      double length = 4.1) {
  pd::ModelSpec s;
  s.surface_correction = pd::SurfaceCorrection::none; // the bare model
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
  b.region.boxes = {pd::Box{{0, 0, 0}, {length, 0.4, 0.3}}};
  s.bodies = {b};
  s.effects.stretch = stretch;
  s.effects.damage = damage;
  s.effects.plasticity = plasticity;
  s.volume_correction = per_bond ? pd::VolumeCorrection::linear : pd::VolumeCorrection::none;
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

/// Particles [first, last) of thread t of `threads`, split by bond count like the SIMD evaluator.
std::pair<std::size_t, std::size_t> my_rows(const pd::Model& m, std::size_t t,
                                            std::size_t threads) {
  const std::size_t n = m.size(), bonds = m.family.offsets[n];
  const auto split = [&](std::size_t part) {
    if (part >= threads) {
      return n;
    }
    const auto* o = m.family.offsets.data();
    return static_cast<std::size_t>(
        std::lower_bound(o, o + n, bonds / threads * part + bonds % threads * part / threads) - o);
  };
  return {split(t), split(t + 1)};
}

void HandWrittenSimd(benchmark::State& state) {
  pd::Model m = pd::build_model(model_a(pd::StretchKind::exact, false, false, false));
  const auto y = deformed(m);
  std::vector<double> b(y.size());
  const pd_bench::HandWrittenData h{m.family.offsets.data(), m.family.neighbour.data(),
                                    m.family.inverse_length.data(), m.field.stiffness};
  for (auto _ : state) {
#pragma omp parallel
    {
      std::size_t t = 0, threads = 1;
#ifdef _OPENMP
      t = static_cast<std::size_t>(omp_get_thread_num());
      threads = static_cast<std::size_t>(omp_get_num_threads());
#endif
      const auto [first, last] = my_rows(m, t, threads);
      pd_bench::hand_written_rows(h, y.data(), b.data(), first, last);
    }
    benchmark::DoNotOptimize(b.data());
    benchmark::ClobberMemory();
  }
  state.SetLabel("simd/" + pd::kernel::simd_target_name());
  report(state, m);
}

/// Elastic exact through the dispatcher on a model nx cells long, on state.range(1) threads,
/// calling the row kernel directly so that the parallel threshold does not decide.
void Threshold(benchmark::State& state) {
  const auto nx = static_cast<double>(state.range(0));
  pd::Model m =
      pd::build_model(model_a(pd::StretchKind::exact, false, false, false, 0.05 * (nx - 1)));
  const auto threads = static_cast<int>(state.range(1));
  const auto rows = pd::kernel::simd_row_kernel(pd::StretchKind::exact, false, false, false);
  const pd::KernelData d = pd::kernel_data(m);
  const auto y = deformed(m);
  std::vector<double> b(y.size());
  for (auto _ : state) {
#pragma omp parallel num_threads(threads)
    {
      std::size_t t = 0, nt = 1;
#ifdef _OPENMP
      t = static_cast<std::size_t>(omp_get_thread_num());
      nt = static_cast<std::size_t>(omp_get_num_threads());
#endif
      const auto [first, last] = my_rows(m, t, nt);
      rows(d, y.data(), b.data(), first, last);
    }
    benchmark::DoNotOptimize(b.data());
    benchmark::ClobberMemory();
  }
  state.SetLabel(std::to_string(m.size()) + " particles, " +
                 std::to_string(m.family.directed_bond_count()) + " directed bonds");
  report(state, m);
}

/// Elastic exact on one instruction set (a bit of hwy's target mask, e.g. HWY_AVX2).
void Target(benchmark::State& state, std::int64_t target) {
  if ((hwy::SupportedTargets() & target) == 0) {
    state.SkipWithError("instruction set not supported by this CPU");
    return;
  }
  hwy::SetSupportedTargetsForTest(target);
  pd::Model m = pd::build_model(model_a(pd::StretchKind::exact, false, false, false));
  auto forces = pd::make_force_evaluator(m);
  hwy::SetSupportedTargetsForTest(0);
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

void Dispatched(benchmark::State& state, pd::StretchKind stretch, bool damage, bool plasticity,
                bool per_bond, pd::KernelPath path = pd::KernelPath::simd,
                pd::BondModel bond_model = pd::BondModel::micro_elastic) {
  pd::ModelSpec spec = model_a(stretch, damage, plasticity, per_bond);
  spec.effects.bond_model = bond_model;
  pd::Model m = pd::build_model(spec);
  auto forces = pd::make_force_evaluator(m, path);
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

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty()      ? 0.0
         : v.size() % 2 ? v[v.size() / 2]
                        : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

/// Both kernels on one fibre model's bond list, alternated so that both see the same load: a
/// ratio taken within one iteration is what a busy, shared machine can still measure.
void FibreVsBond(benchmark::State& state) {
  const auto nx = static_cast<double>(state.range(0));
  pd::ModelSpec spec = model_a(pd::StretchKind::exact, false, false, false, 0.05 * (nx - 1));
  spec.effects.bond_model = pd::BondModel::virtual_fibres;
  pd::Model m = pd::build_model(spec);
  auto fibres = pd::make_force_evaluator(m);
  // The bond-based row kernel over the same CSR rows: the fibre model's family, uniform stiffness.
  const auto rows = pd::kernel::simd_row_kernel(pd::StretchKind::exact, false, false, false);
  pd::KernelData d = pd::kernel_data(m);
  d.stiffness = 1.0;
  const auto y = deformed(m);
  std::vector<double> b(y.size());
  std::vector<double> bond_seconds, fibre_seconds, ratios;
  // Process CPU time, not wall time: on a shared machine a 1 ms evaluation is preempted less
  // often than a 3 ms one, which biases wall-time medians against the slower kernel.
  const auto cpu_now = [] {
    timespec t{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
  };
  for (auto _ : state) {
    double t0 = cpu_now();
    pd::kernel::for_row_ranges(d.offsets, m.size(), [&](std::size_t first, std::size_t last) {
      rows(d, y.data(), b.data(), first, last);
    });
    benchmark::DoNotOptimize(b.data());
    benchmark::ClobberMemory();
    bond_seconds.push_back(cpu_now() - t0);
    t0 = cpu_now();
    fibres->compute(y.data(), b.data());
    benchmark::DoNotOptimize(b.data());
    benchmark::ClobberMemory();
    fibre_seconds.push_back(cpu_now() - t0);
    ratios.push_back(bond_seconds.back() / fibre_seconds.back());
  }
  state.counters["bond_ms"] = 1e3 * median(bond_seconds);
  state.counters["fibre_ms"] = 1e3 * median(fibre_seconds);
  state.counters["fibre_per_bond_rate"] = median(ratios);
  state.SetLabel(fibres->description() + ", " + std::to_string(m.family.directed_bond_count()) +
                 " directed bonds");
}

using K = pd::StretchKind;
BENCHMARK(HandWrittenElastic)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(HandWrittenSimd)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(Dispatched, scalar_elastic_exact, K::exact, false, false, false,
                  pd::KernelPath::scalar)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(Dispatched, scalar_elastic_fast, K::fast, false, false, false,
                  pd::KernelPath::scalar)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(Dispatched, scalar_damage_exact, K::exact, true, false, false,
                  pd::KernelPath::scalar)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(Target, SSE4, HWY_SSE4)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(Target, AVX2, HWY_AVX2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(Target, AVX3, HWY_AVX3)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(FibreVsBond)->Arg(83)->Arg(12)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(Threshold)
    ->ArgsProduct({{4, 8, 12, 16, 24, 32, 48, 64, 83}, {1, 2}})
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime();
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
BENCHMARK_CAPTURE(Dispatched, fibres, K::exact, false, false, false, pd::KernelPath::simd,
                  pd::BondModel::virtual_fibres)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(Dispatched, scalar_fibres, K::exact, false, false, false, pd::KernelPath::scalar,
                  pd::BondModel::virtual_fibres)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

} // namespace

BENCHMARK_MAIN();
