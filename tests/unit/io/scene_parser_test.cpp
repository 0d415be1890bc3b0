// Scene parser: every class of bad input is reported as a SceneError at the offending node, valid
// scenes fill every field, and the generated template is itself a valid scene.
#include "libpd/discretisation/model.hpp"
#include "libpd/io/scene.hpp"
#include "scene_test_support.hpp"

#include <chrono>
#include <filesystem>
#include <fstream>
#include <gtest/gtest.h>
#include <sstream>
#include <string>
#include <vector>

namespace {

// The smallest valid scene, for reference (1D keeps the scenes short):
constexpr const char* minimal = R"(
dimension: 1
lattice:
  spacing: 0.1
materials:
  m:
    youngs_modulus: 1e9
    density: 1000
bodies:
  - name: bar
    material: m
    box: [[0], [1]]
solver:
  end_time: 1
)";

TEST(SceneParser, MinimalSceneParses) {
  const pd::Scene s = pd::parse_scene(yaml(minimal), "s.yaml");
  EXPECT_EQ(s.model.dimension.dim, 1);
  ASSERT_EQ(s.model.bodies.size(), 1u);
  EXPECT_TRUE(s.warnings.empty());
}

// A bond-based material without ν takes the one the model represents (1/3 in plane stress,
// 1/4 in plane strain and 3D), so that an FE solution of the same scene solves the same
// material; the virtual-fibre model honours ν and keeps the material's own default.
TEST(SceneParser, BondBasedMaterialWithoutPoissonRatioTakesTheRepresentedOne) {
  auto with = [](const std::string& dims, const std::string& model) {
    std::string text = std::string(minimal);
    text.replace(text.find("dimension: 1\n"), 13, dims);
    text.replace(text.find("box: [[0], [1]]"), 15, "box: [[0, 0, 0], [1, 1, 1]]");
    const std::string full = text + model;
    return pd::parse_scene(yaml(full.c_str()), "s.yaml").model.materials.at(0).poisson_ratio;
  };
  EXPECT_DOUBLE_EQ(with("dimension: 2\nplane: stress\nthickness: 0.1\n", ""), 1.0 / 3.0);
  EXPECT_DOUBLE_EQ(with("dimension: 2\nplane: strain\nthickness: 0.1\n", ""), 0.25);
  EXPECT_DOUBLE_EQ(with("dimension: 3\n", ""), 0.25);
  EXPECT_DOUBLE_EQ(with("dimension: 2\nplane: stress\nthickness: 0.1\n",
                        "model:\n  bond_model: virtual-fibres\n"),
                   pd::Material{}.poisson_ratio);
}

// ---- Syntax and structure ---------------------------------------------------------------------

TEST(SceneParser, MalformedYamlUnclosedBracket) {
  EXPECT_TRUE(fails_at(yaml(R"(
dimension: 1
lattice: {spacing: 0.1
materials:
)"),
                       3, 10, "a '{' is not closed"));
}

TEST(SceneParser, MalformedYamlBadIndentation) {
  EXPECT_TRUE(fails_at(yaml(R"(
dimension: 1
lattice:
  spacing: 0.1
   horizon_factor: 3
)"),
                       4, 18, "malformed YAML"));
}

TEST(SceneParser, EmptyFile) {
  EXPECT_TRUE(fails_at("", 1, 1, "the scene is empty"));
}

TEST(SceneParser, SecondDocument) {
  EXPECT_TRUE(fails_at(yaml(minimal) + "---\ndimension: 2\n", 15, 1, "second one"));
}

TEST(SceneParser, UnknownKeySuggestsTheClosestOne) {
  EXPECT_TRUE(fails_at(yaml(R"(
dimension: 1
lattice:
  spacng: 0.1
)"),
                       3, 3, "unknown key 'spacng' in 'lattice'\n  hint: did you mean 'spacing'?"));
}

TEST(SceneParser, UnknownKeyInListItem) {
  EXPECT_TRUE(fails_at(yaml(R"(
dimension: 1
lattice:
  spacing: 0.1
materials:
  m:
    youngs_modulus: 1e9
    density: 1000
bodies:
  - name: bar
    material: m
    box: [[0], [1]]
    colour: red
solver:
  end_time: 1
)"),
                       12, 5, "unknown key 'colour' in body 'bar'"));
}

TEST(SceneParser, UnknownKeyThatBelongsToAnotherSection) {
  EXPECT_TRUE(fails_at(yaml(minimal) + "damping: 5\n", 14, 1, "belongs under 'solver'"));
}

TEST(SceneParser, DuplicateKey) {
  EXPECT_TRUE(fails_at(yaml(R"(
dimension: 1
lattice:
  spacing: 0.1
  spacing: 0.2
)"),
                       4, 3, "duplicate key 'spacing'"));
}

TEST(SceneParser, WrongTypeStringForNumber) {
  EXPECT_TRUE(fails_at(yaml(R"(
dimension: 1
lattice:
  spacing: abc
)"),
                       3, 12, "'lattice.spacing' must be a number [m], got 'abc'"));
}

TEST(SceneParser, WrongTypeQuotedNumber) {
  EXPECT_TRUE(fails_at(yaml(R"(
dimension: 1
lattice:
  spacing: "0.1"
)"),
                       3, 12, "remove the quotes"));
}

TEST(SceneParser, WrongTypeListForNumber) {
  EXPECT_TRUE(fails_at(yaml(R"(
dimension: 1
lattice:
  spacing: 0.1
materials:
  m:
    youngs_modulus: 1e9
    density: [1000]
)"),
                       7, 14, "'density' of material 'm' must be a number [kg/m³], got a list"));
}

TEST(SceneParser, WrongTypeScalarForList) {
  EXPECT_TRUE(fails_at(yaml(R"(
dimension: 1
lattice:
  spacing: 0.1
materials:
  m:
    youngs_modulus: 1e9
    density: 1000
bodies: bar
solver:
  end_time: 1
)"),
                       8, 9, "'bodies' must be a list, got 'bar'"));
}

TEST(SceneParser, WrongTypeNonIntegerCount) {
  EXPECT_TRUE(fails_at(yaml(minimal) + "  max_steps: 2.5\n", 14, 14, "must be an integer"));
}

TEST(SceneParser, MissingRequiredFieldPointsAtEnclosingMap) {
  EXPECT_TRUE(fails_at(yaml(R"(
dimension: 1
lattice:
  spacing: 0.1
materials:
  m:
    youngs_modulus: 1e9
bodies:
  - name: bar
    material: m
    box: [[0], [1]]
solver:
  end_time: 1
)"),
                       6, 5, "missing required key 'density' in material 'm'"));
}

TEST(SceneParser, MissingDimension) {
  EXPECT_TRUE(fails_at(yaml(R"(
lattice:
  spacing: 0.1
)"),
                       1, 1, "missing required key 'dimension' at the top level"));
}

TEST(SceneParser, MissingBoxOfBody) {
  EXPECT_TRUE(fails_at(yaml(R"(
dimension: 1
lattice:
  spacing: 0.1
materials:
  m:
    youngs_modulus: 1e9
    density: 1000
bodies:
  - name: bar
    material: m
solver:
  end_time: 1
)"),
                       9, 5,
                       "missing 'box', 'boxes', 'cylinder', 'sphere', 'particles', 'mesh', "
                       "'geometry' or 'graded' in "
                       "body 'bar'"));
}

TEST(SceneParser, BoxAndBoxesTogether) {
  EXPECT_TRUE(fails_at(yaml(R"(
dimension: 1
lattice:
  spacing: 0.1
materials:
  m:
    youngs_modulus: 1e9
    density: 1000
bodies:
  - name: bar
    material: m
    box: [[0], [1]]
    boxes: [[[0], [1]]]
solver:
  end_time: 1
)"),
                       12, 5, "'box' and 'boxes' are alternatives"));
}

TEST(SceneParser, UnknownEnumValue) {
  EXPECT_TRUE(
      fails_at(yaml(minimal) + "model:\n  stretch: fastest\n", 15, 12,
               "unknown value 'fastest' for 'model.stretch'\n  hint: did you mean 'fast'?"));
}

TEST(SceneParser, UnknownMirrorCoupling) {
  EXPECT_TRUE(fails_at(yaml(minimal) + "model:\n  mirror_coupling: consistant\n", 15, 20,
                       "unknown value 'consistant' for 'model.mirror_coupling'\n  hint: did you "
                       "mean 'consistent'?"));
}

TEST(SceneParser, MirrorCouplingDefaultsToQuadratic) {
  EXPECT_EQ(pd::parse_scene(yaml(minimal), "t").model.mirror_coupling,
            pd::MirrorCoupling::quadratic);
  EXPECT_EQ(pd::parse_scene(yaml(minimal) + "model:\n  mirror_coupling: consistent\n", "t")
                .model.mirror_coupling,
            pd::MirrorCoupling::consistent);
}

TEST(SceneParser, UnknownEffect) {
  EXPECT_TRUE(fails_at(yaml(minimal) + "effects: [damage, cracking]\n", 14, 19,
                       "unknown value 'cracking'"));
}

TEST(SceneParser, InvalidDimension) {
  EXPECT_TRUE(fails_at("dimension: 4\n", 1, 12, "'dimension' must be in [1, 3]"));
}

TEST(SceneParser, PointWithTooFewCoordinates) {
  EXPECT_TRUE(fails_at(yaml(R"(
dimension: 3
lattice:
  spacing: 0.1
materials:
  m:
    youngs_modulus: 1e9
    density: 1000
bodies:
  - name: bar
    material: m
    box: [[0, 0], [1, 1, 1]]
)"),
                       11, 11, "has 2 coordinates; a 3D scene needs 3"));
}

TEST(SceneParser, ComponentBeyondDimension) {
  EXPECT_TRUE(fails_at(yaml(minimal) + "supports:\n  - name: s\n    box: [[0], [0.2]]\n"
                                       "    fixed: [x, y]\n",
                       17, 16, "component 'y' does not exist in a 1D scene"));
}

// ---- Non-physical values ----------------------------------------------------------------------

TEST(SceneParser, NonPositiveYoungsModulus) {
  EXPECT_TRUE(fails_at(yaml(R"(
dimension: 1
lattice:
  spacing: 0.1
materials:
  m:
    youngs_modulus: 0
    density: 1000
)"),
                       6, 21, "'youngs_modulus' of material 'm' must be > 0 [Pa], got 0"));
}

TEST(SceneParser, NonPositiveDensity) {
  EXPECT_TRUE(fails_at(yaml(R"(
dimension: 1
lattice:
  spacing: 0.1
materials:
  m:
    youngs_modulus: 1e9
    density: -1
)"),
                       7, 14, "must be > 0 [kg/m³], got -1"));
}

TEST(SceneParser, NonPositiveSpacing) {
  EXPECT_TRUE(fails_at(yaml(R"(
dimension: 1
lattice:
  spacing: 0
)"),
                       3, 12, "'lattice.spacing' must be > 0 [m], got 0"));
}

TEST(SceneParser, HorizonBelowOneSpacing) {
  EXPECT_TRUE(fails_at(yaml(R"(
dimension: 1
lattice:
  spacing: 0.1
  horizon_factor: 0.9
)"),
                       4, 19, "a horizon below one spacing"));
}

TEST(SceneParser, PoissonRatioOutsideOpenInterval) {
  const char* text = R"(
dimension: 1
lattice:
  spacing: 0.1
materials:
  m:
    youngs_modulus: 1e9
    poisson_ratio: %
    density: 1000
)";
  for (const char* nu : {"0.5", "-1", "0.7"}) {
    std::string s = yaml(text);
    s.replace(s.find('%'), 1, nu);
    EXPECT_TRUE(fails_at(s, 7, 20, "must be in (-1, 0.5)")) << nu;
  }
}

TEST(SceneParser, NegativeDamping) {
  EXPECT_TRUE(fails_at(yaml(minimal) + "  damping: -1\n", 14, 12, "must be ≥ 0"));
}

TEST(SceneParser, NegativeRampTime) {
  EXPECT_TRUE(fails_at(yaml(minimal) + "  ramp_time: -0.1\n", 14, 14, "must be ≥ 0 [s]"));
}

TEST(SceneParser, SafetyOutsideUnitInterval) {
  EXPECT_TRUE(fails_at(yaml(minimal) + "  safety: 1.5\n", 14, 11, "must be in (0, 1]"));
  EXPECT_TRUE(fails_at(yaml(minimal) + "  safety: 0\n", 14, 11, "must be in (0, 1]"));
}

TEST(SceneParser, NanValue) {
  EXPECT_TRUE(fails_at(yaml(R"(
dimension: 1
lattice:
  spacing: .nan
)"),
                       3, 12, "is not a finite number (got .nan)"));
}

TEST(SceneParser, InfiniteValue) {
  EXPECT_TRUE(fails_at(yaml(minimal) + "  ramp_time: .inf\n", 14, 14, "not a finite number"));
  EXPECT_TRUE(
      fails_at(yaml(minimal) + "initial:\n  velocity: [-.Inf]\n", 15, 14, "not a finite number"));
}

TEST(SceneParser, BoxWithLoAboveHi) {
  EXPECT_TRUE(fails_at(yaml(R"(
dimension: 1
lattice:
  spacing: 0.1
materials:
  m:
    youngs_modulus: 1e9
    density: 1000
bodies:
  - name: bar
    material: m
    box: [[1], [0]]
)"),
                       11, 10, "has lo > hi in x"));
}

// ---- Empty regions ----------------------------------------------------------------------------

TEST(SceneParser, BodyWithoutLatticePoint) {
  // Cell centres are at 0.05, 0.15, ...: none lies in [0.12, 0.13].
  EXPECT_TRUE(fails_at(yaml(R"(
dimension: 1
lattice:
  spacing: 0.1
materials:
  m:
    youngs_modulus: 1e9
    density: 1000
bodies:
  - name: bar
    material: m
    box: [[0.12], [0.13]]
solver:
  end_time: 1
)"),
                       11, 10, "body 'bar' contains no lattice point"));
}

TEST(SceneParser, SupportOutsideEveryBody) {
  // [2, 3] holds lattice points, but none of a body.
  EXPECT_TRUE(fails_at(yaml(minimal) + R"(supports:
  - name: clamp
    box: [[2], [3]]
    fixed: [x]
)",
                       16, 10, "support 'clamp' selects no particle"));
}

TEST(SceneParser, LoadOnNoParticle) {
  EXPECT_TRUE(fails_at(yaml(minimal) + R"(loads:
  - name: pull
    boxes: [[[1.5], [2]], [[-1], [-0.5]]]
    value: [1]
)",
                       16, 12, "load 'pull' acts on no particle"));
}

TEST(SceneParser, ProbeRegionOnNoParticle) {
  EXPECT_TRUE(fails_at(yaml(minimal) + R"(probes:
  - name: p
    box: [[0.41], [0.42]]
)",
                       16, 10, "probe 'p' averages over no particle"));
}

TEST(SceneParser, ProbePointFarFromEveryBody) {
  EXPECT_TRUE(fails_at(yaml(minimal) + R"(probes:
  - name: near
    point: [1.05]
  - name: far
    point: [1.2]
)",
                       18, 12, "probe 'far' is 0.2 m from the nearest body"));
}

constexpr const char* two_bodies = R"(
dimension: 1
lattice:
  spacing: 0.1
materials:
  a:
    youngs_modulus: 1e9
    density: 1000
  b:
    youngs_modulus: 2e9
    density: 1000
bodies:
  - name: left
    material: a
    box: [[0], [1]]
  - name: right
    material: %
    box: [[%], [2]]
solver:
  end_time: 1
)";

std::string two_bodies_scene(const std::string& material, const std::string& start) {
  std::string s = yaml(two_bodies);
  s.replace(s.find('%'), 1, material);
  s.replace(s.find('%'), 1, start);
  return s;
}

TEST(SceneParser, OverlappingBodiesWithDifferentMaterials) {
  EXPECT_TRUE(fails_at(two_bodies_scene("b", "0.5"), 17, 10,
                       "bodies 'left' and 'right' overlap but have different materials"));
  // Touching boxes share no cell centre, and equal materials may overlap.
  EXPECT_NO_THROW(pd::parse_scene(two_bodies_scene("b", "1"), "s.yaml"));
  EXPECT_NO_THROW(pd::parse_scene(two_bodies_scene("a", "0.5"), "s.yaml"));
}

// ---- Consistency between sections -------------------------------------------------------------

TEST(SceneParser, DamageWithoutCriticalStretch) {
  EXPECT_TRUE(fails_at(yaml(minimal) + "effects: [damage]\n", 5, 3,
                       "material 'm' has neither fracture_energy nor critical_stretch"));
}

TEST(SceneParser, FractureEnergyAndCriticalStretchTogether) {
  EXPECT_TRUE(fails_at(yaml(R"(
dimension: 1
lattice:
  spacing: 0.1
materials:
  m:
    youngs_modulus: 1e9
    density: 1000
    fracture_energy: 100
    critical_stretch: 1e-3
)"),
                       9, 5, "'fracture_energy' and 'critical_stretch' are alternatives"));
}

TEST(SceneParser, PlasticityWithoutYieldStretch) {
  EXPECT_TRUE(fails_at(yaml(minimal) + "effects: [plasticity]\n", 5, 3,
                       "material 'm' has no yield_stretch"));
}

TEST(SceneParser, DampingWithoutDampingEffect) {
  EXPECT_TRUE(
      fails_at(yaml(minimal) + "  damping: 100\n", 14, 12, "the 'damping' effect is not listed"));
}

TEST(SceneParser, DampingEffectWithoutDamping) {
  EXPECT_TRUE(fails_at(yaml(minimal) + "effects: [damping]\n", 14, 11,
                       "effect 'damping' is listed but 'solver.damping' is 0"));
}

TEST(SceneParser, UndampedIntegratorWithDamping) {
  for (const char* integrator : {"verlet", "euler-cromer"}) {
    EXPECT_TRUE(fails_at(yaml(minimal) + "  integrator: " + integrator +
                             "\n  damping: 100\neffects: [damping]\n",
                         14, 15, "has no damping"))
        << integrator;
  }
}

TEST(SceneParser, NeitherEndTimeNorSteady) {
  std::string s = yaml(minimal);
  s.replace(s.find("end_time: 1"), 11, "ramp_time: 0");
  EXPECT_TRUE(fails_at(s, 13, 3, "neither 'solver.end_time' nor 'solver.steady'"));
  s.erase(s.find("solver:"));
  EXPECT_TRUE(fails_at(s, 1, 1, "neither 'solver.end_time' nor 'solver.steady'"));
  // An empty steady section is enough.
  EXPECT_NO_THROW(pd::parse_scene(s + "solver:\n  steady:\n", "s.yaml"));
}

TEST(SceneParser, DuplicateNames) {
  std::string bodies = yaml(minimal);
  bodies.insert(bodies.find("solver:"), "  - name: bar\n    material: m\n    box: [[0], [1]]\n");
  EXPECT_TRUE(fails_at(bodies, 12, 11, "duplicate body name 'bar'"));
  EXPECT_TRUE(fails_at(yaml(minimal) + R"(supports:
  - name: s
    box: [[0], [0.2]]
    fixed: [x]
  - name: s
    box: [[0], [0.2]]
    fixed: [x]
)",
                       18, 11, "duplicate support name 's'"));
  EXPECT_TRUE(fails_at(yaml(minimal) + R"(loads:
  - name: l
    box: [[0], [0.2]]
    value: [1]
  - name: l
    box: [[0], [0.2]]
    value: [1]
)",
                       18, 11, "duplicate load name 'l'"));
  EXPECT_TRUE(fails_at(yaml(minimal) + R"(probes:
  - name: p
    point: [0.5]
  - name: p
    point: [0.5]
)",
                       17, 11, "duplicate probe name 'p'"));
}

TEST(SceneParser, BodyNamesUnknownMaterial) {
  std::string s = yaml(minimal);
  s.replace(s.find("material: m"), 11, "material: n");
  EXPECT_TRUE(fails_at(s, 10, 15, "body 'bar' names unknown material 'n'"));
  s = yaml(minimal);
  s.replace(s.find("  m:"), 4, "  steel:");
  s.replace(s.find("material: m"), 11, "material: stel");
  EXPECT_TRUE(fails_at(s, 10, 15, "did you mean 'steel'?"));
}

TEST(SceneParser, LoadMeasureRules) {
  EXPECT_TRUE(fails_at(yaml(minimal) + R"(loads:
  - name: p
    box: [[0.9], [1]]
    type: per_area
    value: [1]
)",
                       15, 5, "needs 'measure'"));
  EXPECT_TRUE(fails_at(yaml(minimal) + R"(loads:
  - name: p
    box: [[0.9], [1]]
    value: [1]
    measure: 0.01
)",
                       18, 5, "applies only to per_area and per_length loads"));
}

TEST(SceneParser, SupportBothFixedAndDisplaced) {
  EXPECT_TRUE(fails_at(yaml(minimal) + R"(supports:
  - name: s
    box: [[0], [0.2]]
    fixed: [x]
    displacement: {x: 0.1}
)",
                       18, 20, "both fixes and displaces component x"));
}

TEST(SceneParser, OutOfPlaneLoadIn2D) {
  EXPECT_TRUE(fails_at(yaml(R"(
dimension: 2
lattice:
  spacing: 0.1
materials:
  m:
    youngs_modulus: 1e9
    density: 1000
bodies:
  - name: plate
    material: m
    box: [[0, 0], [1, 1]]
loads:
  - name: p
    box: [[0.9, 0], [1, 1]]
    value: [1, 0, 5]
solver:
  end_time: 1
)"),
                       15, 12, "non-zero z component in a 2D scene"));
}

// ---- Warnings ---------------------------------------------------------------------------------

TEST(SceneParser, PoissonRatioWarningIn3D) {
  const pd::Scene s = pd::parse_scene(yaml(R"(
dimension: 3
lattice:
  spacing: 0.1
materials:
  m:
    youngs_modulus: 1e9
    poisson_ratio: 0.3
    density: 1000
bodies:
  - name: b
    material: m
    box: [[0, 0, 0], [1, 1, 1]]
solver:
  end_time: 1
)"),
                                      "s.yaml");
  ASSERT_EQ(s.warnings.size(), 1u);
  EXPECT_EQ(s.warnings[0],
            "s.yaml:7:20: warning: bond-based PD fixes ν = 1/4 here; E is matched (in 3D that "
            "equals matching the bulk modulus, Miranda eq. 8); ν = 0.3 is not represented");
  EXPECT_DOUBLE_EQ(s.model.materials[0].poisson_ratio, 0.3);
}

TEST(SceneParser, PoissonRatioWarningInPlaneStressButNotIn1D) {
  const pd::Scene plane = pd::parse_scene(yaml(R"(
dimension: 2
plane: stress
lattice:
  spacing: 0.1
materials:
  m:
    youngs_modulus: 1e9
    poisson_ratio: 0.25
    density: 1000
bodies:
  - name: b
    material: m
    box: [[0, 0], [1, 1]]
solver:
  end_time: 1
)"),
                                          "s.yaml");
  ASSERT_EQ(plane.warnings.size(), 1u);
  EXPECT_NE(plane.warnings[0].find("s.yaml:8:20: warning: bond-based PD fixes ν = 1/3 here"),
            std::string::npos)
      << plane.warnings[0];

  std::string one_d = yaml(minimal);
  one_d.insert(one_d.find("    density"), "    poisson_ratio: 0.3\n");
  EXPECT_TRUE(pd::parse_scene(one_d, "s.yaml").warnings.empty());
}

TEST(SceneParser, KeyOfAnotherDimensionIsIgnoredWithWarning) {
  const pd::Scene s = pd::parse_scene("thickness: 0.01\n" + yaml(minimal), "s.yaml");
  ASSERT_EQ(s.warnings.size(), 1u);
  EXPECT_EQ(s.warnings[0], "s.yaml:1:1: warning: 'thickness' applies only to 2D scenes and is "
                           "ignored in this 1D scene");
}

// ---- Valid scenes -----------------------------------------------------------------------------

TEST(SceneParser, FullSceneFillsEveryField) {
  const pd::Scene s = pd::parse_scene(yaml(R"(
title: "Block in tension"
dimension: 3
lattice:
  spacing: 0.01
  horizon_factor: 3.015
  convention: node-based
  origin: [1, 2, 3]
  horizon_rule: strict
  position_jitter: 0.1
  volume_variation: 0.2
  seed: 42
materials:
  steel:
    youngs_modulus: 200e9
    poisson_ratio: 0.25
    density: 7850
    fracture_energy: 100
    yield_stretch: 5e-4
    stiffness_factor: 2
  plate:
    youngs_modulus: 2e12
    density: 7000
    critical_stretch: 1e-3
    yield_stretch: 1e-3
bodies:
  - name: bar
    material: steel
    box: [[0, 0, 0], [1, 0.1, 0.1]]
  - name: grips
    material: plate
    boxes: [[[-0.03, 0, 0], [-0.01, 0.1, 0.1]], [[1.01, 0, 0], [1.03, 0.1, 0.1]]]
supports:
  - name: clamp
    box: [[-0.03, 0, 0], [-0.01, 0.1, 0.1]]
    fixed: [x, y]
    displacement: {z: -0.02}
loads:
  - name: pull
    box: [[1.01, 0, 0], [1.03, 0.1, 0.1]]
    type: per_area
    value: [2e6, 0, 1]
    measure: 0.01
  - name: gravity
    boxes: [[[0, 0, 0], [1, 0.1, 0.1]]]
    type: body
    value: [0, 0, -9.81e4]
effects: [damage, plasticity, damping]
model:
  stretch: fast
  surface_correction: macek-silling
  volume_correction: linear
  mirror_coupling: consistent
solver:
  integrator: damped-euler
  dt: 1e-6
  safety: 0.5
  end_time: 15
  ramp_time: 2
  damping: 1e5
  max_steps: 1000
  blowup_displacement: 0.5
  steady:
    kinetic_tolerance: 1e-9
    force_tolerance: 1e-5
    check_every: 50
initial:
  displacement_gradient: [[0.001, 0, 0], [0, 0.002, 0], [0, 0, 0.003]]
  about: [0.5, 0, 0]
  velocity: [1, 2, 3]
probes:
  - name: tip
    point: [1, 0.05, 0.05]
    component: y
  - name: end
    box: [[0.99, 0, 0], [1, 0.1, 0.1]]
    component: z
output:
  vtu: false
  vtu_every: 10
  history_every: 5
)"),
                                      "full.yaml");
  EXPECT_TRUE(s.warnings.empty());
  EXPECT_EQ(s.path, "");
  EXPECT_EQ(s.title, "Block in tension");

  const pd::ModelSpec& m = s.model;
  EXPECT_EQ(m.dimension.dim, 3);
  EXPECT_DOUBLE_EQ(m.lattice.spacing, 0.01);
  EXPECT_DOUBLE_EQ(m.lattice.horizon_factor, 3.015);
  EXPECT_EQ(m.lattice.convention, pd::LatticeConvention::node_based);
  EXPECT_EQ(m.lattice.origin, (pd::Vec3{1, 2, 3}));
  EXPECT_EQ(m.horizon_rule, pd::HorizonRule::strict);
  EXPECT_DOUBLE_EQ(m.lattice.position_jitter, 0.1);
  EXPECT_DOUBLE_EQ(m.lattice.volume_variation, 0.2);
  EXPECT_EQ(m.lattice.seed, 42u);

  ASSERT_EQ(m.materials.size(), 2u);
  const pd::Material& steel = m.materials[0];
  EXPECT_EQ(steel.name, "steel");
  EXPECT_DOUBLE_EQ(steel.youngs_modulus, 200e9);
  EXPECT_DOUBLE_EQ(steel.poisson_ratio, 0.25);
  EXPECT_DOUBLE_EQ(steel.density, 7850);
  EXPECT_EQ(steel.fracture_energy, 100.0);
  EXPECT_FALSE(steel.critical_stretch.has_value());
  EXPECT_EQ(steel.yield_stretch, 5e-4);
  EXPECT_DOUBLE_EQ(steel.stiffness_factor, 2);
  const pd::Material& plate = m.materials[1];
  EXPECT_EQ(plate.name, "plate");
  EXPECT_DOUBLE_EQ(plate.youngs_modulus, 2e12);
  EXPECT_DOUBLE_EQ(plate.poisson_ratio, 0.25);
  EXPECT_DOUBLE_EQ(plate.density, 7000);
  EXPECT_FALSE(plate.fracture_energy.has_value());
  EXPECT_EQ(plate.critical_stretch, 1e-3);
  EXPECT_EQ(plate.yield_stretch, 1e-3);
  EXPECT_DOUBLE_EQ(plate.stiffness_factor, 1);

  ASSERT_EQ(m.bodies.size(), 2u);
  EXPECT_EQ(m.bodies[0].name, "bar");
  EXPECT_EQ(m.bodies[0].material, 0);
  ASSERT_EQ(m.bodies[0].region.boxes.size(), 1u);
  EXPECT_EQ(m.bodies[0].region.boxes[0].lo, (pd::Vec3{0, 0, 0}));
  EXPECT_EQ(m.bodies[0].region.boxes[0].hi, (pd::Vec3{1, 0.1, 0.1}));
  EXPECT_EQ(m.bodies[1].name, "grips");
  EXPECT_EQ(m.bodies[1].material, 1);
  ASSERT_EQ(m.bodies[1].region.boxes.size(), 2u);
  EXPECT_EQ(m.bodies[1].region.boxes[1].lo, (pd::Vec3{1.01, 0, 0}));
  EXPECT_EQ(m.bodies[1].region.boxes[1].hi, (pd::Vec3{1.03, 0.1, 0.1}));

  ASSERT_EQ(m.supports.size(), 1u);
  EXPECT_EQ(m.supports[0].name, "clamp");
  EXPECT_EQ(m.supports[0].region.boxes.size(), 1u);
  EXPECT_EQ(m.supports[0].fixed, (std::array<bool, 3>{true, true, false}));
  EXPECT_EQ(m.supports[0].prescribed, (std::array<bool, 3>{false, false, true}));
  EXPECT_EQ(m.supports[0].displacement, (pd::Vec3{0, 0, -0.02}));

  ASSERT_EQ(m.loads.size(), 2u);
  EXPECT_EQ(m.loads[0].name, "pull");
  EXPECT_EQ(m.loads[0].load.kind, pd::BoxRegionLoad::Kind::per_area);
  EXPECT_EQ(m.loads[0].load.value, (pd::Vec3{2e6, 0, 1}));
  EXPECT_DOUBLE_EQ(m.loads[0].load.measure, 0.01);
  EXPECT_EQ(m.loads[0].load.region.boxes[0].lo, (pd::Vec3{1.01, 0, 0}));
  EXPECT_EQ(m.loads[1].name, "gravity");
  EXPECT_EQ(m.loads[1].load.kind, pd::BoxRegionLoad::Kind::body);
  EXPECT_EQ(m.loads[1].load.value, (pd::Vec3{0, 0, -9.81e4}));
  EXPECT_DOUBLE_EQ(m.loads[1].load.measure, 1);

  EXPECT_TRUE(m.effects.damage);
  EXPECT_TRUE(m.effects.plasticity);
  EXPECT_TRUE(m.effects.damping);
  // body_force is not read: build_model derives it from the loads (simulation_test).
  EXPECT_EQ(m.effects.stretch, pd::StretchKind::fast);
  EXPECT_EQ(m.surface_correction, pd::SurfaceCorrection::macek_silling);
  EXPECT_EQ(m.volume_correction, pd::VolumeCorrection::linear);
  EXPECT_EQ(m.mirror_coupling, pd::MirrorCoupling::consistent);

  const pd::SolverSpec& v = s.solver;
  EXPECT_EQ(v.integrator, pd::IntegratorKind::damped_euler);
  EXPECT_EQ(v.dt, 1e-6);
  EXPECT_DOUBLE_EQ(v.safety, 0.5);
  EXPECT_EQ(v.end_time, 15.0);
  EXPECT_DOUBLE_EQ(v.ramp_time, 2);
  EXPECT_DOUBLE_EQ(v.damping, 1e5);
  EXPECT_EQ(v.max_steps, 1000u);
  EXPECT_DOUBLE_EQ(v.blowup_displacement, 0.5);
  EXPECT_TRUE(v.steady.enabled);
  EXPECT_DOUBLE_EQ(v.steady.kinetic_tolerance, 1e-9);
  EXPECT_DOUBLE_EQ(v.steady.force_tolerance, 1e-5);
  EXPECT_EQ(v.steady.check_every, 50u);

  using Row = std::array<double, 3>;
  EXPECT_EQ(s.initial.displacement_gradient[0], (Row{0.001, 0, 0}));
  EXPECT_EQ(s.initial.displacement_gradient[1], (Row{0, 0.002, 0}));
  EXPECT_EQ(s.initial.displacement_gradient[2], (Row{0, 0, 0.003}));
  EXPECT_EQ(s.initial.about, (pd::Vec3{0.5, 0, 0}));
  EXPECT_EQ(s.initial.velocity, (pd::Vec3{1, 2, 3}));

  ASSERT_EQ(s.probes.size(), 2u);
  EXPECT_EQ(s.probes[0].name, "tip");
  EXPECT_EQ(s.probes[0].kind, pd::ProbeSpec::Kind::point);
  EXPECT_EQ(s.probes[0].point, (pd::Vec3{1, 0.05, 0.05}));
  EXPECT_EQ(s.probes[0].component, 1);
  EXPECT_EQ(s.probes[1].name, "end");
  EXPECT_EQ(s.probes[1].kind, pd::ProbeSpec::Kind::region);
  ASSERT_EQ(s.probes[1].region.boxes.size(), 1u);
  EXPECT_EQ(s.probes[1].region.boxes[0].lo, (pd::Vec3{0.99, 0, 0}));
  EXPECT_EQ(s.probes[1].component, 2);

  EXPECT_FALSE(s.output.vtu);
  EXPECT_EQ(s.output.vtu_every, 10u);
  EXPECT_EQ(s.output.history_every, 5u);
}

TEST(SceneParser, TwoDimensionalScene) {
  const pd::Scene s = pd::parse_scene(yaml(R"(
dimension: 2
plane: strain
thickness: 0.02
lattice:
  spacing: 0.1
materials:
  m:
    youngs_modulus: 1e9
    density: 1000
bodies:
  - name: plate
    material: m
    box: [[0, 0], [1, 1]]
supports:
  - name: edge
    box: [[0, 0, 0], [0.1, 1, 0]]
    fixed: [x, y]
probes:
  - name: corner
    point: [1, 1]
    component: y
solver:
  end_time: 1
  dt: auto
  max_steps: 1e8
)"),
                                      "s.yaml");
  EXPECT_EQ(s.model.dimension.dim, 2);
  EXPECT_EQ(s.model.dimension.plane, pd::PlaneMode::plane_strain);
  EXPECT_DOUBLE_EQ(s.model.dimension.thickness, 0.02);
  EXPECT_EQ(s.model.bodies[0].region.boxes[0].hi, (pd::Vec3{1, 1, 0}));
  EXPECT_EQ(s.probes[0].point, (pd::Vec3{1, 1, 0}));
  EXPECT_FALSE(s.solver.dt.has_value());
  EXPECT_EQ(s.solver.max_steps, 100000000u);
  EXPECT_FALSE(s.solver.steady.enabled);
  EXPECT_TRUE(s.warnings.empty());
}

TEST(SceneParser, TemplateIsAValidSceneWithTheLibraryDefaults) {
  const std::string text = pd::scene_template();
  const pd::Scene s = pd::parse_scene(text, "t");
  EXPECT_TRUE(s.warnings.empty());

  // The template writes the schema's defaults; they must be the structs' defaults.
  const pd::LatticeSpec lattice;
  EXPECT_EQ(s.model.lattice.horizon_factor, lattice.horizon_factor);
  EXPECT_EQ(s.model.lattice.convention, lattice.convention);
  EXPECT_EQ(s.model.lattice.seed, lattice.seed);
  EXPECT_EQ(s.model.horizon_rule, pd::ModelSpec{}.horizon_rule);
  const pd::Material material;
  EXPECT_EQ(s.model.materials[0].poisson_ratio, material.poisson_ratio);
  EXPECT_EQ(s.model.materials[0].stiffness_factor, material.stiffness_factor);
  const pd::SolverSpec solver;
  EXPECT_EQ(s.solver.integrator, solver.integrator);
  EXPECT_EQ(s.solver.dt, solver.dt);
  EXPECT_EQ(s.solver.safety, solver.safety);
  EXPECT_EQ(s.solver.ramp_time, solver.ramp_time);
  EXPECT_EQ(s.solver.damping, solver.damping);
  EXPECT_EQ(s.solver.max_steps, solver.max_steps);
  EXPECT_EQ(s.solver.blowup_displacement, solver.blowup_displacement);
  EXPECT_EQ(s.output.vtu, pd::OutputSpec{}.vtu);
  EXPECT_EQ(s.model.effects.stretch, pd::EffectSet{}.stretch);

  // Every key is listed, the optional ones commented out.
  for (const char* key :
       {"title:", "# plane:", "# thickness:", "# cross_section:", "position_jitter:",
        "# fracture_energy:", "# critical_stretch:", "# yield_stretch:", "# boxes:",
        "# displacement:", "# measure:", "effects:", "surface_correction:", "# steady:",
        "check_every:", "displacement_gradient:", "history_every:", "component:"}) {
    EXPECT_NE(text.find(key), std::string::npos) << key;
  }

  // With the commented keys switched on (one of each alternative), it is still a valid scene.
  std::string all = text;
  for (const char* key : {"# steady:", "#   kinetic_tolerance:", "#   force_tolerance:",
                          "#   check_every:", "# yield_stretch:", "# fracture_energy:"}) {
    const auto at = all.find(key);
    ASSERT_NE(at, std::string::npos) << key;
    all.erase(at, 2);
  }
  all.replace(all.find("effects: []"), 11, "effects: [damage, plasticity]");
  const pd::Scene on = pd::parse_scene(all, "t");
  EXPECT_TRUE(on.solver.steady.enabled);
  EXPECT_EQ(on.solver.steady.check_every, pd::SteadyStateCriterion{}.check_every);
  EXPECT_EQ(on.solver.steady.kinetic_tolerance, pd::SteadyStateCriterion{}.kinetic_tolerance);
  EXPECT_EQ(on.solver.steady.force_tolerance, pd::SteadyStateCriterion{}.force_tolerance);
  EXPECT_TRUE(on.model.materials[0].fracture_energy.has_value());
}

// ---- Files ------------------------------------------------------------------------------------

TEST(SceneParser, MissingFile) {
  try {
    pd::load_scene("/nonexistent/scene.yaml");
    FAIL() << "no error";
  } catch (const pd::SceneError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(
                  "/nonexistent/scene.yaml: error: the scene file cannot be opened", 0),
              0u)
        << e.what();
    EXPECT_EQ(e.mark().line, 0);
    EXPECT_NE(std::string(e.what()).find("\n  hint: "), std::string::npos);
  }
}

#ifdef PD_SCENES_DIR
TEST(SceneParser, DocumentedExampleParses) {
  const std::filesystem::path doc =
      std::filesystem::path(PD_SCENES_DIR) / ".." / ".." / "docs" / "scenes.md";
  std::ifstream in(doc);
  ASSERT_TRUE(in) << doc;
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string text = buffer.str();
  const std::string open = "<!-- example -->\n```yaml\n";
  const auto begin = text.find(open);
  const auto end = text.find("```\n<!-- /example -->");
  ASSERT_NE(begin, std::string::npos);
  ASSERT_NE(end, std::string::npos);
  const std::string example = text.substr(begin + open.size(), end - begin - open.size());
  const pd::Scene s = pd::parse_scene(example, "docs/scenes.md example");
  EXPECT_TRUE(s.warnings.empty());
  EXPECT_EQ(s.model.bodies.size(), 2u);
  EXPECT_TRUE(s.model.effects.damage && s.model.effects.plasticity && s.model.effects.damping);
}

TEST(SceneParser, ShippedScenesLoad) {
  // The shared scenes and those of the case folders (each folder's case.yaml is not a scene).
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(PD_SCENES_DIR)) {
    files.push_back(entry.path());
  }
  for (const auto& folder : std::filesystem::directory_iterator(PD_CASES_DIR)) {
    if (folder.is_directory()) {
      for (const auto& entry : std::filesystem::directory_iterator(folder.path())) {
        if (entry.path().filename() != "case.yaml") {
          files.push_back(entry.path());
        }
      }
    }
  }
  int count = 0;
  for (const auto& file : files) {
    if (file.extension() != ".yaml") {
      continue;
    }
    const std::string path = file.string();
    try {
      const pd::Scene s = pd::load_scene(path);
      EXPECT_EQ(s.path, path);
      ++count;
    } catch (const pd::SceneError& e) {
      ADD_FAILURE() << e.what();
    }
  }
  EXPECT_GT(count, 0);
}
#endif

// ---- Integrators: adr and arkode ----------------------------------------------------------------

TEST(SceneParser, ArkodeSectionParses) {
  if (!pd::arkode_available()) {
    GTEST_SKIP() << "built without SUNDIALS";
  }
  const pd::Scene s = pd::parse_scene(yaml(minimal) + R"(  integrator: arkode
  arkode:
    table: dormand-prince
    adaptive: true
    rtol: 1e-5
    atol: 1e-11
)",
                                      "s.yaml");
  EXPECT_EQ(s.solver.integrator, pd::IntegratorKind::arkode);
  EXPECT_EQ(s.solver.arkode.table, pd::ArkodeTable::dormand_prince);
  EXPECT_TRUE(s.solver.arkode.adaptive);
  EXPECT_EQ(s.solver.arkode.rtol, 1e-5);
  EXPECT_EQ(s.solver.arkode.atol, 1e-11);
  EXPECT_TRUE(s.warnings.empty());
  // Defaults are the struct's.
  const pd::Scene d =
      pd::parse_scene(yaml(minimal) + "  integrator: arkode\n  arkode:\n", "s.yaml");
  EXPECT_EQ(d.solver.arkode.table, pd::ArkodeSpec{}.table);
  EXPECT_EQ(d.solver.arkode.adaptive, pd::ArkodeSpec{}.adaptive);
  EXPECT_EQ(d.solver.arkode.rtol, pd::ArkodeSpec{}.rtol);
  EXPECT_EQ(d.solver.arkode.atol, pd::ArkodeSpec{}.atol);
}

TEST(SceneParser, ArkodeUnknownTable) {
  EXPECT_TRUE(fails_at(yaml(minimal) + "  integrator: arkode\n  arkode:\n    table: rk5\n", 16, 12,
                       "unknown value 'rk5'"));
}

TEST(SceneParser, ArkodeAdaptiveNeedsEmbedding) {
  if (!pd::arkode_available()) {
    GTEST_SKIP() << "built without SUNDIALS";
  }
  EXPECT_TRUE(fails_at(yaml(minimal) + "  integrator: arkode\n  arkode:\n    table: rk4\n"
                                       "    adaptive: true\n",
                       17, 15, "has no embedded method"));
}

TEST(SceneParser, ArkodeRejectsBondHistory) {
  if (!pd::arkode_available()) {
    GTEST_SKIP() << "built without SUNDIALS";
  }
  std::string s = yaml(minimal);
  s.replace(s.find("    density: 1000"), 17, "    density: 1000\n    critical_stretch: 0.01");
  EXPECT_TRUE(fails_at(s + "  integrator: arkode\neffects: [damage]\n", 15, 15,
                       "cannot run the 'damage' effect"));
}

TEST(SceneParser, SmallDisplacementsRefuseBondHistory) {
  std::string s = yaml(minimal);
  s.replace(s.find("    density: 1000"), 17, "    density: 1000\n    critical_stretch: 0.01");
  EXPECT_TRUE(fails_at(s + "  small_displacements: true\neffects: [damage]\n", 15, 24,
                       "cannot run the 'damage' effect"));
  EXPECT_TRUE(pd::parse_scene(yaml(minimal) + "  small_displacements: true\n", "s.yaml")
                  .solver.small_displacements);
}

TEST(SceneParser, ArkodeAcceptsDamping) {
  if (!pd::arkode_available()) {
    GTEST_SKIP() << "built without SUNDIALS";
  }
  const pd::Scene s = pd::parse_scene(
      yaml(minimal) + "  integrator: arkode\n  damping: 100\neffects: [damping]\n", "s.yaml");
  EXPECT_EQ(s.solver.damping, 100);
  EXPECT_TRUE(s.warnings.empty());
}

TEST(SceneParser, AdrIgnoresDampingWithAWarning) {
  const pd::Scene s = pd::parse_scene(
      yaml(minimal) + "  integrator: adr\n  damping: 100\neffects: [damping]\n", "s.yaml");
  EXPECT_EQ(s.solver.integrator, pd::IntegratorKind::adr);
  ASSERT_EQ(s.warnings.size(), 1u);
  EXPECT_NE(s.warnings[0].find("s.yaml:15:12: warning: 'solver.damping' is ignored by the adr"),
            std::string::npos)
      << s.warnings[0];
}

TEST(SceneParser, ArkodeSectionWithAnotherIntegratorWarns) {
  const pd::Scene s = pd::parse_scene(
      yaml(minimal) + "  integrator: verlet\n  arkode:\n    table: rk4\n", "s.yaml");
  ASSERT_EQ(s.warnings.size(), 1u);
  EXPECT_NE(s.warnings[0].find("s.yaml:15:3: warning: 'solver.arkode' is ignored"),
            std::string::npos)
      << s.warnings[0];
}

} // namespace

// ---- Mirror supports --------------------------------------------------------------------------

TEST(SceneParser, MirrorSupportParses) {
  const pd::Scene s =
      pd::parse_scene(yaml(minimal) + "supports:\n  - name: face\n    box: [[0], [0.3]]\n"
                                      "    mirror: {x: 0.3}\n",
                      "s.yaml");
  ASSERT_EQ(s.model.supports.size(), 1u);
  EXPECT_TRUE(s.model.supports[0].mirror[0]);
  EXPECT_DOUBLE_EQ(s.model.supports[0].mirror_at[0], 0.3);
  EXPECT_FALSE(s.model.supports[0].fixed[0]);
}

TEST(SceneParser, MirrorTogetherWithFixed) {
  EXPECT_TRUE(fails_at(yaml(minimal) + "supports:\n  - name: s\n    box: [[0], [0.2]]\n"
                                       "    fixed: [x]\n    mirror: {x: 0.2}\n",
                       18, 13, "support 's' both mirrors and fixes or displaces"));
}

TEST(SceneParser, MirrorImageOutsideTheBody) {
  EXPECT_TRUE(fails_at(yaml(minimal) + "supports:\n  - name: s\n    box: [[0], [0.3]]\n"
                                       "    mirror: {x: 0.95}\n"
                                       "model:\n  mirror_coupling: consistent\n", // odd images
                       17, 13, "support 's': no particle at the mirror image (1.85, 0, 0)"));
}

TEST(SceneParser, MirrorSupportsHoldingTheWholeBody) {
  // Under the default quadratic coupling a mirror support's particles are extrapolated from the
  // free ones; a box over the whole bar leaves none (it used to end in an internal error).
  EXPECT_TRUE(fails_at(yaml(minimal) + "supports:\n  - name: s\n    box: [[0], [1]]\n"
                                       "    mirror: {x: 1}\n",
                       17, 13, "support 's': with the other mirror supports it holds every"));
}

TEST(SceneParser, MirrorImageHeldByAnotherSupport) {
  EXPECT_TRUE(fails_at(yaml(minimal) + "supports:\n  - name: m\n    box: [[0], [0.3]]\n"
                                       "    mirror: {x: 0.3}\n"
                                       "  - name: f\n    box: [[0.3], [0.5]]\n    fixed: [x]\n"
                                       "model:\n  mirror_coupling: consistent\n", // odd images
                       17, 13, "is itself supported"));
}

// ---- Virtual fibres (issue 17) -----------------------------------------------------------------

constexpr const char* fibre_scene = R"(
dimension: 2
plane: strain
lattice:
  spacing: 0.1
materials:
  m:
    youngs_modulus: 1e9
    poisson_ratio: 0.3
    density: 1000
bodies:
  - name: plate
    material: m
    box: [[0, 0], [1, 1]]
model:
  bond_model: virtual-fibres
  fibre_kernel_exponent: 3
  fibre_kernel_alpha: 4.5
solver:
  integrator: adr
  end_time: 1
)";

TEST(SceneParser, FibreModelHonoursThePoissonRatioWithoutAWarning) {
  const pd::Scene s = pd::parse_scene(yaml(fibre_scene), "s.yaml");
  EXPECT_EQ(s.model.effects.bond_model, pd::BondModel::virtual_fibres);
  EXPECT_EQ(s.model.fibre_kernel.exponent, 3);
  EXPECT_DOUBLE_EQ(s.model.fibre_kernel.alpha, 4.5);
  EXPECT_TRUE(s.warnings.empty()) << s.warnings.front();
  // The same material under the default bond model warns (ν = 1/4 in plane strain).
  std::string plain = yaml(fibre_scene);
  plain.replace(plain.find("  bond_model: virtual-fibres\n"),
                std::string("  bond_model: virtual-fibres\n").size(), "");
  EXPECT_EQ(pd::parse_scene(plain, "s.yaml").warnings.size(), 1u);
}

TEST(SceneParser, FibreModelRefusesTheStaticSolver) {
  std::string text = yaml(fibre_scene);
  text.replace(text.find("integrator: adr"), 15, "integrator: static");
  EXPECT_TRUE(fails_at(text, 19, 15, "no linearisation"));
}

TEST(SceneParser, FibreModelRefusesDamageWithoutPlasticityAndOneDimension) {
  std::string damage = yaml(fibre_scene);
  damage.replace(damage.find("    density: 1000\n"), 18,
                 "    density: 1000\n    critical_stretch: 0.01\n");
  damage += "effects: [damage]\n";
  EXPECT_TRUE(fails_at(damage, 16, 15, "needs 'plasticity'"));
  EXPECT_TRUE(fails_at(yaml(R"(
dimension: 1
lattice:
  spacing: 0.1
materials:
  m:
    youngs_modulus: 1e9
    density: 1000
bodies:
  - name: bar
    material: m
    box: [[0], [1]]
model:
  bond_model: virtual-fibres
solver:
  integrator: adr
  end_time: 1
)"),
                       13, 15, "dimension 2 or 3"));
}

// ---- Bodies given as particle files (issue 17)
// ----------------------------------------------------

/// A fibre scene whose body is the particle file `csv` (written to a temporary file).
std::string particle_scene(const std::string& csv, const std::string& bond_model) {
  const auto path =
      std::filesystem::temp_directory_path() /
      ("libpd-particles-" +
       std::to_string(::testing::UnitTest::GetInstance()->current_test_info()->line()) + ".csv");
  std::ofstream(path) << csv;
  return "dimension: 2\n"
         "lattice:\n"
         "  spacing: 0.1\n"
         "materials:\n"
         "  m:\n"
         "    youngs_modulus: 1e9\n"
         "    poisson_ratio: 0.2\n"
         "    density: 1000\n"
         "bodies:\n"
         "  - name: plate\n"
         "    material: m\n"
         "    particles: " +
         path.string() +
         "\n"
         "model:\n"
         "  bond_model: " +
         bond_model +
         "\n"
         "solver:\n"
         "  integrator: adr\n"
         "  end_time: 1\n";
}

TEST(SceneParser, ParticleFileBodyIsReadAndBuilt) {
  std::string csv = "x,y,volume\n";
  for (int j = 0; j < 8; ++j) {
    for (int i = 0; i < 8; ++i) {
      csv += std::to_string(0.1 * i + 0.013 * (j % 3)) + "," + std::to_string(0.1 * j) + ",0.01\n";
    }
  }
  const pd::Scene s = pd::parse_scene(particle_scene(csv, "virtual-fibres"), "s.yaml");
  ASSERT_TRUE(s.model.bodies.front().points);
  EXPECT_EQ(s.model.bodies.front().points->count(), 64U);
  const pd::Model m = pd::build_model(s.model);
  EXPECT_EQ(m.size(), 64U); // no lattice particles in the bounding box, no ghosts
  EXPECT_GT(m.family.directed_bond_count(), 0U);
}

// Issue 38, item 7: a particle file's body was estimated as the lattice points of its bounding
// box (192,000 particles passed as 300), so the memory guard never saw its size.
TEST(SceneParser, ParticleFileCountsInTheMemoryGuard) {
  std::string csv = "x,y,volume\n";
  for (int j = 0; j < 150; ++j) {
    for (int i = 0; i < 150; ++i) {
      csv += std::to_string(0.001 * i) + "," + std::to_string(0.001 * j) + ",1e-6\n";
    }
  }
  const std::string text = particle_scene(csv, "virtual-fibres");
  ASSERT_EQ(pd::parse_scene(text, "s.yaml").model.bodies.front().points->count(), 22500U);
  ::setenv("PD_MEMORY_LIMIT", "2M", 1);
  try {
    pd::parse_scene(text, "s.yaml");
    ADD_FAILURE() << "22,500 particles passed a 2 MiB limit";
  } catch (const pd::SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("22500 particles"), std::string::npos) << e.what();
  }
  ::unsetenv("PD_MEMORY_LIMIT");
}

/// The 8 × 8 particles of ParticleFileBodyIsReadAndBuilt, each of volume `volume`, then `extra`.
std::string particle_grid(const std::string& volume, const std::string& extra = "") {
  std::string csv = "x,y,volume\n";
  for (int j = 0; j < 8; ++j) {
    for (int i = 0; i < 8; ++i) {
      csv += std::to_string(0.1 * i + 0.013 * (j % 3)) + "," + std::to_string(0.1 * j) + "," +
             volume + "\n";
    }
  }
  return csv + extra;
}

/// The message of the SceneError parsing `text` throws, at line 12 (the body's `particles`).
std::string particle_body_error(const std::string& text) {
  try {
    pd::parse_scene(text, "s.yaml");
  } catch (const pd::SceneError& e) {
    EXPECT_EQ(e.mark().line, 12) << e.what();
    return e.what();
  }
  ADD_FAILURE() << "parsed";
  return "";
}

// Issue 38, item 11: a particle volume of 1e300 m³ ran (strain energy 4e278 J, exit 0) or ended
// in "no usable time step ... does the model have bonds?"; it is refused against the cell of the
// particle's size, naming the particle.
TEST(SceneParser, ParticleVolumeFarBeyondItsCellIsRefused) {
  const std::string ok =
      particle_body_error(particle_scene(particle_grid("1e300"), "virtual-fibres"));
  EXPECT_NE(ok.find("particle 1 of body 'plate' has volume 1e+300 m³ (with the thickness), "),
            std::string::npos)
      << ok;
  EXPECT_NE(ok.find("a particle may be at most 1000 cells"), std::string::npos) << ok;
  // Volumes of about one cell pass (the plate's cells are 0.1 m wide, thickness 1 m).
  EXPECT_NO_THROW(pd::parse_scene(particle_scene(particle_grid("0.01"), "virtual-fibres"), "s"));
}

// Issue 38, item 11: a particle at x = 1e12 m was refused as "a box of body" (its bounding box),
// earlier as beyond "32-bit particles"; the message names the particle and the bound.
TEST(SceneParser, ParticleFarFromTheOriginIsRefusedByName) {
  const std::string m =
      particle_body_error(particle_scene(particle_grid("0.01", "1e12,0,0.01\n"), "virtual-fibres"));
  EXPECT_NE(m.find("particle 65 of body 'plate' has a coordinate 1000000000000 m, more than 10^9 "
                   "spacings"),
            std::string::npos)
      << m;
}

TEST(SceneParser, ParticleFileWithBadContentIsRefusedNamingFileAndRow) {
  const std::string text =
      particle_scene("x,y,volume\n0,0,0.01\n0.1,0,0.01\n0,0,0.01\n", "virtual-fibres");
  try {
    pd::parse_scene(text, "s.yaml");
    ADD_FAILURE() << "parsed";
  } catch (const pd::SceneError& e) {
    const std::string message = e.what();
    EXPECT_EQ(e.mark().line, 12);
    EXPECT_NE(message.find(".csv:4: duplicate point (0, 0, 0): row 2 has the same position"),
              std::string::npos)
        << message;
  }
  EXPECT_TRUE(fails_at(particle_scene("x,y,volume\n0,0,0.01\n0.1,0,0.01\n", "micro-elastic"), 12,
                       16, "only the virtual-fibre model"));
}

namespace {

std::string graded_scene(const std::string& graded) {
  return "dimension: 2\n"
         "plane: strain\n"
         "lattice:\n"
         "  spacing: 0.01\n"
         "materials:\n"
         "  m:\n"
         "    youngs_modulus: 210e9\n"
         "    poisson_ratio: 0.3\n"
         "    density: 7800\n"
         "bodies:\n"
         "  - name: disk\n"
         "    material: m\n"
         "    graded:\n" +
         graded +
         "model:\n"
         "  bond_model: virtual-fibres\n"
         "solver:\n"
         "  integrator: adr\n"
         "  end_time: 1\n";
}

TEST(SceneParser, GradedBodyIsGeneratedDeterministically) {
  const std::string text = graded_scene("      focal_half_distance: 0.0416667\n"
                                        "      zones: [8, 6]\n"
                                        "      pattern: 3\n"
                                        "      seed: 4\n");
  const pd::Scene a = pd::parse_scene(text, "s.yaml");
  const pd::Scene b = pd::parse_scene(text, "s.yaml");
  ASSERT_TRUE(a.model.bodies.front().points);
  EXPECT_EQ(a.model.bodies.front().points->count(), 8U * 6U * 9U);
  EXPECT_EQ(a.model.bodies.front().points->position, b.model.bodies.front().points->position);
  const pd::Model m = pd::build_model(a.model);
  EXPECT_EQ(m.size(), 8U * 6U * 9U);
}

// Issue 38, item 7: a graded set was made before any guard saw it: zones × pattern overflowed an
// int (SIGSEGV), 10^12 particles ended in std::bad_alloc after 18 s, a huge grading hung.
TEST(SceneParser, GradedSetsAreBoundedBeforeTheyAreMade) {
  const auto refused = [](const std::string& graded, const std::string& words) {
    const auto t0 = std::chrono::steady_clock::now();
    try {
      pd::parse_scene(graded_scene(graded), "s.yaml");
      ADD_FAILURE() << "accepted: " << graded;
    } catch (const pd::SceneError& e) {
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    }
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 5.0)
        << graded;
  };
  refused("      focal_half_distance: 0.0416667\n      zones: [1000, 1]\n      pattern: 3000000\n",
          "more than 1e+06 particles");
  refused("      focal_half_distance: 0.0416667\n      zones: [1000000, 1000000]\n",
          "more than 1e+06 particles");
  refused("      shape: box\n      box: [[0, 0], [1, 0.5]]\n      grading: 1e300\n", "particles");
  ::setenv("PD_MEMORY_LIMIT", "1M", 1); // 40 × 20 zones of 5 × 5: 20,000 particles, 1.8 MiB
  refused("      focal_half_distance: 0.0416667\n", "are allowed by PD_MEMORY_LIMIT");
  ::unsetenv("PD_MEMORY_LIMIT");
}

TEST(SceneParser, GradedBodyErrorsNameTheLine) {
  // Errors point at the value (zones: line 15, column 14) or at the graded map (line 14).
  EXPECT_TRUE(fails_at(graded_scene("      focal_half_distance: 0.04\n"
                                    "      zones: [8.5, 6]\n"),
                       15, 14, "must be two integers"));
  EXPECT_TRUE(
      fails_at(graded_scene("      zones: [8, 6]\n"), 14, 7, "needs 'focal_half_distance'"));
  EXPECT_TRUE(fails_at(graded_scene("      shape: box\n"
                                    "      zones: [8, 6]\n"),
                       14, 7, "needs 'box'"));
  EXPECT_TRUE(fails_at(graded_scene("      focal_half_distance: 0.04\n"
                                    "      noise: -1\n"),
                       15, 14, "noise"));
}

} // namespace
