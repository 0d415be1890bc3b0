// The observed order of convergence of pd verify's sweeps (verification/runner/observed_order.hpp):
// fitted over consecutive levels where |error| falls, "not monotone" where none does.
#include "observed_order.hpp"

#include <cmath>
#include <gtest/gtest.h>

namespace {

using pd::verification::observed_order;

// e = 3 h²: the fit over every level gives 2, in whichever order the levels come.
TEST(ObservedOrder, MonotoneSequenceGivesItsOrder) {
  const auto o = observed_order({{0.025, 3 * 0.025 * 0.025}, {0.1, 0.03}, {0.05, 0.0075}});
  ASSERT_TRUE(o.order);
  EXPECT_NEAR(*o.order, 2.0, 1e-12);
  EXPECT_TRUE(o.monotone);
  EXPECT_EQ(o.levels, 3U);
  EXPECT_EQ(o.spacings, (std::vector<double>{0.1, 0.05, 0.025}));
  EXPECT_EQ(o.text(), "2.000 over λ = 0.1 … 0.025 (3 levels)");
}

// A sign change is no obstacle when |error| still falls: +4 %, −1 %, +0.25 % is order 2.
TEST(ObservedOrder, SignChangesCountByMagnitude) {
  const auto o = observed_order({{0.1, 0.04}, {0.05, -0.01}, {0.025, 0.0025}});
  ASSERT_TRUE(o.order);
  EXPECT_NEAR(*o.order, 2.0, 1e-12);
  EXPECT_TRUE(o.monotone);
}

// The error rises from the coarsest level to the next, then falls as h: the fit leaves the
// coarsest level out and says so. A fit over all four levels would report 0.22.
TEST(ObservedOrder, FitsOnlyTheMonotoneLevels) {
  const auto o = observed_order({{0.1, 0.01}, {0.05, 0.03}, {0.025, 0.015}, {0.0125, 0.0075}});
  ASSERT_TRUE(o.order);
  EXPECT_NEAR(*o.order, 1.0, 1e-12);
  EXPECT_FALSE(o.monotone);
  EXPECT_EQ(o.spacings, (std::vector<double>{0.05, 0.025, 0.0125}));
  EXPECT_EQ(o.errors, (std::vector<double>{0.03, 0.015, 0.0075}));
  EXPECT_NE(o.text().find("3 of 4 levels"), std::string::npos) << o.text();
}

// Two falling pairs of the same length, broken by a rise: the finer pair is fitted (nearer the
// asymptotic range): 0.02 → 0.005 over a halving is order 2, the coarse pair's would be 1.
TEST(ObservedOrder, PrefersTheFinerOfEqualRuns) {
  const auto o = observed_order({{0.1, 0.02}, {0.05, 0.01}, {0.025, 0.02}, {0.0125, 0.005}});
  ASSERT_TRUE(o.order);
  EXPECT_NEAR(*o.order, 2.0, 1e-12);
  EXPECT_EQ(o.spacings, (std::vector<double>{0.025, 0.0125}));
}

// An error that grows under every refinement has no order.
TEST(ObservedOrder, RisingErrorIsNotMonotone) {
  const auto o = observed_order({{0.1, 0.01}, {0.05, 0.02}, {0.025, 0.04}});
  EXPECT_FALSE(o.order);
  EXPECT_FALSE(o.monotone);
  EXPECT_TRUE(o.spacings.empty());
  EXPECT_EQ(o.text().rfind("not monotone", 0), 0U) << o.text();
  const auto json = pd::verification::to_json(o).dump(0);
  EXPECT_NE(json.find("\"order\":null"), std::string::npos) << json;
}

// A repeated spacing (the sweep's baseline and its own spacing row) counts once; a single level
// has no order.
TEST(ObservedOrder, RepeatedSpacingCountsOnce) {
  const auto o = observed_order({{0.05, 0.01}, {0.05, 0.02}});
  EXPECT_EQ(o.levels, 1U);
  EXPECT_FALSE(o.order);
}

} // namespace
