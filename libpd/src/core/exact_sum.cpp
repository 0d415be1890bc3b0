#include "libpd/core/exact_sum.hpp"

#include <bit>
#include <cmath>
#include <cstdlib>

namespace pd {

namespace {

constexpr std::int64_t limb_mask = (std::int64_t{1} << ExactSum::limb_bits) - 1;
/// A limb takes terms below 2^32 each, so 2^30 of them leave it far from overflowing int64.
constexpr std::uint32_t adds_before_normalise = 1U << 30U;

} // namespace

void ExactSum::add(double x) {
  // |x| = significand · 2^(position − exponent_offset), read from the bits (frexp and ldexp
  // cost 5× the rest of add()): a normal number's biased exponent e gives the implicit leading
  // bit and position e + 52, a subnormal's (e = 0) position 53. Zero adds zeros.
  const auto bits = std::bit_cast<std::uint64_t>(x);
  const auto biased = static_cast<int>((bits >> 52U) & 0x7FFU);
  if (biased == 0x7FF) { // ±inf or NaN
    non_finite_ += x;
    return;
  }
  const std::uint64_t fraction = bits & ((std::uint64_t{1} << 52U) - 1);
  const std::uint64_t significand = biased == 0 ? fraction : fraction | (std::uint64_t{1} << 52U);
  const int position = (biased == 0 ? 1 : biased) + 52; // exponent_offset − 1075 = 52
  const auto at = static_cast<std::size_t>(position / limb_bits);
  const int shift = position % limb_bits;
  // significand · 2^shift < 2^85 in three 32-bit pieces, from its low and high words.
  const std::uint64_t low = significand & static_cast<std::uint64_t>(limb_mask);
  const std::uint64_t high = significand >> limb_bits;
  const std::uint64_t low_shifted = low << shift;                           // < 2^63
  const std::uint64_t upper = (high << shift) + (low_shifted >> limb_bits); // < 2^54
  const std::int64_t sign = 1 - 2 * static_cast<std::int64_t>(bits >> 63U); // no branch
  limb_[at] += sign * static_cast<std::int64_t>(low_shifted & limb_mask);
  limb_[at + 1] += sign * static_cast<std::int64_t>(upper & limb_mask);
  limb_[at + 2] += sign * static_cast<std::int64_t>(upper >> limb_bits);
  if (++adds_ >= adds_before_normalise) {
    normalise();
  }
}

void ExactSum::normalise() {
  for (std::size_t k = 0; k + 1 < limb_.size(); ++k) {
    const std::int64_t carry = limb_[k] >> limb_bits; // arithmetic shift: floor division
    limb_[k] -= carry * (std::int64_t{1} << limb_bits);
    limb_[k + 1] += carry;
  }
  adds_ = 0;
}

void ExactSum::merge(const ExactSum& other) {
  ExactSum rhs = other;
  rhs.normalise();
  normalise();
  for (std::size_t k = 0; k < limb_.size(); ++k) {
    limb_[k] += rhs.limb_[k];
  }
  non_finite_ += rhs.non_finite_;
  normalise();
}

double ExactSum::value() const {
  if (non_finite_ != 0 || std::isnan(non_finite_)) {
    return non_finite_;
  }
  ExactSum s = *this;
  s.normalise();
  // Convert the magnitude: a negative sum's canonical form is its two's complement, whose limbs
  // would cancel; negate it so every limb is a non-negative digit.
  const bool negative = s.limb_.back() < 0;
  if (negative) {
    for (auto& l : s.limb_) {
      l = -l;
    }
    s.normalise();
  }
  // From the top digit down: three digits hold 96 bits, more than a double keeps, and the order
  // is fixed, so the result is a function of the exact sum alone.
  double magnitude = 0;
  for (std::size_t k = s.limb_.size(); k-- > 0;) {
    if (s.limb_[k] != 0) {
      magnitude += std::ldexp(static_cast<double>(s.limb_[k]),
                              static_cast<int>(k) * limb_bits - exponent_offset);
    }
  }
  return negative ? -magnitude : magnitude;
}

} // namespace pd
