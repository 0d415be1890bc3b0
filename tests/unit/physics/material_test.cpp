// Micromodulus and critical stretch against independent derivations: the closed forms of Miranda
// eqs. 8 and 11, and quadratures of the PD energy density and fracture energy done here.
#include "libpd/physics/material.hpp"

#include <array>
#include <cmath>
#include <functional>
#include <gtest/gtest.h>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using pd::ModelDimension;
using pd::PlaneMode;
using Strain = std::array<std::array<double, 3>, 3>;
constexpr double pi = std::numbers::pi;

/// Gauss–Legendre rule on [a, b]: exact for polynomials of degree < 2n.
struct Rule {
  std::vector<double> x, w;
};

Rule gauss_legendre(int n, double a, double b) {
  Rule r;
  for (int i = 0; i < n; ++i) {
    double z = std::cos(pi * (i + 0.75) / (n + 0.5));
    double dp = 0;
    for (int it = 0; it < 100; ++it) {
      double p0 = 1, p1 = z;
      for (int k = 2; k <= n; ++k) {
        const double p2 = ((2.0 * k - 1) * z * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      dp = n * (z * p1 - p0) / (z * z - 1);
      const double dz = p1 / dp;
      z -= dz;
      if (std::abs(dz) < 1e-16) {
        break;
      }
    }
    r.x.push_back(0.5 * (a + b) + 0.5 * (b - a) * z);
    r.w.push_back((b - a) / ((1 - z * z) * dp * dp));
  }
  return r;
}

/// Trapezoid rule on a full period: exact for trigonometric polynomials of degree < n.
Rule periodic(int n) {
  Rule r;
  for (int i = 0; i < n; ++i) {
    r.x.push_back(2 * pi * i / n);
    r.w.push_back(2 * pi / n);
  }
  return r;
}

double integrate(const Rule& r, const std::function<double(double)>& f) {
  double s = 0;
  for (std::size_t i = 0; i < r.x.size(); ++i) {
    s += r.w[i] * f(r.x[i]);
  }
  return s;
}

/// Linearised stretch of a bond ξ under a small uniform strain: s = ξ·εξ/|ξ|².
double stretch(const Strain& e, const std::array<double, 3>& n) {
  double s = 0;
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) {
      s += n[a] * e[a][b] * n[b];
    }
  }
  return s;
}

/// PD strain energy density W = ½ ∫_H ½ c s² |ξ| dV_ξ (Silling 2000), by quadrature over the
/// horizon in the given dimension. dV = t dA in 2D and A dξ in 1D (the convention of the lattice).
double pd_energy_density(const ModelDimension& d, double c, double delta, const Strain& e) {
  const Rule rr = gauss_legendre(8, 0, delta);
  if (d.dim == 3) {
    const Rule ru = gauss_legendre(12, -1, 1); // u = cos θ
    const Rule rp = periodic(16);
    return integrate(rr, [&](double r) {
      return integrate(ru, [&](double u) {
        return integrate(rp, [&](double phi) {
          const double st = std::sqrt(1 - u * u);
          const double s = stretch(e, {st * std::cos(phi), st * std::sin(phi), u});
          return 0.25 * c * s * s * r * r * r;
        });
      });
    });
  }
  if (d.dim == 2) {
    const Rule rp = periodic(16);
    return integrate(rr, [&](double r) {
      return integrate(rp, [&](double th) {
        const double s = stretch(e, {std::cos(th), std::sin(th), 0});
        return 0.25 * c * s * s * r * d.thickness * r;
      });
    });
  }
  const double s = e[0][0];
  return 2 * integrate(rr, [&](double r) { return 0.25 * c * s * s * r * d.cross_section; });
}

/// Classical strain energy density of an isotropic material in the same setting.
double classical_energy_density(const ModelDimension& d, double E, double nu, const Strain& e) {
  if (d.dim == 1) {
    return 0.5 * E * e[0][0] * e[0][0];
  }
  const double lam = E * nu / ((1 + nu) * (1 - 2 * nu));
  const double mu = E / (2 * (1 + nu));
  if (d.dim == 3) {
    const double tr = e[0][0] + e[1][1] + e[2][2];
    double ee = 0;
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b < 3; ++b) {
        ee += e[a][b] * e[a][b];
      }
    }
    return 0.5 * lam * tr * tr + mu * ee;
  }
  const double e11 = e[0][0], e22 = e[1][1], e12 = e[0][1];
  if (d.plane == PlaneMode::plane_strain) {
    return 0.5 * lam * (e11 + e22) * (e11 + e22) + mu * (e11 * e11 + e22 * e22 + 2 * e12 * e12);
  }
  const double k = E / (1 - nu * nu);
  return 0.5 * k * (e11 * e11 + e22 * e22 + 2 * nu * e11 * e22) + 2 * mu * e12 * e12;
}

std::vector<std::pair<std::string, ModelDimension>> settings() {
  ModelDimension d3;
  ModelDimension ps;
  ps.dim = 2;
  ps.plane = PlaneMode::plane_stress;
  ps.thickness = 0.013;
  ModelDimension pe = ps;
  pe.plane = PlaneMode::plane_strain;
  ModelDimension d1;
  d1.dim = 1;
  d1.cross_section = 2.5e-3;
  return {{"3D", d3}, {"plane stress", ps}, {"plane strain", pe}, {"1D", d1}};
}

TEST(Material, ThreeDimensionalMicromodulusIsMirandaEq8) {
  const ModelDimension d;
  for (double E : {30e9, 210e9, 1.0}) {
    for (double delta : {0.1732, 0.05, 3.0}) {
      const double nu = 0.25;
      const double k = E / (3 * (1 - 2 * nu));
      const double expected = 18 * k / (pi * delta * delta * delta * delta);
      EXPECT_NEAR(pd::micromodulus(d, E, delta), expected, 1e-13 * expected);
      EXPECT_NEAR(pd::micromodulus(d, E, delta), 12 * E / (pi * std::pow(delta, 4)),
                  1e-13 * expected);
    }
  }
}

TEST(Material, ThreeDimensionalCriticalStretchIsMirandaEq11) {
  const ModelDimension d;
  const double E = 30e9, G0 = 120.0;
  for (double delta : {0.1732, 0.05}) {
    const double c = pd::micromodulus(d, E, delta);
    const double s0 = pd::critical_stretch_from_fracture_energy(d, E, delta, G0);
    EXPECT_NEAR(s0, std::sqrt(10 * G0 / (pi * c * std::pow(delta, 5))), 1e-14);
    EXPECT_NEAR(s0, std::sqrt(5 * G0 / (6 * E * delta)), 1e-14);
  }
  // A number to recognise: concrete-like E = 30 GPa, G0 = 120 J/m², δ = 2√3·0.05 m.
  const double delta = 2 * std::sqrt(3.0) * 0.05;
  EXPECT_NEAR(pd::critical_stretch_from_fracture_energy(d, E, delta, G0),
              std::sqrt(5 * 120.0 / (6 * 30e9 * delta)), 1e-15);
}

TEST(Material, EnergyDensityMatchesClassicalElasticity) {
  // Isotropic, uniaxial and shear strains: all three must match once c is calibrated and ν is the
  // Poisson ratio the bond-based model represents.
  const double E = 70e9;
  for (const auto& [name, d] : settings()) {
    SCOPED_TRACE(name);
    const double delta = 0.03;
    const double c = pd::micromodulus(d, E, delta);
    const auto nu = pd::bond_based_poisson_ratio(d);
    ASSERT_EQ(nu.has_value(), d.dim != 1);
    const double eps = 1e-3;
    std::vector<Strain> strains;
    Strain iso{}, uni{}, shear{}, mixed{};
    for (int a = 0; a < d.dim; ++a) {
      iso[a][a] = eps;
    }
    uni[0][0] = eps;
    strains = {iso, uni};
    if (d.dim > 1) {
      shear[0][1] = shear[1][0] = eps;
      mixed[0][0] = eps;
      mixed[1][1] = -0.3 * eps;
      mixed[0][1] = mixed[1][0] = 0.7 * eps;
      strains.push_back(shear);
      strains.push_back(mixed);
    }
    for (const Strain& e : strains) {
      const double w_pd = pd_energy_density(d, c, delta, e);
      const double w_cl = classical_energy_density(d, E, nu.value_or(0.0), e);
      EXPECT_NEAR(w_pd, w_cl, 1e-10 * w_cl);
    }
  }
}

TEST(Material, PoissonRatioFollowsFromThePairPotential) {
  // The stiffness components C1111 and C1122 of the PD energy, by quadrature; the Cauchy relation
  // of central pair forces fixes their ratio, and with it ν.
  const double E = 1.0, delta = 1.0;
  for (const auto& [name, d] : settings()) {
    if (d.dim == 1) {
      EXPECT_FALSE(pd::bond_based_poisson_ratio(d).has_value());
      continue;
    }
    SCOPED_TRACE(name);
    const double c = pd::micromodulus(d, E, delta);
    Strain e1{}, e12{};
    e1[0][0] = 1;
    e12[0][0] = e12[1][1] = 1;
    const double c11 = 2 * pd_energy_density(d, c, delta, e1);
    // W(ε11 = ε22 = 1) = ½(C11 + C22) + C12 = C11 + C12.
    const double c12 = pd_energy_density(d, c, delta, e12) - c11;
    double nu = 0;
    if (d.dim == 2 && d.plane == PlaneMode::plane_stress) {
      nu = c12 / c11; // C11 = E/(1−ν²), C12 = νE/(1−ν²)
    } else {
      nu = c12 / (c11 + c12); // C12/C11 = ν/(1−ν)
    }
    EXPECT_NEAR(pd::bond_based_poisson_ratio(d).value(), nu, 1e-12);
  }
  ModelDimension d3;
  EXPECT_DOUBLE_EQ(pd::bond_based_poisson_ratio(d3).value(), 0.25);
  ModelDimension ps;
  ps.dim = 2;
  EXPECT_DOUBLE_EQ(pd::bond_based_poisson_ratio(ps).value(), 1.0 / 3.0);
  ps.plane = PlaneMode::plane_strain;
  EXPECT_DOUBLE_EQ(pd::bond_based_poisson_ratio(ps).value(), 0.25);
}

/// Energy needed to break every bond crossing a unit area, G0 = ∫∫ w dV dV' with
/// w = c s0² |ξ|/2 (Silling & Askari 2005). Summing over bonds instead of points: a bond ξ with
/// component ξ_n > 0 normal to the crack is cut for the points at depth z ∈ (0, ξ_n), so
/// G0 = ∫_{|ξ|≤δ, ξ_n>0} ξ_n w(ξ) dV_ξ (times t or A in 2D/1D).
double fracture_energy_by_bonds(const ModelDimension& d, double c, double delta, double s0) {
  const Rule rr = gauss_legendre(10, 0, delta);
  auto w = [&](double r) { return 0.5 * c * s0 * s0 * r; };
  if (d.dim == 3) {
    const Rule ru = gauss_legendre(10, 0, 1); // u = cos θ, normal component r·u
    return integrate(rr, [&](double r) {
      return integrate(ru, [&](double u) { return 2 * pi * r * u * w(r) * r * r; });
    });
  }
  if (d.dim == 2) {
    const Rule rt = gauss_legendre(20, 0, pi);
    return d.thickness * integrate(rr, [&](double r) {
             return integrate(rt, [&](double th) { return r * std::sin(th) * w(r) * r; });
           });
  }
  return d.cross_section * integrate(rr, [&](double r) { return r * w(r); });
}

TEST(Material, CriticalStretchBreaksBondsWithTheFractureEnergy) {
  const double E = 30e9, G0 = 95.0;
  for (const auto& [name, d] : settings()) {
    SCOPED_TRACE(name);
    for (double delta : {0.01, 0.1732}) {
      const double c = pd::micromodulus(d, E, delta);
      const double s0 = pd::critical_stretch_from_fracture_energy(d, E, delta, G0);
      EXPECT_GT(s0, 0);
      EXPECT_NEAR(fracture_energy_by_bonds(d, c, delta, s0), G0, 1e-11 * G0);
    }
  }
}

TEST(Material, ThreeDimensionalFractureEnergyByPointsAndBonds) {
  // The original double integral over points below the crack (depth z) and their partners above:
  // G0 = ∫_0^δ dz ∫_{r>z} ∫_{cos θ > z/r} w r² sinθ dφ dθ dr, done without swapping the order.
  const ModelDimension d;
  const double E = 30e9, G0 = 95.0, delta = 0.2;
  const double c = pd::micromodulus(d, E, delta);
  const double s0 = pd::critical_stretch_from_fracture_energy(d, E, delta, G0);
  const Rule rz = gauss_legendre(16, 0, delta);
  const double g = integrate(rz, [&](double z) {
    const Rule rr = gauss_legendre(16, z, delta);
    return integrate(rr, [&](double r) {
      const Rule rt = gauss_legendre(16, 0, std::acos(z / r));
      return integrate(
          rt, [&](double th) { return 2 * pi * 0.5 * c * s0 * s0 * r * r * r * std::sin(th); });
    });
  });
  EXPECT_NEAR(g, G0, 1e-10 * G0);
}

TEST(Material, TwoAndOneDimensionalClosedForms) {
  const double E = 200e9, G0 = 1000.0, delta = 0.004;
  ModelDimension ps;
  ps.dim = 2;
  ps.thickness = 0.01;
  ModelDimension pe = ps;
  pe.plane = PlaneMode::plane_strain;
  ModelDimension d1;
  d1.dim = 1;
  d1.cross_section = 1e-4;
  const double d3 = delta * delta * delta;
  EXPECT_NEAR(pd::micromodulus(ps, E, delta), 9 * E / (pi * 0.01 * d3), 1e-12 * E / d3 / 0.01);
  EXPECT_NEAR(pd::micromodulus(pe, E, delta), 48 * E / (5 * pi * 0.01 * d3), 1e-12 * E / d3 / 0.01);
  EXPECT_NEAR(pd::micromodulus(d1, E, delta), 2 * E / (1e-4 * delta * delta),
              1e-12 * E / (1e-4 * delta * delta));
  EXPECT_NEAR(pd::critical_stretch_from_fracture_energy(ps, E, delta, G0),
              std::sqrt(4 * pi * G0 / (9 * E * delta)), 1e-15);
  EXPECT_NEAR(pd::critical_stretch_from_fracture_energy(pe, E, delta, G0),
              std::sqrt(5 * pi * G0 / (12 * E * delta)), 1e-15);
  EXPECT_NEAR(pd::critical_stretch_from_fracture_energy(d1, E, delta, G0),
              std::sqrt(3 * G0 / (E * delta)), 1e-15);
}

TEST(Material, ThicknessAndCrossSectionCancelInCTimesVolume) {
  // c·V_j must not depend on the out-of-plane size: otherwise a 2D model's response would change
  // with a purely nominal thickness.
  const double E = 5e9, delta = 0.03, lambda = 0.01;
  ModelDimension a;
  a.dim = 2;
  a.thickness = 0.001;
  ModelDimension b = a;
  b.thickness = 0.5;
  EXPECT_NEAR(pd::micromodulus(a, E, delta) * lambda * lambda * a.thickness,
              pd::micromodulus(b, E, delta) * lambda * lambda * b.thickness,
              1e-12 * pd::micromodulus(a, E, delta) * lambda * lambda * a.thickness);
  a.dim = b.dim = 1;
  a.cross_section = 1e-6;
  b.cross_section = 3.0;
  EXPECT_NEAR(pd::micromodulus(a, E, delta) * lambda * a.cross_section,
              pd::micromodulus(b, E, delta) * lambda * b.cross_section,
              1e-12 * pd::micromodulus(a, E, delta) * lambda * a.cross_section);
  // s0 does not depend on them either.
  EXPECT_DOUBLE_EQ(pd::critical_stretch_from_fracture_energy(a, E, delta, 10.0),
                   pd::critical_stretch_from_fracture_energy(b, E, delta, 10.0));
}

TEST(Material, InvalidDimensionThrows) {
  ModelDimension d;
  d.dim = 4;
  EXPECT_THROW(pd::micromodulus(d, 1.0, 1.0), std::invalid_argument);
  EXPECT_THROW(pd::critical_stretch_from_fracture_energy(d, 1.0, 1.0, 1.0), std::invalid_argument);
}

} // namespace
