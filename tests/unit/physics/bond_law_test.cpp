// Stretch measures and bond laws: values, the relation between the measures (Miranda eq. 26),
// energy/force consistency, the common linearisation (Appendix A) and micro-plasticity
// (eqs. 14–16).
#include "libpd/physics/bond_laws.hpp"
#include "libpd/physics/stretch.hpp"

#include <array>
#include <cmath>
#include <gtest/gtest.h>
#include <limits>
#include <string>

namespace {

using V3 = std::array<double, 3>;

double sq(const V3& a) {
  return a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
}

TEST(Stretch, ValuesForKnownLengths) {
  const double len = 0.2;
  const double inv = 1.0 / len;
  for (double r : {0.2, 0.21, 0.19, 0.3, 0.1}) {
    SCOPED_TRACE(r);
    const double s = (r - len) / len;                          // eq. 6
    const double sbar = (r * r - len * len) / (2 * len * len); // eq. 17
    const auto e = pd::ExactStretch::evaluate(r * r, inv);
    const auto m = pd::ModifiedStretch::evaluate(r * r, inv);
    const auto f = pd::FastStretch::evaluate(r * r, inv);
    EXPECT_NEAR(e.stretch, s, 1e-14);
    EXPECT_NEAR(m.stretch, sbar, 1e-14);
    EXPECT_NEAR(f.stretch, sbar, 1e-14);
    // The force direction is Δy/r for exact and modified, Δy/L for fast.
    EXPECT_NEAR(e.direction_scale, 1.0 / r, 1e-12);
    EXPECT_NEAR(m.direction_scale, 1.0 / r, 1e-12);
    EXPECT_NEAR(f.direction_scale, 1.0 / len, 1e-12);
  }
  // A concrete case: L = 0.2, r = 0.22 → s = 0.1, s̄ = (0.0484 − 0.04)/0.08 = 0.105.
  EXPECT_NEAR(pd::ExactStretch::evaluate(0.22 * 0.22, 5.0).stretch, 0.1, 1e-14);
  EXPECT_NEAR(pd::ModifiedStretch::evaluate(0.22 * 0.22, 5.0).stretch, 0.105, 1e-14);
}

TEST(Stretch, ModifiedStretchIsSPlusHalfSSquared) {
  // Miranda eq. 26 for stretches from strong compression to strong tension.
  const double len = 1.7;
  for (double s = -0.5; s <= 1.0; s += 0.05) {
    const double r = len * (1 + s);
    const double r2 = r * r;
    const double s_exact = pd::ExactStretch::evaluate(r2, 1 / len).stretch;
    EXPECT_NEAR(s_exact, s, 1e-13);
    EXPECT_NEAR(pd::ModifiedStretch::evaluate(r2, 1 / len).stretch, s + 0.5 * s * s, 1e-13);
    EXPECT_NEAR(pd::FastStretch::evaluate(r2, 1 / len).stretch, s + 0.5 * s * s, 1e-13);
  }
  // At s = 0.1 the modified stretch is 5 % larger (the header's example).
  const double r = 1.1 * len;
  EXPECT_NEAR(pd::ModifiedStretch::evaluate(r * r, 1 / len).stretch / 0.1, 1.05, 1e-12);
}

/// Force vector per unit c of a linear bond: stretch · direction_scale · Δy.
template <class S>
V3 force(const V3& dy, double inv_len) {
  const auto sr = S::evaluate(sq(dy), inv_len);
  return {sr.stretch * sr.direction_scale * dy[0], sr.stretch * sr.direction_scale * dy[1],
          sr.stretch * sr.direction_scale * dy[2]};
}

template <class S>
void check_energy_gradient(const std::string& name) {
  SCOPED_TRACE(name);
  const V3 xi{0.3, -0.1, 0.2};
  const double len = std::sqrt(sq(xi));
  // Deformed bonds: stretched, compressed, rotated and sheared.
  const std::array<V3, 5> dys{V3{0.33, -0.1, 0.2}, V3{0.27, -0.09, 0.18}, V3{0.1, 0.35, 0.2},
                              V3{0.35, 0.05, 0.25}, V3{0.2, -0.1, 0.1}};
  for (const V3& dy : dys) {
    const V3 f = force<S>(dy, 1 / len);
    const double fnorm = std::sqrt(sq(f));
    ASSERT_GT(fnorm, 0.0);
    const double h = 1e-6 * len;
    for (int c = 0; c < 3; ++c) {
      V3 p = dy, m = dy;
      p[c] += h;
      m[c] -= h;
      const double grad =
          (S::bond_energy(sq(p), 1 / len) - S::bond_energy(sq(m), 1 / len)) / (2 * h);
      // The force on i is +c·s·dir·Δy, and w depends on Δy = y_j − y_i, so ∂w/∂(Δy) = f.
      EXPECT_NEAR(grad, f[c], 1e-6 * fnorm) << "component " << c;
    }
  }
  // Zero in the reference configuration, up to cancellation in the cubic of `modified`.
  EXPECT_NEAR(S::bond_energy(len * len, 1 / len), 0.0, 1e-15 * len);
}

TEST(Stretch, BondEnergyIsThePotentialOfTheForce) {
  check_energy_gradient<pd::ExactStretch>("exact");
  check_energy_gradient<pd::ModifiedStretch>("modified");
  check_energy_gradient<pd::FastStretch>("fast");
}

TEST(Stretch, BondEnergyKnownValues) {
  // Closed forms integrated by hand: w = ∫_L^r f dr'.
  const double len = 0.5, r = 0.55;
  const double s = 0.1;
  EXPECT_NEAR(pd::ExactStretch::bond_energy(r * r, 1 / len), 0.5 * len * s * s, 1e-15);
  // modified: ∫ (r'² − L²)/(2L²) dr' = (r³ − L³)/(6L²) − (r − L)/2.
  const double wm = (r * r * r - len * len * len) / (6 * len * len) - 0.5 * (r - len);
  EXPECT_NEAR(pd::ModifiedStretch::bond_energy(r * r, 1 / len), wm, 1e-15);
  const double sbar = s + 0.5 * s * s;
  EXPECT_NEAR(pd::FastStretch::bond_energy(r * r, 1 / len), 0.5 * len * sbar * sbar, 1e-15);
}

/// Relative error of S::bond_energy against a long-double evaluation of the same closed form
/// written without cancellation, for the same (r², 1/L) inputs.
template <class S>
double small_stretch_energy_error(double s) {
  const double len = 0.0173;
  const double r2 = (len * (1 + s)) * (len * (1 + s));
  const double inv = 1 / len;
  const long double r = std::sqrt(static_cast<long double>(r2));
  const long double l = 1.0L / static_cast<long double>(inv);
  long double w = 0;
  if (S::name == "modified") {
    w = (r - l) * (r - l) * (r + 2 * l) / (6 * l * l); // ∫_L^r (r'² − L²)/(2L²) dr'
  } else if (S::name == "exact") {
    w = 0.5L * l * ((r - l) / l) * ((r - l) / l);
  } else {
    const long double sb = (r * r - l * l) / (2 * l * l);
    w = 0.5L * l * sb * sb;
  }
  return static_cast<double>(std::abs((static_cast<long double>(S::bond_energy(r2, inv)) - w) / w));
}

TEST(Stretch, BondEnergyKeepsItsPrecisionAtSmallStretch) {
  // Quasi-static runs have stretches of 1e-6…1e-4. The stretch itself carries an absolute error of
  // ~1e-16, so the energy ∝ s² can be known to ~1e-16/s relative; a form that subtracts terms of
  // size L³ loses 1e-16/s² instead (1e-4 at s = 1e-6).
  for (double s : {1e-4, 1e-5, 1e-6}) {
    SCOPED_TRACE(s);
    EXPECT_LT(small_stretch_energy_error<pd::ExactStretch>(s), 1e-8);
    EXPECT_LT(small_stretch_energy_error<pd::FastStretch>(s), 1e-8);
    EXPECT_LT(small_stretch_energy_error<pd::ModifiedStretch>(s), 1e-8);
  }
}

template <class S>
void check_linearisation(const std::string& name) {
  SCOPED_TRACE(name);
  for (const V3& xi : {V3{1.0, 0, 0}, V3{0.3, -0.1, 0.2}, V3{-0.02, 0.05, 0.01}}) {
    const double len = std::sqrt(sq(xi));
    const double h = 1e-6 * len;
    const double scale = 1 / len; // |C| = c/|ξ|
    for (int b = 0; b < 3; ++b) {
      V3 p = xi, m = xi;
      p[b] += h;
      m[b] -= h;
      const V3 fp = force<S>(p, 1 / len);
      const V3 fm = force<S>(m, 1 / len);
      for (int a = 0; a < 3; ++a) {
        const double jac = (fp[a] - fm[a]) / (2 * h);
        const double micromodulus = xi[a] * xi[b] / (len * len * len); // Appendix A
        EXPECT_NEAR(jac, micromodulus, 1e-6 * scale) << a << "," << b;
      }
    }
  }
}

TEST(Stretch, AllMeasuresShareTheMicromodulusTensor) {
  check_linearisation<pd::ExactStretch>("exact");
  check_linearisation<pd::ModifiedStretch>("modified");
  check_linearisation<pd::FastStretch>("fast");
}

TEST(Stretch, FastForceIsModifiedForceTimesROverL) {
  const V3 dy{0.4, 0.1, -0.3};
  const double len = 0.45;
  const double r = std::sqrt(sq(dy));
  const V3 fm = force<pd::ModifiedStretch>(dy, 1 / len);
  const V3 ff = force<pd::FastStretch>(dy, 1 / len);
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(ff[c], fm[c] * r / len, 1e-14);
  }
}

TEST(Stretch, Names) {
  EXPECT_EQ(pd::ExactStretch::name, "exact");
  EXPECT_EQ(pd::ModifiedStretch::name, "modified");
  EXPECT_EQ(pd::FastStretch::name, "fast");
}

TEST(BondLaw, MicroElasticIsLinearAndStateless) {
  double plastic = 0.123;
  for (double s : {-0.3, 0.0, 1e-5, 0.02}) {
    EXPECT_EQ(pd::MicroElastic::force(s, 1e-4, plastic), s);
  }
  EXPECT_EQ(plastic, 0.123);
  EXPECT_FALSE(pd::MicroElastic::has_history);
  EXPECT_EQ(pd::MicroElastic::name, "elastic");
}

TEST(BondLaw, MicroPlasticLoadYieldUnloadReverse) {
  const double sy = 0.002;
  double plastic = 0;
  auto f = [&](double s) { return pd::MicroPlastic::force(s, sy, plastic); };
  EXPECT_TRUE(pd::MicroPlastic::has_history);
  EXPECT_EQ(pd::MicroPlastic::name, "plastic");

  // Elastic loading: f = s, no plastic stretch (eq. 14 with ŝ = 0).
  EXPECT_DOUBLE_EQ(f(0.001), 0.001);
  EXPECT_EQ(plastic, 0.0);
  EXPECT_DOUBLE_EQ(f(sy), sy);
  EXPECT_EQ(plastic, 0.0);
  // Yielding: the force is capped at f_Y = c s_Y (eq. 16) and ŝ follows s (eq. 15).
  EXPECT_DOUBLE_EQ(f(0.003), sy);
  EXPECT_DOUBLE_EQ(plastic, 0.001);
  EXPECT_DOUBLE_EQ(f(0.005), sy);
  EXPECT_DOUBLE_EQ(plastic, 0.003);
  // Unloading is elastic around the permanent plastic stretch.
  EXPECT_DOUBLE_EQ(f(0.004), 0.001);
  EXPECT_DOUBLE_EQ(plastic, 0.003);
  EXPECT_NEAR(f(0.003), 0.0, 1e-18); // zero force at s = ŝ
  EXPECT_DOUBLE_EQ(f(0.002), -0.001);
  EXPECT_DOUBLE_EQ(f(0.001), -sy); // on the compressive yield surface, still elastic
  EXPECT_DOUBLE_EQ(plastic, 0.003);
  // Reverse yielding in compression: force capped at −f_Y, ŝ = s + s_Y.
  EXPECT_DOUBLE_EQ(f(0.0), -sy);
  EXPECT_DOUBLE_EQ(plastic, sy);
  EXPECT_DOUBLE_EQ(f(-0.004), -sy);
  EXPECT_DOUBLE_EQ(plastic, -0.002);
  // Reloading elastic from the new plastic stretch.
  EXPECT_DOUBLE_EQ(f(-0.001), 0.001);
  EXPECT_DOUBLE_EQ(plastic, -0.002);
  // History does not depend on the path taken within the elastic range.
  double p1 = 0, p2 = 0;
  for (int k = 0; k <= 20; ++k) {
    pd::MicroPlastic::force(0.0005 * k, sy, p1);
  }
  pd::MicroPlastic::force(0.01, sy, p2);
  EXPECT_NEAR(p1, p2, 1e-15);
  EXPECT_NEAR(p2, 0.01 - sy, 1e-15);
}

TEST(BondLaw, MicroPlasticWithInfiniteYieldIsElastic) {
  double plastic = 0;
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(pd::MicroPlastic::force(0.5, inf, plastic), 0.5);
  EXPECT_EQ(pd::MicroPlastic::force(-0.5, inf, plastic), -0.5);
  EXPECT_EQ(plastic, 0.0);
}

} // namespace
