// Exact, order-independent sums (core/exact_sum.hpp): what makes energies, residuals and ADR's
// damping the same on any number of ranks or threads.
#include "libpd/core/exact_sum.hpp"

#include <algorithm>
#include <cmath>
#include <gtest/gtest.h>
#include <limits>
#include <random>
#include <vector>

namespace {

std::vector<double> wild_terms(std::size_t n, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> mantissa(-1.0, 1.0);
  std::uniform_int_distribution<int> exponent(-60, 60);
  std::vector<double> v(n);
  for (double& x : v) {
    x = std::ldexp(mantissa(rng), exponent(rng));
  }
  return v;
}

double sum_of(const std::vector<double>& v) {
  pd::ExactSum s;
  for (double x : v) {
    s.add(x);
  }
  return s.value();
}

TEST(ExactSum, CancellationLosesNothing) {
  pd::ExactSum s;
  s.add(1e100);
  s.add(1.0);
  s.add(-1e100);
  EXPECT_EQ(s.value(), 1.0); // a naive sum gives 0
  pd::ExactSum t;
  t.add(std::numeric_limits<double>::denorm_min());
  t.add(std::numeric_limits<double>::max());
  t.add(-std::numeric_limits<double>::max());
  EXPECT_EQ(t.value(), std::numeric_limits<double>::denorm_min());
}

TEST(ExactSum, RoundsTheExactValue) {
  // Ten copies of double(0.1) add up to 1 + 5.55e-17 exactly; the nearest double is 1.
  pd::ExactSum s;
  for (int k = 0; k < 10; ++k) {
    s.add(0.1);
  }
  EXPECT_EQ(s.value(), 1.0);
  pd::ExactSum negative;
  for (int k = 0; k < 10; ++k) {
    negative.add(-0.1);
  }
  EXPECT_EQ(negative.value(), -1.0);
}

TEST(ExactSum, AnyOrderAnyGroupingGivesTheSameBits) {
  std::vector<double> v = wild_terms(20000, 7);
  const double reference = sum_of(v);
  std::mt19937_64 rng(11);
  for (int trial = 0; trial < 5; ++trial) {
    std::shuffle(v.begin(), v.end(), rng);
    EXPECT_EQ(sum_of(v), reference);
    // Split over 4 "ranks" of uneven size, merged in another order.
    pd::ExactSum part[4];
    for (std::size_t i = 0; i < v.size(); ++i) {
      part[(i * 7 + static_cast<std::size_t>(trial)) % 4].add(v[i]);
    }
    part[3].merge(part[1]);
    part[3].merge(part[0]);
    part[3].merge(part[2]);
    EXPECT_EQ(part[3].value(), reference);
  }
  // And it is close to the long-double sum (the exact value rounded once).
  long double naive = 0;
  for (double x : v) {
    naive += x;
  }
  EXPECT_NEAR(reference, static_cast<double>(naive), 1e-12 * std::abs(reference) + 1e-30);
}

TEST(ExactSum, NormalisingKeepsTheValue) {
  pd::ExactSum s;
  for (double x : wild_terms(1000, 3)) {
    s.add(x);
  }
  const double before = s.value();
  s.normalise();
  for (std::size_t k = 0; k + 1 < s.limbs().size(); ++k) {
    EXPECT_GE(s.limbs()[k], 0);
    EXPECT_LT(s.limbs()[k], std::int64_t{1} << pd::ExactSum::limb_bits);
  }
  EXPECT_EQ(s.value(), before);
}

TEST(ExactSum, NonFiniteTermsFollowIeee) {
  pd::ExactSum s;
  s.add(1.0);
  s.add(std::numeric_limits<double>::infinity());
  EXPECT_EQ(s.value(), std::numeric_limits<double>::infinity());
  s.add(-std::numeric_limits<double>::infinity());
  EXPECT_TRUE(std::isnan(s.value()));
  pd::ExactSum overflow;
  overflow.add(std::numeric_limits<double>::max());
  overflow.add(std::numeric_limits<double>::max());
  EXPECT_EQ(overflow.value(), std::numeric_limits<double>::infinity());
}

} // namespace
