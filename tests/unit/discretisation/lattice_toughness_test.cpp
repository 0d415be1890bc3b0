// The toughness ratio of the lattice (model.hpp, lattice_toughness.cpp) and how s0 takes it.
#include "libpd/discretisation/model.hpp"
#include "libpd/io/scene.hpp"

#include <algorithm>
#include <cmath>
#include <gtest/gtest.h>
#include <string>

namespace {

pd::ModelSpec two_dimensional(pd::PlaneMode plane, pd::VolumeCorrection volume) {
  pd::ModelSpec spec;
  spec.dimension.dim = 2;
  spec.dimension.plane = plane;
  spec.volume_correction = volume;
  return spec;
}

// The K field differs between plane stress and plane strain (κ, μ, E') exactly as the bond-based
// model's constants do (c, s0, ν), so the lattice must trap a crack by the same factor in both:
// a mismatch would mean the boundary-layer problem or the constants are inconsistent.
TEST(LatticeToughness, PlaneStressAndPlaneStrainTrapACrackAlike) {
  // `gradient` only: the weights without a cut-off keep bonds to 3.5λ, and their boundary-layer
  // problem takes seconds (the report's sweeps run them).
  for (const auto volume : {pd::VolumeCorrection::gradient}) {
    const double stress =
        pd::lattice_toughness_ratio_in(two_dimensional(pd::PlaneMode::plane_stress, volume));
    const double strain =
        pd::lattice_toughness_ratio_in(two_dimensional(pd::PlaneMode::plane_strain, volume));
    EXPECT_NEAR(strain / stress, 1.0, 1e-3) << pd::to_string(volume);
    // A lattice of brittle bonds is tougher than the energy of its crossing bonds, never weaker.
    EXPECT_GT(stress, 1.0) << pd::to_string(volume);
  }
}

// The acceptance of issue 36 asks that switching the volume treatment moves a failure stress by at
// most 5 %. The ratio sets the failure stress in proportion, so the documented treatments' ratios
// (none, moment, gradient) must lie within that of each other. A crack held to one row (the first
// version of this calculation) trapped `none` 10 % more than `gradient`; free to zig-zag, they
// differ by 2 %.
TEST(LatticeToughness, TheThreeVolumeWeightingsTrapACrackWithinFivePercentOfEachOther) {
  double lowest = INFINITY, highest = 0;
  for (const auto volume :
       {pd::VolumeCorrection::gradient, pd::VolumeCorrection::none, pd::VolumeCorrection::moment}) {
    const double ratio =
        pd::lattice_toughness_ratio_in(two_dimensional(pd::PlaneMode::plane_stress, volume));
    lowest = std::min(lowest, ratio);
    highest = std::max(highest, ratio);
  }
  EXPECT_LT(highest / lowest, 1.05);
}

TEST(LatticeToughness, NotDerivedInOneDimension) {
  pd::ModelSpec spec;
  spec.dimension.dim = 1;
  EXPECT_FALSE(pd::lattice_toughness_ratio(spec).has_value());
}

// In 3D the front is a straight line of columns in plane strain; every bond of the cubic
// lattice's stencil joins two columns. A lattice of brittle bonds traps the front as the square
// lattice traps a 2D crack, never below the energy of its crossing bonds, and by a factor of the
// same kind (the 2D default is 1.14): far from 1 would mean the projection is wrong.
TEST(LatticeToughness, AThreeDimensionalFrontIsTrapped) {
  pd::ModelSpec spec;
  spec.dimension.dim = 3;
  const auto ratio = pd::lattice_toughness_ratio(spec);
  ASSERT_TRUE(ratio.has_value());
  EXPECT_GT(*ratio, 1.0);
  EXPECT_LT(*ratio, 1.3);
  // the cache is keyed by dimension: the 2D factor is not the 3D one
  spec.dimension.dim = 2;
  EXPECT_NE(*pd::lattice_toughness_ratio(spec), *ratio);
}

std::string plate(const std::string& model_keys) {
  return "dimension: 2\nplane: stress\nthickness: 0.001\nlattice: {spacing: 0.002}\n"
         "materials:\n  glass: {youngs_modulus: 72e9, density: 2500, fracture_energy: 10}\n"
         "bodies:\n  - {name: plate, material: glass, box: [[0, 0], [0.04, 0.02]]}\n"
         "supports:\n  - {name: left, box: [[0, 0], [0.002, 0.02]], fixed: [x, y]}\n"
         "effects: [damage]\n" +
         model_keys + "solver: {integrator: adr, end_time: 1}\n";
}

// The scene's s0 is the energy-derived value divided by the lattice's ratio, for the defaults and
// for another surface treatment alike.
TEST(LatticeToughness, TheCriticalStretchOfAPlaneStressSceneIsDividedByTheRatio) {
  for (const std::string& keys :
       {std::string{}, std::string{"model: {surface_correction: tensor}\n"}}) {
    const pd::Scene scene = pd::parse_scene(plate(keys), "plate");
    const pd::Model model = pd::build_model(scene);
    const double energy = pd::critical_stretch_from_fracture_energy(
        model.spec.dimension, 72e9, model.spec.lattice.horizon(), 10);
    const double ratio = *pd::lattice_toughness_ratio(model.spec);
    ASSERT_FALSE(model.field.bond_critical_stretch.empty()) << keys;
    EXPECT_NEAR(model.field.bond_critical_stretch.front(), energy / ratio, 1e-12 * energy) << keys;
  }
}

std::string slab() {
  return "dimension: 3\nlattice: {spacing: 0.002}\n"
         "materials:\n  glass: {youngs_modulus: 72e9, density: 2500, fracture_energy: 10}\n"
         "bodies:\n  - {name: slab, material: glass, box: [[0, 0, 0], [0.02, 0.01, 0.01]]}\n"
         "supports:\n  - {name: left, box: [[0, 0, 0], [0.002, 0.01, 0.01]], fixed: [x, y, z]}\n"
         "effects: [damage]\nsolver: {integrator: adr, end_time: 1}\n";
}

TEST(LatticeToughness, TheCriticalStretchOfAThreeDimensionalSceneIsDividedByTheRatio) {
  const pd::Scene scene = pd::parse_scene(slab(), "slab");
  const pd::Model model = pd::build_model(scene);
  const double energy = pd::critical_stretch_from_fracture_energy(model.spec.dimension, 72e9,
                                                                  model.spec.lattice.horizon(), 10);
  const double ratio = *pd::lattice_toughness_ratio(model.spec);
  ASSERT_FALSE(model.field.bond_critical_stretch.empty());
  EXPECT_NEAR(model.field.bond_critical_stretch.front(), energy / ratio, 1e-12 * energy);
}

} // namespace
