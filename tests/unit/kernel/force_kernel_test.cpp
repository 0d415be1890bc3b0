// The force kernel against a naive reference written from the papers (Miranda et al. 2019 eqs.
// 6–17 and 27), for every combination of stretch measure × plasticity × damage × field storage.
#include "effect_combos.hpp"
#include "libpd/discretisation/model.hpp"
#include "libpd/kernel/force_kernel.hpp"

#include <gtest/gtest.h>

#ifdef _OPENMP
#include <omp.h>
#endif

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>
#include <string>
#include <vector>

namespace {

using pd::StretchKind;
using pd::Vec3;

constexpr double lambda = 0.1;
constexpr double m_factor = 2.015; // δ/λ; no lattice distance within 1 % of δ
constexpr double E = 30e9;

using pd::test::all_combos;
using pd::test::Combo;

/// Box of nx × ny × nz cells. The per-bond variant has a second, stiffer and more brittle material
/// for x > 0.2, the linear partial-volume correction and varying particle volumes; the uniform one
/// a single material.
pd::ModelSpec spec_for(const Combo& c, int nx = 5, int ny = 4, int nz = 3) {
  pd::ModelSpec s;
  s.surface_correction = pd::SurfaceCorrection::none; // the bare model
  s.volume_correction = pd::VolumeCorrection::none;   // linear in the per-bond combos
  s.lattice.spacing = lambda;
  s.lattice.horizon_factor = m_factor;
  s.effects.stretch = c.stretch;
  s.effects.plasticity = c.plasticity;
  s.effects.damage = c.damage;
  pd::Material a;
  a.youngs_modulus = E;
  a.density = 2400;
  a.critical_stretch = 0.004;
  a.yield_stretch = 0.002;
  s.materials.push_back(a);
  const Vec3 hi{nx * lambda, ny * lambda, nz * lambda};
  if (c.per_bond) {
    pd::Material b = a;
    b.stiffness_factor = 2.5;
    b.critical_stretch = 0.006;
    b.yield_stretch = 0.001;
    s.materials.push_back(b);
    pd::BodySpec left, right;
    left.region.boxes = {pd::Box{{0, 0, 0}, {0.2, hi[1], hi[2]}}};
    right.region.boxes = {pd::Box{{0.2, 0, 0}, hi}};
    right.material = 1;
    s.bodies = {left, right};
    s.volume_correction = pd::VolumeCorrection::linear;
    // Unequal volumes tell c·V_j (neighbour) apart from c·V_i.
    s.lattice.volume_variation = 0.2;
  } else {
    pd::BodySpec body;
    body.region.boxes = {pd::Box{{0, 0, 0}, hi}};
    s.bodies = {body};
  }
  return s;
}

/// Independent reference: O(N²) pair search, constants from the closed forms, the bond laws
/// written out. Bond state is kept per directed bond in rows sorted by neighbour.
class Reference {
public:
  struct Bond {
    std::size_t j;
    double len;
    double cv; ///< c_ij · V_j · volume fraction
    double s0, sy;
    double plastic = 0;
    bool broken = false;
  };

  Reference(const pd::ModelSpec& spec, const pd::Model& model, const Combo& combo)
      : combo_(combo), x_(model.particles.position), v_(model.particles.volume) {
    const double delta = m_factor * lambda;
    const double pi = std::numbers::pi;
    std::vector<double> c, s0, sy;
    for (const pd::Material& mat : spec.materials) {
      c.push_back(12 * E * mat.stiffness_factor / (pi * std::pow(delta, 4))); // eq. 8, ν = 1/4
      s0.push_back(*mat.critical_stretch);
      sy.push_back(*mat.yield_stretch);
    }
    rows_.resize(x_.size());
    for (std::size_t i = 0; i < x_.size(); ++i) {
      for (std::size_t j = 0; j < x_.size(); ++j) {
        const double len = distance(x_[i], x_[j]);
        if (j == i || len > delta) {
          continue;
        }
        const int mi = model.particles.material[i], mj = model.particles.material[j];
        double fraction = 1;
        if (combo.per_bond && len > delta - 0.5 * lambda) {
          fraction = (delta + 0.5 * lambda - len) / lambda; // linear partial volume
        }
        // Interface bonds take the weaker material (Miranda §5.2).
        rows_[i].push_back({j, len, std::min(c[mi], c[mj]) * v_[j] * fraction,
                            std::min(s0[mi], s0[mj]), std::min(sy[mi], sy[mj])});
      }
    }
  }

  static double distance(const Vec3& a, const Vec3& b) {
    return std::sqrt((b[0] - a[0]) * (b[0] - a[0]) + (b[1] - a[1]) * (b[1] - a[1]) +
                     (b[2] - a[2]) * (b[2] - a[2]));
  }

  /// Stretch of the chosen measure: eq. 6 or eq. 17.
  double measure(double r, double len) const {
    return combo_.stretch == StretchKind::exact ? (r - len) / len
                                                : (r * r - len * len) / (2 * len * len);
  }

  /// Force densities (eq. 27) and, via `scale`, the sum of the magnitudes of the terms.
  void compute(const std::vector<double>& y, std::vector<double>& b, std::vector<double>& scale) {
    b.assign(y.size(), 0.0);
    scale.assign(x_.size(), 0.0);
    for (std::size_t i = 0; i < x_.size(); ++i) {
      for (Bond& bond : rows_[i]) {
        if (combo_.damage && bond.broken) {
          continue;
        }
        const double dy[3] = {y[3 * bond.j] - y[3 * i], y[3 * bond.j + 1] - y[3 * i + 1],
                              y[3 * bond.j + 2] - y[3 * i + 2]};
        const double r = std::sqrt(dy[0] * dy[0] + dy[1] * dy[1] + dy[2] * dy[2]);
        const double s = measure(r, bond.len);
        if (combo_.damage && s >= bond.s0) { // eq. 10, irreversible
          bond.broken = true;
          continue;
        }
        double f = s;
        if (combo_.plasticity) { // eqs. 14–16: ŝ follows s beyond |s − ŝ| = s_Y
          if (s - bond.plastic > bond.sy) {
            bond.plastic = s - bond.sy;
          } else if (s - bond.plastic < -bond.sy) {
            bond.plastic = s + bond.sy;
          }
          f = s - bond.plastic;
        }
        // Direction: unit vector Δy/r (eq. 5); the fast measure uses Δy/L instead.
        const double dir = combo_.stretch == StretchKind::fast ? 1 / bond.len : 1 / r;
        for (int k = 0; k < 3; ++k) {
          b[3 * i + k] += bond.cv * f * dir * dy[k];
          scale[i] += std::abs(bond.cv * f * dir * dy[k]);
        }
      }
    }
  }

  /// Damage index φ_i = broken / family size (eq. 13).
  std::vector<double> damage() const {
    std::vector<double> phi(x_.size(), 0.0);
    for (std::size_t i = 0; i < x_.size(); ++i) {
      std::size_t broken = 0;
      for (const Bond& bond : rows_[i]) {
        broken += bond.broken ? 1 : 0;
      }
      phi[i] = rows_[i].empty()
                   ? 0.0
                   : static_cast<double>(broken) / static_cast<double>(rows_[i].size());
    }
    return phi;
  }

  /// Stored energy Σ_i V_i ½ Σ_j w_ij V_j where w is the potential of the bond force with the
  /// plastic stretch frozen (the energy the bond gives back when unloaded elastically).
  double strain_energy(const std::vector<double>& y) const {
    double total = 0;
    for (std::size_t i = 0; i < x_.size(); ++i) {
      double sum = 0;
      for (const Bond& bond : rows_[i]) {
        if (combo_.damage && bond.broken) {
          continue;
        }
        const double r = distance({y[3 * i], y[3 * i + 1], y[3 * i + 2]},
                                  {y[3 * bond.j], y[3 * bond.j + 1], y[3 * bond.j + 2]});
        const double len = bond.len;
        const double p = combo_.plasticity ? bond.plastic : 0.0;
        double w = 0;
        switch (combo_.stretch) {
        case StretchKind::exact: // f = c(s − ŝ) along r: w = c L (s − ŝ)²/2
          w = 0.5 * len * std::pow((r - len) / len - p, 2);
          break;
        case StretchKind::fast: // f = c(s̄ − ŝ)Δy/L, ∂s̄/∂Δy = Δy/L²: w = c L (s̄ − ŝ)²/2
          w = 0.5 * len * std::pow(measure(r, len) - p, 2);
          break;
        case StretchKind::modified: {
          // w = ∫_{r_p}^{r} c(s̄(r') − ŝ) dr' with s̄(r_p) = ŝ, i.e. ∫ c(r'² − r_p²)/(2L²) dr'
          // = c (r − r_p)²(r + 2r_p)/(6L²), a form without cancellation.
          const double rp = len * std::sqrt(1 + 2 * p);
          w = (r - rp) * (r - rp) * (r + 2 * rp) / (6 * len * len);
          break;
        }
        }
        sum += bond.cv * w;
      }
      total += v_[i] * 0.5 * sum;
    }
    return total;
  }

  const std::vector<std::vector<Bond>>& rows() const { return rows_; }

  /// Bond counts by state: broken, yielded (ŝ ≠ 0) and intact elastic.
  std::array<std::size_t, 3> census() const {
    std::array<std::size_t, 3> n{0, 0, 0};
    for (const auto& row : rows_) {
      for (const Bond& b : row) {
        ++n[b.broken ? 0 : (b.plastic != 0 ? 1 : 2)];
      }
    }
    return n;
  }

private:
  Combo combo_;
  std::vector<Vec3> x_;
  std::vector<double> v_;
  std::vector<std::vector<Bond>> rows_;
};

/// A smooth strain field of a few 10⁻³ plus a displacement jump across x = 0.25: bonds crossing
/// the jump break, bonds in the smooth part yield (s_Y = 1–2·10⁻³) or stay elastic.
std::vector<double> deformed(const pd::Model& model, double amplitude) {
  std::vector<double> y(3 * model.size());
  for (std::size_t i = 0; i < model.size(); ++i) {
    const Vec3& x = model.particles.position[i];
    const double ux = 0.004 * x[0] * (1 + 2 * x[1]) + (x[0] > 0.25 ? 0.0009 : 0.0);
    const double uy = -0.002 * x[1] * std::sin(3 * x[0]) + 0.001 * x[2];
    const double uz = 0.003 * x[2] * std::cos(2 * x[1]) - 0.0015 * x[0] * x[0];
    y[3 * i] = x[0] + amplitude * ux;
    y[3 * i + 1] = x[1] + amplitude * uy;
    y[3 * i + 2] = x[2] + amplitude * uz;
  }
  return y;
}

std::vector<double> reference_positions(const pd::Model& model) {
  return deformed(model, 0.0);
}

/// Load, partial unload, reverse, reload: exercises yielding, elastic unloading and reverse yield.
const std::vector<double> history{1.0, 0.3, -0.8, 1.2};

TEST(ForceKernel, ZeroForceInTheReferenceConfiguration) {
  for (const Combo& combo : all_combos()) {
    SCOPED_TRACE(combo.label());
    pd::Model model = pd::build_model(spec_for(combo));
    auto eval = pd::make_force_evaluator(model);
    const auto y = reference_positions(model);
    std::vector<double> b(y.size(), 1.0);
    eval->compute(y.data(), b.data());
    for (std::size_t i = 0; i < model.size(); ++i) {
      double scale = 0; // Σ c V: the force density of a unit stretch
      for (std::size_t k = model.family.offsets[i]; k < model.family.offsets[i + 1]; ++k) {
        scale += pd::bond_stiffness(model, k);
      }
      ASSERT_GT(scale, 0);
      const double norm = std::hypot(b[3 * i], b[3 * i + 1], b[3 * i + 2]);
      EXPECT_LE(norm, 1e-12 * scale) << "particle " << i;
    }
    // Zero up to cancellation, measured against the energy of a modest deformation.
    // (`modified` evaluates its energy as a difference of cubes, hence the loose bound.)
    const double loaded = eval->strain_energy(deformed(model, 1.0).data());
    ASSERT_GT(loaded, 0);
    EXPECT_NEAR(eval->strain_energy(y.data()), 0.0, 1e-8 * loaded);
    if (combo.damage) {
      for (double phi : model.state.damage) {
        EXPECT_EQ(phi, 0.0);
      }
    }
  }
}

TEST(ForceKernel, EveryCombinationMatchesTheNaiveReference) {
  bool saw_breaking = false, saw_yielding = false;
  for (const Combo& combo : all_combos()) {
    SCOPED_TRACE(combo.label());
    const pd::ModelSpec spec = spec_for(combo);
    pd::Model model = pd::build_model(spec);
    ASSERT_EQ(model.effects.per_bond_field, combo.per_bond);
    Reference ref(spec, model, combo);
    // The families agree (rows sorted by neighbour on both sides).
    for (std::size_t i = 0; i < model.size(); ++i) {
      ASSERT_EQ(model.family.family_size(i), ref.rows()[i].size()) << i;
      for (std::size_t k = model.family.offsets[i]; k < model.family.offsets[i + 1]; ++k) {
        const auto& bond = ref.rows()[i][k - model.family.offsets[i]];
        ASSERT_EQ(model.family.neighbour[k], bond.j);
        EXPECT_NEAR(pd::bond_stiffness(model, k), bond.cv, 1e-12 * bond.cv);
      }
    }
    auto eval = pd::make_force_evaluator(model);
    std::vector<double> b(3 * model.size()), b_ref, scale;
    for (double amplitude : history) {
      SCOPED_TRACE(amplitude);
      const auto y = deformed(model, amplitude);
      eval->compute(y.data(), b.data());
      ref.compute(y, b_ref, scale);
      for (std::size_t i = 0; i < model.size(); ++i) {
        for (int c = 0; c < 3; ++c) {
          ASSERT_NEAR(b[3 * i + c], b_ref[3 * i + c], 1e-12 * scale[i] + 1e-300)
              << "particle " << i << " component " << c;
        }
      }
      // Bond state, bond by bond.
      for (std::size_t i = 0; i < model.size(); ++i) {
        for (std::size_t k = model.family.offsets[i]; k < model.family.offsets[i + 1]; ++k) {
          const auto& bond = ref.rows()[i][k - model.family.offsets[i]];
          if (combo.damage) {
            ASSERT_EQ(model.state.broken[k] != 0, bond.broken) << i << "->" << bond.j;
          }
          if (combo.plasticity) {
            ASSERT_NEAR(model.state.plastic_stretch[k], bond.plastic, 1e-14) << i << "->" << bond.j;
          }
        }
      }
      if (combo.damage) {
        const auto phi = ref.damage();
        for (std::size_t i = 0; i < model.size(); ++i) {
          EXPECT_DOUBLE_EQ(model.state.damage[i], phi[i]) << i;
        }
      }
      if (amplitude == history.front()) {
        const auto n = ref.census();
        if (combo.damage) {
          EXPECT_GT(n[0], 0u) << "no bond broke";
          saw_breaking = true;
        }
        if (combo.plasticity) {
          EXPECT_GT(n[1], 0u) << "no bond yielded";
          saw_yielding = true;
        }
        EXPECT_GT(n[2], 0u) << "no bond stayed elastic";
      }
    }
  }
  EXPECT_TRUE(saw_breaking);
  EXPECT_TRUE(saw_yielding);
}

TEST(ForceKernel, LinearMomentumIsConserved) {
  // Every pair force appears twice with opposite signs, V_i·c·V_j·f on i and −V_j·c·V_i·f on j:
  // Σ_i V_i b_i = 0 (the uniform variant has uniform volumes, the per-bond one varying volumes).
  for (const Combo& combo : all_combos()) {
    SCOPED_TRACE(combo.label());
    pd::Model model = pd::build_model(spec_for(combo));
    auto eval = pd::make_force_evaluator(model);
    std::vector<double> b(3 * model.size());
    for (double amplitude : history) {
      const auto y = deformed(model, amplitude);
      eval->compute(y.data(), b.data());
      double total[3] = {0, 0, 0}, magnitude = 0;
      for (std::size_t i = 0; i < model.size(); ++i) {
        for (int c = 0; c < 3; ++c) {
          total[c] += model.particles.volume[i] * b[3 * i + c];
          magnitude += model.particles.volume[i] * std::abs(b[3 * i + c]);
        }
      }
      ASSERT_GT(magnitude, 0);
      for (int c = 0; c < 3; ++c) {
        EXPECT_LE(std::abs(total[c]), 1e-13 * magnitude) << "component " << c;
      }
    }
  }
}

TEST(ForceKernel, IdenticalWithOneAndTwoThreads) {
#ifndef _OPENMP
  GTEST_SKIP() << "built without OpenMP";
#else
  const int saved = omp_get_max_threads();
  for (const Combo& combo : all_combos()) {
    SCOPED_TRACE(combo.label());
    std::vector<std::vector<double>> forces(2);
    std::vector<pd::BondState> states(2);
    std::vector<double> energies(2);
    for (int t = 0; t < 2; ++t) {
      omp_set_num_threads(t + 1);
      pd::Model model = pd::build_model(spec_for(combo, 9, 5, 4));
      auto eval = pd::make_force_evaluator(model);
      std::vector<double> b(3 * model.size());
      for (double amplitude : history) {
        const auto y = deformed(model, amplitude);
        eval->compute(y.data(), b.data());
        forces[t].insert(forces[t].end(), b.begin(), b.end());
      }
      states[t] = model.state;
      energies[t] = eval->strain_energy(deformed(model, 0.7).data());
    }
    ASSERT_EQ(forces[0].size(), forces[1].size());
    EXPECT_EQ(std::memcmp(forces[0].data(), forces[1].data(), forces[0].size() * sizeof(double)),
              0);
    EXPECT_EQ(states[0].broken, states[1].broken);
    EXPECT_EQ(states[0].damage, states[1].damage);
    EXPECT_EQ(states[0].plastic_stretch, states[1].plastic_stretch);
    EXPECT_EQ(std::memcmp(&energies[0], &energies[1], sizeof(double)), 0);
  }
  omp_set_num_threads(saved);
#endif
}

/// The library's `modified` bond energy r³/3 − L²r + 2L³/3 cancels to about 1e-16/s² relative
/// (bond_law_test checks that separately); at the stretches used here that is ~1e-10.
double energy_tolerance(const Combo& c) {
  return c.stretch == StretchKind::modified ? 1e-9 : 1e-11;
}

TEST(ForceKernel, StrainEnergyMatchesHandSum) {
  // Elastic bonds for all measures, and plastic bonds with the exact stretch; the plastic case
  // with the other measures is checked separately below.
  for (const Combo& combo : all_combos()) {
    if (combo.plasticity && combo.stretch != StretchKind::exact) {
      continue;
    }
    SCOPED_TRACE(combo.label());
    const pd::ModelSpec spec = spec_for(combo);
    pd::Model model = pd::build_model(spec);
    Reference ref(spec, model, combo);
    auto eval = pd::make_force_evaluator(model);
    std::vector<double> b(3 * model.size()), b_ref, scale;
    for (double amplitude : history) {
      const auto y = deformed(model, amplitude);
      eval->compute(y.data(), b.data());
      ref.compute(y, b_ref, scale);
      // Energy at a different configuration than the one that set the history.
      const auto probe = deformed(model, 0.6 * amplitude);
      const double expected = ref.strain_energy(probe);
      ASSERT_GT(expected, 0);
      EXPECT_NEAR(eval->strain_energy(probe.data()), expected, energy_tolerance(combo) * expected);
    }
    // strain_energy does not touch the history.
    const pd::BondState before = model.state;
    eval->strain_energy(deformed(model, 5.0).data());
    EXPECT_EQ(model.state.broken, before.broken);
    EXPECT_EQ(model.state.plastic_stretch, before.plastic_stretch);
  }
}

/// For plastic bonds the stored energy must be the potential of the bond force with ŝ frozen, in
/// the stretch measure that defines the force — in particular a plastic bond that has not yielded
/// stores exactly what the elastic bond stores, and a bond at s = ŝ (zero force) stores nothing.
void check_plastic_energy(StretchKind stretch) {
  for (bool damage : {false, true}) {
    for (bool per_bond : {false, true}) {
      const Combo combo{stretch, true, damage, per_bond};
      SCOPED_TRACE(combo.label());
      const pd::ModelSpec spec = spec_for(combo);
      pd::Model model = pd::build_model(spec);
      Reference ref(spec, model, combo);
      auto eval = pd::make_force_evaluator(model);
      // Before any yielding: same as the elastic law.
      {
        Combo elastic = combo;
        elastic.plasticity = false;
        pd::Model m2 = pd::build_model(spec_for(elastic));
        auto e2 = pd::make_force_evaluator(m2);
        const auto y = deformed(model, 0.4);
        EXPECT_NEAR(eval->strain_energy(y.data()), e2->strain_energy(y.data()),
                    energy_tolerance(combo) * e2->strain_energy(y.data()))
            << "unyielded plastic bonds store a different energy than elastic ones";
      }
      std::vector<double> b(3 * model.size()), b_ref, scale;
      for (double amplitude : history) {
        const auto y = deformed(model, amplitude);
        eval->compute(y.data(), b.data());
        ref.compute(y, b_ref, scale);
        const auto probe = deformed(model, 0.6 * amplitude);
        const double expected = ref.strain_energy(probe);
        EXPECT_NEAR(eval->strain_energy(probe.data()), expected,
                    energy_tolerance(combo) * expected);
      }
    }
  }
}

TEST(ForceKernel, PlasticStrainEnergyIsThePotentialOfTheForceExact) {
  check_plastic_energy(StretchKind::exact);
}
TEST(ForceKernel, PlasticStrainEnergyIsThePotentialOfTheForceModified) {
  check_plastic_energy(StretchKind::modified);
}
TEST(ForceKernel, PlasticStrainEnergyIsThePotentialOfTheForceFast) {
  check_plastic_energy(StretchKind::fast);
}

TEST(ForceKernel, ForceIsMinusTheGradientOfTheStrainEnergy) {
  // Elastic bonds: b_i V_i = −∂U/∂y_i, checked by central differences on a few particles.
  for (StretchKind stretch : {StretchKind::exact, StretchKind::modified, StretchKind::fast}) {
    for (bool per_bond : {false, true}) {
      const Combo combo{stretch, false, false, per_bond};
      SCOPED_TRACE(combo.label());
      pd::Model model = pd::build_model(spec_for(combo));
      auto eval = pd::make_force_evaluator(model);
      auto y = deformed(model, 3.0);
      std::vector<double> b(y.size());
      eval->compute(y.data(), b.data());
      for (std::size_t i : {std::size_t{0}, std::size_t{17}, model.size() - 1}) {
        for (int c = 0; c < 3; ++c) {
          const double h = 1e-7;
          const double keep = y[3 * i + c];
          y[3 * i + c] = keep + h;
          const double up = eval->strain_energy(y.data());
          y[3 * i + c] = keep - h;
          const double down = eval->strain_energy(y.data());
          y[3 * i + c] = keep;
          const double grad = (up - down) / (2 * h);
          const double f = b[3 * i + c] * model.particles.volume[i];
          EXPECT_NEAR(-grad, f,
                      1e-5 * std::abs(f) +
                          1e-9 * pd::bond_stiffness(model, 0) * model.particles.volume[i])
              << "particle " << i << " component " << c;
        }
      }
    }
  }
}

TEST(ForceKernel, DescriptionNamesThePolicies) {
  for (const Combo& combo : all_combos()) {
    pd::Model model = pd::build_model(spec_for(combo));
    const std::string d = pd::make_force_evaluator(model)->description();
    SCOPED_TRACE(d);
    EXPECT_NE(d.find("stretch=" + pd::to_string(combo.stretch)), std::string::npos);
    EXPECT_NE(d.find(combo.plasticity ? "law=plastic" : "law=elastic"), std::string::npos);
    EXPECT_NE(d.find(combo.damage ? "damage=on" : "damage=off"), std::string::npos);
    EXPECT_NE(d.find(combo.per_bond ? "field=per-bond" : "field=uniform"), std::string::npos);
  }
}

TEST(ForceKernel, MissingStateIsRejected) {
  const Combo combo{StretchKind::exact, true, true, false};
  pd::Model model = pd::build_model(spec_for(combo));
  pd::Model no_damage = model;
  no_damage.state.broken.clear();
  EXPECT_THROW(pd::make_force_evaluator(no_damage), std::logic_error);
  pd::Model no_plastic = model;
  no_plastic.state.plastic_stretch.clear();
  EXPECT_THROW(pd::make_force_evaluator(no_plastic), std::logic_error);
  pd::Model no_field = model;
  no_field.effects.per_bond_field = true;
  EXPECT_THROW(pd::make_force_evaluator(no_field), std::logic_error);
}

TEST(ForceKernel, BrokenBondsStayBroken) {
  // eq. 10: μ = 0 once s ≥ s0 at any earlier time, even after the bond is compressed again.
  const Combo combo{StretchKind::exact, false, true, false};
  pd::Model model = pd::build_model(spec_for(combo));
  auto eval = pd::make_force_evaluator(model);
  std::vector<double> b(3 * model.size());
  eval->compute(deformed(model, 1.0).data(), b.data());
  const auto broken = model.state.broken;
  const std::size_t count = static_cast<std::size_t>(std::count(broken.begin(), broken.end(), 1));
  ASSERT_GT(count, 0u);
  eval->compute(reference_positions(model).data(), b.data());
  EXPECT_EQ(model.state.broken, broken);
  // In the reference configuration the broken bonds are simply absent: forces stay zero.
  for (double v : b) {
    EXPECT_LE(std::abs(v), 1e-12 * pd::bond_stiffness(model, 0) * 32);
  }
  // The two directions of every bond agree.
  const auto rev = pd::reverse_bond_index(model.family);
  for (std::size_t k = 0; k < broken.size(); ++k) {
    EXPECT_EQ(broken[k], broken[rev[k]]);
  }
}

} // namespace
