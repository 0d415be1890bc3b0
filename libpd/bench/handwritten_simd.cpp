// A hand-written vectorised elastic bond loop (exact stretch, uniform c), for kernel_bench.cpp to
// show that the dispatched SIMD kernel costs nothing for its policies: the same loading of
// neighbour positions and 8-lane sums as kernel/simd_bond_loop.cpp, without the effect machinery
// (no tail block copy: the last < 8 bonds of a row run as scalar code).
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "handwritten_simd.cpp"
#include "handwritten_simd.hpp"

#include <cmath>
#include <hwy/foreach_target.h> // IWYU pragma: keep
#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace pd_bench::HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

void HandWrittenRows(const HandWrittenData& h, const double* y, double* b, std::size_t first,
                     std::size_t last) {
  using D = hn::CappedTag<double, 8>;
  const D d;
  constexpr std::size_t kN = hn::MaxLanes(D());
  constexpr std::size_t kU = 8 / kN;
  const auto one = hn::Set(d, 1.0), c = hn::Set(d, h.stiffness);
  for (std::size_t i = first; i < last; ++i) {
    const auto yi0 = hn::Set(d, y[3 * i]), yi1 = hn::Set(d, y[3 * i + 1]),
               yi2 = hn::Set(d, y[3 * i + 2]);
    hn::Vec<D> a0[kU], a1[kU], a2[kU];
    for (std::size_t u = 0; u < kU; ++u) {
      a0[u] = a1[u] = a2[u] = hn::Zero(d);
    }
    std::size_t k = h.offsets[i];
    const std::size_t end = h.offsets[i + 1];
    for (; k + 8 <= end; k += 8) {
      for (std::size_t u = 0; u < kU; ++u) {
        alignas(64) double t0[kN], t1[kN], t2[kN];
        for (std::size_t l = 0; l < kN; ++l) {
          const double* yj = y + 3 * static_cast<std::size_t>(h.neighbour[k + u * kN + l]);
          t0[l] = yj[0];
          t1[l] = yj[1];
          t2[l] = yj[2];
        }
        const auto d0 = hn::Sub(hn::Load(d, t0), yi0), d1 = hn::Sub(hn::Load(d, t1), yi1),
                   d2 = hn::Sub(hn::Load(d, t2), yi2);
        const auto r =
            hn::Sqrt(hn::Add(hn::Add(hn::Mul(d0, d0), hn::Mul(d1, d1)), hn::Mul(d2, d2)));
        const auto s = hn::Sub(hn::Mul(r, hn::LoadU(d, h.inverse_length + k + u * kN)), one);
        const auto g = hn::Div(hn::Mul(c, s), r);
        a0[u] = hn::Add(a0[u], hn::Mul(g, d0));
        a1[u] = hn::Add(a1[u], hn::Mul(g, d1));
        a2[u] = hn::Add(a2[u], hn::Mul(g, d2));
      }
    }
    double f[3] = {0, 0, 0};
    for (std::size_t u = 0; u < kU; ++u) {
      f[0] += hn::GetLane(hn::SumOfLanes(d, a0[u]));
      f[1] += hn::GetLane(hn::SumOfLanes(d, a1[u]));
      f[2] += hn::GetLane(hn::SumOfLanes(d, a2[u]));
    }
    for (; k < end; ++k) {
      const std::size_t j = h.neighbour[k];
      const double d0 = y[3 * j] - y[3 * i], d1 = y[3 * j + 1] - y[3 * i + 1],
                   d2 = y[3 * j + 2] - y[3 * i + 2];
      const double r = std::sqrt(d0 * d0 + d1 * d1 + d2 * d2);
      const double g = h.stiffness * (r * h.inverse_length[k] - 1.0) / r;
      f[0] += g * d0;
      f[1] += g * d1;
      f[2] += g * d2;
    }
    b[3 * i] = f[0];
    b[3 * i + 1] = f[1];
    b[3 * i + 2] = f[2];
  }
}

} // namespace pd_bench::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace pd_bench {
HWY_EXPORT(HandWrittenRows);
void hand_written_rows(const HandWrittenData& h, const double* y, double* b, std::size_t first,
                       std::size_t last) {
  HWY_DYNAMIC_DISPATCH(HandWrittenRows)(h, y, b, first, last);
}
} // namespace pd_bench
#endif
