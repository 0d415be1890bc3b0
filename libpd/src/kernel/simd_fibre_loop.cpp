// The virtual-fibre kernel's passes over Google Highway (see kernel/simd_fibre_loop.hpp for the
// contract). foreach_target.h re-includes this file once per instruction set. As in
// simd_bond_loop.cpp, every floating-point operation is an explicit Highway op in the scalar
// kernel's order (compiled with -ffp-contract=off), and each particle's sum uses the fixed
// virtual-lane order: that is what keeps the result the same on every instruction set.

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "kernel/simd_fibre_loop.cpp"
#include "libpd/kernel/simd_fibre_loop.hpp"

#include "libpd/kernel/simd_bond_loop.hpp"

#include <hwy/foreach_target.h> // IWYU pragma: keep
#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace pd::kernel::HWY_NAMESPACE {
namespace fibre {
namespace hn = hwy::HWY_NAMESPACE;

using D = hn::CappedTag<double, virtual_lanes>;
using V = hn::Vec<D>;
constexpr std::size_t kN = hn::MaxLanes(D());
constexpr std::size_t kU = virtual_lanes / kN;
static_assert(kN * kU == virtual_lanes, "vector width must divide the virtual lane count");

/// One block's per-arm arrays: the row itself, or a padded copy for the row's last < 8 arms
/// (lanes past the row end repeat the block's first arm: finite values, masked off).
struct Block {
  const std::int32_t* neighbour;
  const double* inverse_length;
  const double* weight; ///< pass 1: (1/N) A_k |ξ_k|; pass 2: A_k
  const double* other;  ///< pass 2 only
};

struct Tail {
  alignas(64) std::int32_t neighbour[virtual_lanes];
  alignas(64) double inverse_length[virtual_lanes];
  alignas(64) double weight[virtual_lanes];
  alignas(64) double other[virtual_lanes];
  Block fill(const std::int32_t* nb, const FibreData& fd, const double* weight_row, std::size_t k,
             std::size_t n, bool pass2) {
    for (std::size_t l = 0; l < virtual_lanes; ++l) {
      const std::size_t src = k + (l < n ? l : 0);
      neighbour[l] = nb[src];
      inverse_length[l] = fd.inverse_length[src];
      weight[l] = weight_row[src];
      other[l] = pass2 ? fd.other[src] : 0.0;
    }
    return {neighbour, inverse_length, weight, other};
  }
};

/// The records (y_0, y_1, y_2, w) of kN neighbours, one lane each. With 4 or 8 lanes each
/// record is one 32-byte load and the block is transposed in registers (through the stack, the
/// vector loads would wait on the record stores: measured 1.8× slower on Zen 4); narrower
/// targets take scalar loads as the bond-based loop does. Only data moves here, so the lanes hold
/// the same values on every instruction set.
HWY_INLINE void neighbours(D d, const double* record, const std::int32_t* nb, V& yj0, V& yj1,
                           V& yj2, V& w) {
  const auto at = [&](std::size_t l) { return record + 4 * static_cast<std::size_t>(nb[l]); };
#if HWY_TARGET != HWY_SCALAR // which has no block operations
  if constexpr (kN == 4 || kN == 8) {
    // v[m] holds records m (lower half) and m + 4 (upper half, 8 lanes only); InterleaveLower/
    // Upper pair them per 128-bit block, the block selects finish the transpose.
    V v[4];
    for (std::size_t m = 0; m < 4; ++m) {
      if constexpr (kN == 4) {
        v[m] = hn::LoadU(d, at(m));
      } else {
        const hn::Half<D> dh;
        v[m] = hn::Combine(d, hn::LoadU(dh, at(m + 4)), hn::LoadU(dh, at(m)));
      }
    }
    const V even01 = hn::InterleaveLower(d, v[0], v[1]),
            even23 = hn::InterleaveLower(d, v[2], v[3]);
    const V odd01 = hn::InterleaveUpper(d, v[0], v[1]), odd23 = hn::InterleaveUpper(d, v[2], v[3]);
    yj0 = hn::OddEvenBlocks(hn::SwapAdjacentBlocks(even23), even01);
    yj2 = hn::OddEvenBlocks(even23, hn::SwapAdjacentBlocks(even01));
    yj1 = hn::OddEvenBlocks(hn::SwapAdjacentBlocks(odd23), odd01);
    w = hn::OddEvenBlocks(odd23, hn::SwapAdjacentBlocks(odd01));
    return;
  }
#endif
  {
    alignas(64) double lanes[4][kN];
    for (std::size_t l = 0; l < kN; ++l) {
      for (std::size_t c = 0; c < 4; ++c) {
        lanes[c][l] = at(l)[c];
      }
    }
    yj0 = hn::Load(d, lanes[0]);
    yj1 = hn::Load(d, lanes[1]);
    yj2 = hn::Load(d, lanes[2]);
    w = hn::Load(d, lanes[3]);
  }
}

/// The lanes of `acc` added in virtual-lane order 0…7.
HWY_INLINE double lane_sum(D d, const V (&acc)[kU]) {
  alignas(64) double lanes[virtual_lanes];
  for (std::size_t u = 0; u < kU; ++u) {
    hn::Store(acc[u], d, lanes + u * kN);
  }
  double sum = lanes[0];
  for (std::size_t l = 1; l < virtual_lanes; ++l) {
    sum += lanes[l];
  }
  return sum;
}

void PackRows(const FibreData& fd, const double* y, double* /*b*/, std::size_t first,
              std::size_t last) {
  for (std::size_t i = first; i < last; ++i) {
    double* r = fd.record + 4 * i;
    r[0] = y[3 * i];
    r[1] = y[3 * i + 1];
    r[2] = y[3 * i + 2];
    r[3] = 0.0;
  }
}

/// Pass 1 on one block: Σ (1/N) A_k |ξ_k| ε_k into the lane sums.
template <bool Full>
HWY_INLINE void mean_block(const FibreData& fd, V yi0, V yi1, V yi2, const Block& p,
                           std::size_t valid, V (&acc)[kU]) {
  const D d;
  const V one = hn::Set(d, 1.0);
  for (std::size_t u = 0; u < kU; ++u) {
    const std::size_t o = u * kN;
    V yj0, yj1, yj2, unused;
    neighbours(d, fd.record, p.neighbour + o, yj0, yj1, yj2, unused);
    const V dy0 = hn::Sub(yj0, yi0), dy1 = hn::Sub(yj1, yi1), dy2 = hn::Sub(yj2, yi2);
    const V r = hn::Sqrt(hn::Add(hn::Add(hn::Mul(dy0, dy0), hn::Mul(dy1, dy1)), hn::Mul(dy2, dy2)));
    const V strain = hn::Sub(hn::Mul(r, hn::LoadU(d, p.inverse_length + o)), one);
    V term = hn::Mul(hn::LoadU(d, p.weight + o), strain);
    if constexpr (!Full) {
      term = hn::IfThenElseZero(hn::FirstN(d, valid > o ? valid - o : 0), term);
    }
    acc[u] = hn::Add(acc[u], term);
  }
}

void MeanRows(const FibreData& fd, const double* y, double* /*b*/, std::size_t first,
              std::size_t last) {
  const D d;
  const auto* nb = reinterpret_cast<const std::int32_t*>(fd.neighbour);
  for (std::size_t i = first; i < last; ++i) {
    const V yi0 = hn::Set(d, y[3 * i]), yi1 = hn::Set(d, y[3 * i + 1]),
            yi2 = hn::Set(d, y[3 * i + 2]);
    V acc[kU];
    for (V& a : acc) {
      a = hn::Zero(d);
    }
    const std::size_t end = fd.offsets[i + 1];
    std::size_t k = fd.offsets[i];
    for (; k + virtual_lanes <= end; k += virtual_lanes) {
      mean_block<true>(fd, yi0, yi1, yi2,
                       Block{nb + k, fd.inverse_length + k, fd.mean_weight + k, nullptr},
                       virtual_lanes, acc);
    }
    if (k < end) {
      Tail t;
      const Block p = t.fill(nb, fd, fd.mean_weight, k, end - k, false);
      mean_block<false>(fd, yi0, yi1, yi2, p, end - k, acc);
    }
    const double mean = fd.volumetric[i] * lane_sum(d, acc);
    fd.mean_term[i] = mean;
    double* r = fd.state + 4 * i;
    r[0] = y[3 * i];
    r[1] = y[3 * i + 1];
    r[2] = y[3 * i + 2];
    r[3] = mean;
  }
}

/// Pass 2 on one block: each arm's tension (eq. 70) times its direction into the lane sums.
/// `Uniform`: every particle has the shear constant `shear_all`, so none is gathered.
template <bool Full, bool Uniform>
HWY_INLINE void force_block(const FibreData& fd, V yi0, V yi1, V yi2, V shear_i, V mean_i,
                            V shear_all, const Block& p, std::size_t valid, V (&acc)[3][kU]) {
  const D d;
  const V one = hn::Set(d, 1.0);
  for (std::size_t u = 0; u < kU; ++u) {
    const std::size_t o = u * kN;
    V yj0, yj1, yj2, mean_j;
    neighbours(d, fd.state, p.neighbour + o, yj0, yj1, yj2, mean_j);
    const V dy0 = hn::Sub(yj0, yi0), dy1 = hn::Sub(yj1, yi1), dy2 = hn::Sub(yj2, yi2);
    V shear_j = shear_all;
    if constexpr (!Uniform) {
      alignas(64) double lanes[kN];
      for (std::size_t l = 0; l < kN; ++l) {
        lanes[l] = fd.shear[static_cast<std::size_t>(p.neighbour[o + l])];
      }
      shear_j = hn::Load(d, lanes);
    }
    const V r = hn::Sqrt(hn::Add(hn::Add(hn::Mul(dy0, dy0), hn::Mul(dy1, dy1)), hn::Mul(dy2, dy2)));
    const V strain = hn::Sub(hn::Mul(r, hn::LoadU(d, p.inverse_length + o)), one);
    const V s_i = hn::Add(hn::Mul(shear_i, strain), mean_i);
    const V s_j = hn::Add(hn::Mul(shear_j, strain), mean_j);
    V g = hn::Div(
        hn::Add(hn::Mul(hn::LoadU(d, p.weight + o), s_i), hn::Mul(hn::LoadU(d, p.other + o), s_j)),
        r);
    if constexpr (!Full) {
      g = hn::IfThenElseZero(hn::FirstN(d, valid > o ? valid - o : 0), g);
    }
    acc[0][u] = hn::Add(acc[0][u], hn::Mul(g, dy0));
    acc[1][u] = hn::Add(acc[1][u], hn::Mul(g, dy1));
    acc[2][u] = hn::Add(acc[2][u], hn::Mul(g, dy2));
  }
}

template <bool Uniform>
void ForceRows(const FibreData& fd, const double* y, double* b, std::size_t first,
               std::size_t last) {
  const D d;
  const auto* nb = reinterpret_cast<const std::int32_t*>(fd.neighbour);
  const V shear_all = hn::Set(d, Uniform ? fd.shear[0] : 0.0);
  for (std::size_t i = first; i < last; ++i) {
    const V yi0 = hn::Set(d, y[3 * i]), yi1 = hn::Set(d, y[3 * i + 1]),
            yi2 = hn::Set(d, y[3 * i + 2]);
    const V shear_i = hn::Set(d, fd.shear[i]), mean_i = hn::Set(d, fd.mean_term[i]);
    V acc[3][kU];
    for (auto& row : acc) {
      for (V& a : row) {
        a = hn::Zero(d);
      }
    }
    const std::size_t end = fd.offsets[i + 1];
    std::size_t k = fd.offsets[i];
    for (; k + virtual_lanes <= end; k += virtual_lanes) {
      force_block<true, Uniform>(fd, yi0, yi1, yi2, shear_i, mean_i, shear_all,
                                 Block{nb + k, fd.inverse_length + k, fd.own + k, fd.other + k},
                                 virtual_lanes, acc);
    }
    if (k < end) {
      Tail t;
      const Block p = t.fill(nb, fd, fd.own, k, end - k, true);
      force_block<false, Uniform>(fd, yi0, yi1, yi2, shear_i, mean_i, shear_all, p, end - k, acc);
    }
    for (std::size_t c = 0; c < 3; ++c) {
      b[3 * i + c] = lane_sum(d, acc[c]);
    }
  }
}

} // namespace fibre

FibreRows FibrePackRowsFor() {
  return &fibre::PackRows;
}
FibreRows FibreMeanRowsFor() {
  return &fibre::MeanRows;
}
FibreRows FibreForceRowsFor(bool uniform_shear) {
  return uniform_shear ? &fibre::ForceRows<true> : &fibre::ForceRows<false>;
}

} // namespace pd::kernel::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace pd::kernel {

HWY_EXPORT(FibrePackRowsFor);
HWY_EXPORT(FibreMeanRowsFor);
HWY_EXPORT(FibreForceRowsFor);

FibreRows simd_fibre_pack_rows() {
  return HWY_DYNAMIC_DISPATCH(FibrePackRowsFor)();
}

FibreRows simd_fibre_mean_rows() {
  return HWY_DYNAMIC_DISPATCH(FibreMeanRowsFor)();
}

FibreRows simd_fibre_force_rows(bool uniform_shear) {
  return HWY_DYNAMIC_DISPATCH(FibreForceRowsFor)(uniform_shear);
}

} // namespace pd::kernel
#endif
