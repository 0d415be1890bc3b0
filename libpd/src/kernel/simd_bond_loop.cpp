// The vectorised bond loop over Google Highway (see kernel/simd_bond_loop.hpp for the contract).
// foreach_target.h re-includes this file once per instruction set; everything between
// HWY_BEFORE_NAMESPACE and HWY_AFTER_NAMESPACE is compiled for each of them.
//
// Bitwise reproducibility rests on two rules kept below: every floating-point operation is an
// explicit, correctly rounded Highway op in the same order as in the scalar kernel (this file is
// compiled with -ffp-contract=off, so no mul+add pair becomes an FMA on one target but not on
// another), and each particle's sum uses the fixed 8-virtual-lane order.

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "kernel/simd_bond_loop.cpp"
#include "libpd/kernel/simd_bond_loop.hpp"

#include "libpd/physics/bond_laws.hpp"
#include "libpd/physics/stretch.hpp"

#include <array>
#include <cstring>
#include <hwy/foreach_target.h> // IWYU pragma: keep
#include <hwy/highway.h>
#include <tuple>
#include <type_traits>
#include <utility>

#ifndef LIBPD_SIMD_BOND_LOOP_SHARED
#define LIBPD_SIMD_BOND_LOOP_SHARED
namespace pd::kernel::detail {

/// Combination index 0…23: stretch × plasticity × damage × per-bond field.
constexpr std::size_t combo_index(StretchKind stretch, bool plasticity, bool damage,
                                  bool per_bond) {
  return static_cast<std::size_t>(stretch) * 8 + (plasticity ? 4 : 0) + (damage ? 2 : 0) +
         (per_bond ? 1 : 0);
}
inline constexpr std::size_t combo_count = 24;
using Stretches = std::tuple<ExactStretch, ModifiedStretch, FastStretch>;
static_assert(static_cast<std::size_t>(StretchKind::exact) == 0 &&
              static_cast<std::size_t>(StretchKind::modified) == 1 &&
              static_cast<std::size_t>(StretchKind::fast) == 2);

/// One block of up to `virtual_lanes` bonds copied out of the row so the tail can use full
/// vectors: lanes past the row end repeat the block's first bond (finite values, masked off).
struct TailBlock {
  alignas(64) std::int32_t neighbour[virtual_lanes];
  alignas(64) double inverse_length[virtual_lanes];
  alignas(64) double stiffness[virtual_lanes];
  alignas(64) double critical_stretch[virtual_lanes];
  alignas(64) double yield_stretch[virtual_lanes];
  alignas(64) double plastic[virtual_lanes];
  alignas(64) std::uint8_t broken[virtual_lanes];
};
static_assert(virtual_lanes == sizeof(std::uint64_t), "a block's flags are tested as one word");

} // namespace pd::kernel::detail
#endif

HWY_BEFORE_NAMESPACE();
namespace pd::kernel::HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

// At most 8 lanes per vector, so one block of `virtual_lanes` bonds is kU whole vectors.
using D = hn::CappedTag<double, virtual_lanes>;
using V = hn::Vec<D>;
using M = hn::Mask<D>;
constexpr std::size_t kN = hn::MaxLanes(D());
constexpr std::size_t kU = virtual_lanes / kN;
static_assert(kN * kU == virtual_lanes, "vector width must divide the virtual lane count");

/// Where one block's per-bond arrays start: the row itself, or a TailBlock.
struct BlockPointers {
  const std::int32_t* neighbour;
  const double* inverse_length;
  const double* stiffness;
  const double* critical_stretch;
  const double* yield_stretch;
  double* plastic;
  std::uint8_t* broken;
};

/// Stretch and direction scale of eqs. 5–6 (exact) and 17 (modified, fast), rounded as the scalar
/// policies in stretch.hpp round them.
template <class Stretch>
HWY_INLINE void stretch_of(D d, V r2, V inv, V& s, V& scale) {
  const V one = hn::Set(d, 1.0);
  if constexpr (std::is_same_v<Stretch, ExactStretch>) {
    const V r = hn::Sqrt(r2);
    s = hn::Sub(hn::Mul(r, inv), one);
    scale = hn::Div(one, r);
  } else if constexpr (std::is_same_v<Stretch, ModifiedStretch>) {
    s = hn::Mul(hn::Set(d, 0.5), hn::Sub(hn::Mul(hn::Mul(r2, inv), inv), one));
    scale = hn::Div(one, hn::Sqrt(r2));
  } else {
    static_assert(std::is_same_v<Stretch, FastStretch>, "no SIMD form for this stretch measure");
    s = hn::Mul(hn::Set(d, 0.5), hn::Sub(hn::Mul(hn::Mul(r2, inv), inv), one));
    scale = inv;
  }
}

/// f/c of the bond law (eq. 7, or eqs. 14–16 updating the plastic stretch where `active`).
template <class Law>
HWY_INLINE V law_of(D d, V s, V yield, V& plastic, M active) {
  if constexpr (std::is_same_v<Law, MicroElastic>) {
    (void)d, (void)yield, (void)plastic, (void)active;
    return s;
  } else {
    static_assert(std::is_same_v<Law, MicroPlastic>, "no SIMD form for this bond law");
    const V elastic = hn::Sub(s, plastic);
    const V neg_yield = hn::Neg(yield);
    const M up = hn::Gt(elastic, yield);
    const M down = hn::Lt(elastic, neg_yield);
    const V moved =
        hn::IfThenElse(up, hn::Sub(s, yield), hn::IfThenElse(down, hn::Add(s, yield), plastic));
    plastic = hn::IfThenElse(active, moved, plastic);
    (void)d;
    return hn::IfThenElse(up, yield, hn::IfThenElse(down, neg_yield, elastic));
  }
}

/// Sets the flags of the lanes in `breaks`. Rare, so kept out of line: inlined, its byte stores
/// (which may alias anything) made GCC keep the hot loop's values on the stack.
HWY_NOINLINE void mark_broken(M breaks, std::uint8_t* broken) {
  const D d;
  std::uint8_t bits[8] = {};
  hn::StoreMaskBits(d, breaks, bits);
  for (std::size_t l = 0; l < kN; ++l) {
    if ((bits[l / 8] >> (l % 8)) & 1U) {
      broken[l] = 1;
    }
  }
}

/// The bonds of one block (kU vectors); `valid` bonds of it exist (kN·kU for a full block).
/// Adds to the per-virtual-lane sums and returns how many valid bonds are broken. `Intact`: the
/// caller has seen that no bond of this (full) block is broken yet, so the flags are not read.
template <class Stretch, class Law, bool Damage, class Field, bool Full, bool Intact = false>
HWY_INLINE std::size_t block(const KernelData& kd, const double* y, V yi0, V yi1, V yi2,
                             const BlockPointers& p, std::size_t valid, V (&acc)[3][kU]) {
  static_assert(Full || !Intact, "only a full block is tested for intact bonds");
  const D d;
  const hn::Rebind<std::int32_t, D> di32;
  const hn::Rebind<std::uint8_t, D> du8;
  std::size_t broken_count = 0;
  for (std::size_t u = 0; u < kU; ++u) {
    const std::size_t o = u * kN;
    M active = Full ? hn::FirstN(d, kN) : hn::FirstN(d, valid > o ? valid - o : 0);
    if constexpr (Damage && !Intact) {
      const V was = hn::PromoteTo(d, hn::PromoteTo(di32, hn::LoadU(du8, p.broken + o)));
      const M was_broken = hn::And(active, hn::Gt(was, hn::Zero(d)));
      broken_count += hn::CountTrue(d, was_broken);
      active = hn::AndNot(was_broken, active);
    }
    // y_j − y_i. The neighbour positions are gathered by scalar loads into three lane arrays,
    // not by vgatherqpd: on the AMD EPYC (Zen 4) this was measured on, the hardware gather made
    // the whole loop 1.5× (exact) to 1.9× (fast) slower (pd-kernel-bench, same-run CPU times).
    alignas(64) double yj0[kN], yj1[kN], yj2[kN];
    for (std::size_t l = 0; l < kN; ++l) {
      const double* yj = y + 3 * static_cast<std::size_t>(p.neighbour[o + l]);
      yj0[l] = yj[0];
      yj1[l] = yj[1];
      yj2[l] = yj[2];
    }
    const V dy0 = hn::Sub(hn::Load(d, yj0), yi0);
    const V dy1 = hn::Sub(hn::Load(d, yj1), yi1);
    const V dy2 = hn::Sub(hn::Load(d, yj2), yi2);
    const V r2 = hn::Add(hn::Add(hn::Mul(dy0, dy0), hn::Mul(dy1, dy1)), hn::Mul(dy2, dy2));
    V s, scale;
    stretch_of<Stretch>(d, r2, hn::LoadU(d, p.inverse_length + o), s, scale);
    if constexpr (Damage) {
      const V s0 =
          Field::per_bond ? hn::LoadU(d, p.critical_stretch + o) : hn::Set(d, kd.critical_stretch);
      const M breaks = hn::And(active, hn::Ge(s, s0)); // eq. 10: once broken, never restored
      if (!hn::AllFalse(d, breaks)) {
        mark_broken(breaks, p.broken + o);
        broken_count += hn::CountTrue(d, breaks);
        active = hn::AndNot(breaks, active);
      }
    }
    V f;
    if constexpr (Law::has_history) {
      const V yield =
          Field::per_bond ? hn::LoadU(d, p.yield_stretch + o) : hn::Set(d, kd.yield_stretch);
      V plastic = hn::LoadU(d, p.plastic + o);
      f = law_of<Law>(d, s, yield, plastic, active);
      hn::StoreU(plastic, d, p.plastic + o);
    } else {
      V unused = hn::Zero(d);
      f = law_of<Law>(d, s, hn::Zero(d), unused, active);
    }
    const V c = Field::per_bond ? hn::LoadU(d, p.stiffness + o) : hn::Set(d, kd.stiffness);
    const V g = hn::IfThenElseZero(active, hn::Mul(hn::Mul(c, f), scale));
    acc[0][u] = hn::Add(acc[0][u], hn::Mul(g, dy0));
    acc[1][u] = hn::Add(acc[1][u], hn::Mul(g, dy1));
    acc[2][u] = hn::Add(acc[2][u], hn::Mul(g, dy2));
  }
  return broken_count;
}

template <class Stretch, class Law, bool Damage, class Field>
void rows(const KernelData& kd_in, const double* y, double* b, std::size_t first,
          std::size_t last) {
  // A local copy: the flag stores (uint8_t, which may alias anything) and the out-of-line
  // mark_broken would otherwise make GCC reload every field of `kd_in` in each block.
  const KernelData kd = kd_in;
  const D d;
  static_assert(sizeof(std::int32_t) == sizeof(std::uint32_t));
  // Indices are < 2^31 (particle counts are checked against this in make_force_evaluator).
  const auto* neighbour = reinterpret_cast<const std::int32_t*>(kd.neighbour);
  for (std::size_t i = first; i < last; ++i) {
    const V yi0 = hn::Set(d, y[3 * i]), yi1 = hn::Set(d, y[3 * i + 1]),
            yi2 = hn::Set(d, y[3 * i + 2]);
    V acc[3][kU];
    for (auto& row : acc) {
      for (V& a : row) {
        a = hn::Zero(d);
      }
    }
    std::size_t broken_count = 0;
    const std::size_t begin = kd.offsets[i], end = kd.offsets[i + 1];
    std::size_t k = begin;
    for (; k + virtual_lanes <= end; k += virtual_lanes) {
      const BlockPointers p{neighbour + k,
                            kd.inverse_length + k,
                            Field::per_bond ? kd.bond_stiffness + k : nullptr,
                            Field::per_bond && Damage ? kd.bond_critical_stretch + k : nullptr,
                            Field::per_bond && Law::has_history ? kd.bond_yield_stretch + k
                                                                : nullptr,
                            Law::has_history ? kd.plastic_stretch + k : nullptr,
                            Damage ? kd.broken + k : nullptr};
      if constexpr (Damage) {
        // Nearly every block of a run has no broken bond: one 8-byte test replaces the widening
        // and counting of the flags lane by lane.
        std::uint64_t flags = 0;
        std::memcpy(&flags, kd.broken + k, sizeof flags);
        if (flags == 0) {
          broken_count += block<Stretch, Law, Damage, Field, true, true>(kd, y, yi0, yi1, yi2, p,
                                                                         virtual_lanes, acc);
          continue;
        }
      }
      broken_count +=
          block<Stretch, Law, Damage, Field, true>(kd, y, yi0, yi1, yi2, p, virtual_lanes, acc);
    }
    if (k < end) { // masked tail through a padded copy
      const std::size_t n = end - k;
      detail::TailBlock t;
      for (std::size_t l = 0; l < virtual_lanes; ++l) {
        const std::size_t src = k + (l < n ? l : 0);
        t.neighbour[l] = neighbour[src];
        t.inverse_length[l] = kd.inverse_length[src];
        t.stiffness[l] = Field::per_bond ? kd.bond_stiffness[src] : 0.0;
        t.critical_stretch[l] = Field::per_bond && Damage ? kd.bond_critical_stretch[src] : 0.0;
        t.yield_stretch[l] = Field::per_bond && Law::has_history ? kd.bond_yield_stretch[src] : 0.0;
        t.plastic[l] = Law::has_history ? kd.plastic_stretch[src] : 0.0;
        t.broken[l] = Damage ? kd.broken[src] : 0;
      }
      const BlockPointers p{t.neighbour,     t.inverse_length, t.stiffness, t.critical_stretch,
                            t.yield_stretch, t.plastic,        t.broken};
      broken_count += block<Stretch, Law, Damage, Field, false>(kd, y, yi0, yi1, yi2, p, n, acc);
      for (std::size_t l = 0; l < n; ++l) {
        if constexpr (Law::has_history) {
          kd.plastic_stretch[k + l] = t.plastic[l];
        }
        if constexpr (Damage) {
          kd.broken[k + l] = t.broken[l];
        }
      }
    }
    // Fixed-order reduction: virtual lanes 0…7, whatever kN is.
    for (int c = 0; c < 3; ++c) {
      alignas(64) double lanes[virtual_lanes];
      for (std::size_t u = 0; u < kU; ++u) {
        hn::Store(acc[c][u], d, lanes + u * kN);
      }
      double sum = lanes[0];
      for (std::size_t l = 1; l < virtual_lanes; ++l) {
        sum += lanes[l];
      }
      b[3 * i + static_cast<std::size_t>(c)] = sum;
    }
    if constexpr (Damage) {
      const std::size_t family = end - begin;
      kd.damage[i] = family > 0 ? static_cast<double>(broken_count) / static_cast<double>(family)
                                : 0.0; // eq. 13
    }
  }
}

template <std::size_t C>
void rows_combo(const KernelData& kd, const double* y, double* b, std::size_t first,
                std::size_t last) {
  using Stretch = std::tuple_element_t<C / 8, detail::Stretches>;
  using Law = std::conditional_t<(C / 4) % 2 == 1, MicroPlastic, MicroElastic>;
  using Field = std::conditional_t<C % 2 == 1, PerBondField, UniformField>;
  rows<Stretch, Law, (C / 2) % 2 == 1, Field>(kd, y, b, first, last);
}

template <std::size_t... C>
constexpr std::array<RowKernel, sizeof...(C)> make_table(std::index_sequence<C...>) {
  return {&rows_combo<C>...};
}

RowKernel RowKernelFor(std::size_t combo) {
  static constexpr auto table = make_table(std::make_index_sequence<detail::combo_count>());
  return table[combo];
}

const char* TargetNameHere() {
  return hwy::TargetName(HWY_TARGET);
}

} // namespace pd::kernel::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace pd::kernel {

HWY_EXPORT(RowKernelFor);
HWY_EXPORT(TargetNameHere);

RowKernel simd_row_kernel(StretchKind stretch, bool plasticity, bool damage, bool per_bond_field) {
  return HWY_DYNAMIC_DISPATCH(RowKernelFor)(
      detail::combo_index(stretch, plasticity, damage, per_bond_field));
}

std::string simd_target_name() {
  return HWY_DYNAMIC_DISPATCH(TargetNameHere)();
}

} // namespace pd::kernel
#endif
