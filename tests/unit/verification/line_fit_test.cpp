// The Griffith case's line fit (verification/runner/line_fit.hpp): exact on points of a line, the
// textbook R² on a set with scatter, and its refusals.
#include "line_fit.hpp"

#include <cmath>
#include <gtest/gtest.h>
#include <stdexcept>
#include <vector>

namespace pd::verification {
namespace {

TEST(LineFit, PointsOnALineGiveItsSlopeInterceptAndRSquaredOne) {
  const std::vector<double> x{0.0175, 0.02, 0.025, 0.0316, 0.0365};
  std::vector<double> y;
  for (double v : x) {
    y.push_back(14.2 * v + 0.031);
  }
  const LineFit f = fit_line(x, y);
  EXPECT_NEAR(f.slope, 14.2, 1e-10);
  EXPECT_NEAR(f.intercept, 0.031, 1e-12);
  EXPECT_NEAR(f.r_squared, 1.0, 1e-12);
}

TEST(LineFit, ScatterGivesTheTextbookValues) {
  // x = 1…5, y = 2, 4, 5, 4, 5: slope 0.6, intercept 2.2, R² = 3.6 / 6 = 0.6.
  const LineFit f = fit_line({1, 2, 3, 4, 5}, {2, 4, 5, 4, 5});
  EXPECT_NEAR(f.slope, 0.6, 1e-12);
  EXPECT_NEAR(f.intercept, 2.2, 1e-12);
  EXPECT_NEAR(f.r_squared, 0.6, 1e-12);
}

TEST(LineFit, RefusesTooFewPointsMismatchedSizesAndEqualX) {
  EXPECT_THROW(fit_line({1.0}, {2.0}), std::invalid_argument);
  EXPECT_THROW(fit_line({1.0, 2.0}, {2.0}), std::invalid_argument);
  EXPECT_THROW(fit_line({3.0, 3.0, 3.0}, {1.0, 2.0, 3.0}), std::invalid_argument);
  EXPECT_TRUE(std::isnan(fit_line({1.0, 2.0}, {4.0, 4.0}).r_squared));
}

} // namespace
} // namespace pd::verification
