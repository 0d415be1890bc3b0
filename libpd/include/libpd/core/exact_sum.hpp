// Sums whose value does not depend on the order of their terms.
//
// A floating-point sum depends on the order of its terms: a run split over 1, 2 or 4 MPI ranks
// (or threads) that added the same terms in another grouping would round differently, and a
// steady-state test or ADR's damping coefficient built on the sum would then send the runs apart.
// ExactSum instead keeps the exact value of the sum in a long fixed-point accumulator, 32 bits per
// limb from the smallest subnormal (2^-1074) to beyond the largest double, so adding, merging and
// reducing across ranks are exact integer operations, and the double it returns is a function of
// the exact sum alone. This is Neal's "small superaccumulator" (R. M. Neal, Fast exact summation
// using small and large superaccumulators, arXiv:1505.05571, 2015) in its plainest form.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

namespace pd {

class ExactSum {
public:
  /// Limbs of 32 bits each from 2^-1127 (53 bits below the smallest subnormal, so that a term's
  /// 53-bit significand always lands at limb bit ≥ 0) to above 2^1024 with headroom.
  static constexpr int limb_bits = 32;
  static constexpr int limb_count = 70;
  static constexpr int exponent_offset = 1127;

  void add(double x);
  ExactSum& operator+=(double x) {
    add(x);
    return *this;
  }
  /// Adds another accumulator's exact value (both are normalised first).
  void merge(const ExactSum& other);

  /// The sum, rounded; the same double for the same exact sum whatever the order of the terms.
  /// Non-finite terms: +inf, -inf or NaN by IEEE rules (also order-independent).
  double value() const;

  /// The canonical limbs (every limb in [0, 2^32) but the last, which carries the sign) and the
  /// sum of the non-finite terms, for reducing across ranks (core/communicator.hpp).
  std::array<std::int64_t, limb_count>& limbs() { return limb_; }
  double& non_finite() { return non_finite_; }
  /// Bring every limb into [0, 2^32) by carrying upwards. Needed before limbs are exchanged;
  /// add() and merge() call it when the headroom of a limb could run out.
  void normalise();

private:
  std::array<std::int64_t, limb_count> limb_{};
  double non_finite_ = 0;  ///< sum of ±inf / NaN terms (order-independent by IEEE rules)
  std::uint32_t adds_ = 0; ///< terms since the last normalise
};

/// Σ values[i] for i in [0, n) where keep(i), exactly (see ExactSum).
template <class Keep, class Term>
double exact_sum(std::size_t n, Keep keep, Term term) {
  ExactSum s;
  for (std::size_t i = 0; i < n; ++i) {
    if (keep(i)) {
      s.add(term(i));
    }
  }
  return s.value();
}

} // namespace pd
