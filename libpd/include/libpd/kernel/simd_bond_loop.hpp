// The vectorised bond loop: the same physics as `accumulate_bond_forces` (Miranda eq. 27 with the
// stretch measures of eqs. 5–6 and 17, the laws of eqs. 7 and 14–16, damage eqs. 9–13), written
// once over Google Highway and compiled for every x86 instruction set Highway knows (SSE4, AVX2,
// AVX-512, …). The best one the running CPU supports is picked at run time (HWY_DYNAMIC_DISPATCH),
// so the shipped binary stays baseline x86-64.
//
// Lanes run over the bonds of one particle's CSR row: neighbour positions are gathered, a masked
// tail covers the end of the row. Each particle's force is summed in 8 "virtual lanes" (bond k of a
// row goes to lane (k − row start) mod 8, whatever the hardware vector width), and the 8 lanes are
// added in lane order 0…7. Each bond's force is rounded exactly as in the scalar kernel (no FMA
// contraction in this file), so the result depends on neither the thread count nor the instruction
// set; it differs from the scalar kernel only by the order of the per-particle sum.
#pragma once

#include "libpd/kernel/kernel_data.hpp"
#include "libpd/physics/stretch.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace pd::kernel {

/// Bonds summed per virtual lane group (see above). A power of two ≥ every vector width used.
inline constexpr std::size_t virtual_lanes = 8;

/// Computes b (and damage/plastic history) for particles [first, last): one effect combination,
/// one instruction set. Reads and writes only rows of those particles, so threads may call it on
/// disjoint ranges.
using RowKernel = void (*)(const KernelData& d, const double* y, double* b, std::size_t first,
                           std::size_t last);

/// The row kernel for one effect combination, for the best instruction set of this CPU.
RowKernel simd_row_kernel(StretchKind stretch, bool plasticity, bool damage, bool per_bond_field);

/// Name of the instruction set the dispatcher picks on this CPU, e.g. "AVX3" (= AVX-512), "AVX2".
std::string simd_target_name();

/// Below this many directed bonds the SIMD kernel runs on one thread. On a quiet machine
/// (`pd-kernel-bench --benchmark_filter=Threshold`) a second thread pays from about 20,000
/// directed bonds, nearly doubling the rate at the clamped beam's size; the threshold sits a
/// little above that. Under load the second thread can lose at every size: that is for the
/// thread policy to answer (core/threads.hpp: pd follows the idle processors), not the threshold.
inline constexpr std::size_t simd_parallel_min_bonds = 32768;

/// Calls each of `phases(first, last)` in turn once per thread of one parallel region (one thread
/// below simd_parallel_min_bonds directed bonds), with a barrier between phases, on contiguous
/// particle ranges with equal bond counts (irregular sets balance too). A row kernel's result for
/// a particle does not depend on which thread computes it, so neither does the whole. One region
/// for several phases: on a busy machine each region's start and end costs more than a barrier.
template <class... Phases>
void for_row_phases(const std::size_t* offsets, std::size_t n, Phases&&... phases) {
  const std::size_t bonds = offsets[n];
#pragma omp parallel if (bonds >= simd_parallel_min_bonds)
  {
    std::size_t first = 0, last = n;
#ifdef _OPENMP
    const auto t = static_cast<std::size_t>(omp_get_thread_num());
    const auto threads = static_cast<std::size_t>(omp_get_num_threads());
    const auto split = [&](std::size_t part) {
      if (part >= threads) {
        return n;
      }
      const std::size_t target = bonds / threads * part + bonds % threads * part / threads;
      return static_cast<std::size_t>(std::lower_bound(offsets, offsets + n, target) - offsets);
    };
    first = split(t);
    last = split(t + 1);
#endif
    bool after_first = false;
    const auto phase = [&](auto& rows) {
      if (after_first) {
#pragma omp barrier
      }
      after_first = true;
      rows(first, last);
    };
    (phase(phases), ...);
  }
}

/// for_row_phases with one phase.
template <class Rows>
void for_row_ranges(const std::size_t* offsets, std::size_t n, Rows&& rows) {
  for_row_phases(offsets, n, rows);
}

} // namespace pd::kernel
