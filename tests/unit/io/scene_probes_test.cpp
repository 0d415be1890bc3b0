// The probe vocabulary engineers read (issue 37): stress and strain components with shear, von
// Mises, a crack's opening, a support's moment and line probes, as the scene reader takes them,
// and the scenes it refuses.
#include "scene_test_support.hpp"

#include <string>

namespace {

/// A 2D plate held on its left edge; `probes` is appended as the scene's probes list.
std::string plate(const std::string& probes) {
  return yaml(R"(
dimension: 2
plane: stress
thickness: 0.01
lattice:
  spacing: 0.1
materials:
  m:
    youngs_modulus: 1e9
    poisson_ratio: 0.3333333333333333
    density: 1000
bodies:
  - name: plate
    material: m
    box: [[0, 0], [1, 1]]
supports:
  - name: edge
    box: [[0, 0], [0.1, 1]]
    fixed: [x, y]
solver:
  integrator: static
probes:
)") + probes;
}

} // namespace

TEST(SceneProbes, TensorComponentsVonMisesOpeningMomentAndLine) {
  const pd::Scene s =
      pd::parse_scene(plate(R"(  - {name: sxy, point: [0.5, 0.5], quantity: stress, component: xy}
  - {name: sxx, point: [0.5, 0.5], quantity: stress, component: x}
  - {name: eyy, box: [[0.4, 0.4], [0.6, 0.6]], quantity: strain, component: yy}
  - {name: vm, point: [0.5, 0.5], quantity: von_mises}
  - {name: cmod, point: [0.5, 0.45], to: [0.5, 0.55], quantity: opening}
  - {name: m, support: edge, quantity: moment, about: [0, 0.5]}
  - name: prof
    line: {from: [0.15, 0.05], to: [0.95, 0.05], points: 5}
    quantity: strain
    component: xx
)"),
                      "s.yaml");
  using Q = pd::ProbeSpec::Quantity;
  ASSERT_EQ(s.probes.size(), 11u);
  EXPECT_EQ(s.probes[0].quantity, Q::stress);
  EXPECT_EQ(s.probes[0].component, 3); // xy
  EXPECT_EQ(s.probes[1].component, 0); // x is xx
  EXPECT_EQ(s.probes[2].quantity, Q::strain);
  EXPECT_EQ(s.probes[2].component, 1);
  EXPECT_EQ(s.probes[3].quantity, Q::von_mises);
  EXPECT_EQ(s.probes[4].quantity, Q::opening);
  EXPECT_EQ(s.probes[4].to, (pd::Vec3{0.5, 0.55, 0}));
  EXPECT_EQ(s.probes[5].quantity, Q::moment);
  EXPECT_EQ(s.probes[5].kind, pd::ProbeSpec::Kind::support);
  EXPECT_EQ(s.probes[5].component, 2); // a 2D moment is about z
  EXPECT_EQ(s.probes[5].about, (pd::Vec3{0, 0.5, 0}));
  for (int k = 0; k < 5; ++k) {
    const pd::ProbeSpec& p = s.probes[static_cast<std::size_t>(6 + k)];
    EXPECT_EQ(p.name, "prof[" + std::to_string(k) + "]");
    EXPECT_EQ(p.kind, pd::ProbeSpec::Kind::point);
    EXPECT_EQ(p.line, "prof");
    EXPECT_EQ(p.line_index, k);
    EXPECT_DOUBLE_EQ(p.point[0], 0.15 + 0.2 * k);
    EXPECT_DOUBLE_EQ(p.line_distance, 0.2 * k);
    EXPECT_EQ(p.quantity, Q::strain);
  }
}

TEST(SceneProbes, RefusesWhatDoesNotExist) {
  // Line 22 is the first probe of plate().
  const auto refused = [](const char* probe, int column, const char* fragment) {
    return fails_at(plate(probe), 22, column, fragment);
  };
  EXPECT_TRUE(refused("  - {name: s, point: [0.5, 0.5], quantity: stress, component: zz}\n", 63,
                      "component 'zz' of stress does not exist in a 2D scene"));
  EXPECT_TRUE(
      refused("  - {name: u, point: [0.5, 0.5], component: xy}\n", 45, "is a tensor component"));
  EXPECT_TRUE(refused("  - {name: v, point: [0.5, 0.5], quantity: von_mises, component: x}\n", 66,
                      "which has no component"));
  EXPECT_TRUE(refused("  - {name: o, point: [0.5, 0.5], quantity: opening}\n", 22,
                      "needs the second point 'to'"));
  EXPECT_TRUE(refused("  - {name: m, support: edge, quantity: moment}\n", 24,
                      "needs the point the moment is taken 'about'"));
  EXPECT_TRUE(refused("  - {name: m, point: [0.5, 0.5], quantity: moment, about: [0, 0]}\n", 44,
                      "names no 'support'"));
  EXPECT_TRUE(refused("  - {name: d, point: [0.5, 0.5], to: [0.5, 0.6]}\n", 38,
                      "'to' belongs to an opening probe"));
  EXPECT_TRUE(refused("  - {name: l, line: {from: [0.5, 0.5], to: [0.5, 0.5], points: 3}}\n", 44,
                      "has 'from' = 'to'"));
  EXPECT_TRUE(refused("  - {name: l, line: {from: [0.5, 0.5], to: [0.5, 0.9], points: 1}}\n", 64,
                      "'line.points' must be in [2, 10000]"));
}
