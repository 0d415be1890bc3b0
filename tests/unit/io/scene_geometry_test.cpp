// Scene keys of issue 19: shapes and holes, pre-cracks, point loads, symmetry supports, reaction,
// stress and damage probes, and solver.stop_when. Each class of bad input is refused at its node;
// valid scenes fill the fields and build the model they describe.
#include "libpd/app/run.hpp"
#include "libpd/discretisation/model.hpp"
#include "libpd/io/scene.hpp"
#include "scene_test_support.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <gtest/gtest.h>
#include <string>

namespace {

/// A 2D plate, 20 × 10 spacings, to which each test appends its own lines.
std::string plate(const std::string& more) {
  return yaml(R"(
dimension: 2
plane: stress
thickness: 0.01
lattice:
  spacing: 0.01
materials:
  steel:
    youngs_modulus: 200e9
    density: 7800
bodies:
  - name: plate
    material: steel
    box: [[0, 0], [0.2, 0.1]]
)") + more;
}

constexpr const char* solver = R"(solver:
  integrator: static
)";

TEST(SceneGeometry, HoleRemovesTheParticlesInside) {
  const pd::Scene s = pd::parse_scene(plate(R"(    minus:
      - cylinder: {centre: [0.1, 0.05], radius: 0.02}
)") + solver,
                                      "s.yaml");
  ASSERT_EQ(s.model.bodies[0].region.minus.size(), 1u);
  const pd::Model m = pd::build_model(s);
  // Cell centres within 0.02 of (0.1, 0.05): the 12 of the 4 × 4 block around the centre that
  // lie inside the circle (the 4 corners at distance 0.0212 stay).
  EXPECT_EQ(m.body_particle_count(), 200u - 12u);
}

TEST(SceneGeometry, CylinderBodyNeedsALengthIn3D) {
  EXPECT_TRUE(fails_at(yaml(R"(
dimension: 3
lattice:
  spacing: 0.01
materials:
  m:
    youngs_modulus: 1e9
    density: 1000
bodies:
  - name: rod
    material: m
    cylinder: {centre: [0, 0, 0], radius: 0.05}
solver:
  integrator: static
)"),
                       11, 15, "the cylinder of body 'rod' is unbounded"));
}

TEST(SceneGeometry, TwoDimensionalCylinderRunsAlongZ) {
  EXPECT_TRUE(fails_at(plate(R"(    minus:
      - cylinder: {centre: [0.1, 0.05], radius: 0.02, axis: x}
)") + solver,
                       15, 61, "in a 2D scene a cylinder runs along z"));
}

TEST(SceneGeometry, MinusShapeNeedsExactlyOneKind) {
  EXPECT_TRUE(fails_at(plate(R"(    minus:
      - {}
)") + solver,
                       15, 9, "missing 'box', 'cylinder', 'sphere' or 'half_space'"));
}

TEST(SceneGeometry, HalfSpaceNeedsANormal) {
  EXPECT_TRUE(fails_at(plate(R"(    minus:
      - half_space: {point: [0.1, 0.05], normal: [0, 0]}
)") + solver,
                       15, 50, "the normal of a half_space is zero"));
}

TEST(SceneGeometry, OverlappingShapedBodiesOfDifferentMaterials) {
  EXPECT_TRUE(fails_at(yaml(R"(
dimension: 2
plane: stress
thickness: 0.01
lattice:
  spacing: 0.01
materials:
  steel: {youngs_modulus: 200e9, density: 7800}
  soft: {youngs_modulus: 1e9, density: 1000}
bodies:
  - name: plate
    material: steel
    box: [[0, 0], [0.2, 0.1]]
  - name: inclusion
    material: soft
    cylinder: {centre: [0.1, 0.05], radius: 0.02}
solver:
  integrator: static
)"),
                       15, 15, "bodies 'plate' and 'inclusion' overlap"));
}

// Issue 38, item 9: a box inclusion in a hole of the same box was refused as "overlap" in either
// order (the box check ignored the hole), although SCENE_FORMAT.md says to do exactly that.
TEST(SceneGeometry, BoxInclusionCarvedOutWithMinusIsNoOverlap) {
  const std::string plate_body = R"(  - name: plate
    material: steel
    box: [[0, 0], [0.2, 0.1]]
    minus:
      - box: [[0.08, 0.03], [0.12, 0.07]]
)";
  const std::string inclusion_body = R"(  - name: inclusion
    material: soft
    box: [[0.08, 0.03], [0.12, 0.07]]
)";
  const char* head = R"(
dimension: 2
plane: stress
thickness: 0.01
lattice:
  spacing: 0.01
materials:
  steel: {youngs_modulus: 200e9, density: 7800}
  soft: {youngs_modulus: 1e9, density: 1000}
bodies:
)";
  for (const bool plate_first : {true, false}) {
    const std::string text =
        yaml(head) + (plate_first ? plate_body + inclusion_body : inclusion_body + plate_body) +
        solver;
    try {
      const pd::Model m = pd::build_model(pd::parse_scene(text, "s.yaml"));
      EXPECT_EQ(m.body_particle_count(), 200u) << "plate first: " << plate_first;
    } catch (const std::exception& e) {
      ADD_FAILURE() << "plate first: " << plate_first << ": " << e.what();
    }
  }
}

/// The plate with a crack along y = 0.05 from x = 0.05 to 0.15 (between particle rows).
pd::Scene cracked_plate() {
  return pd::parse_scene(plate(R"(cracks:
  - name: c
    segment: [[0.05, 0.05], [0.15, 0.05]]
)") + solver,
                         "s.yaml");
}

TEST(SceneGeometry, CrackCutsTheBondsThatCrossIt) {
  const pd::Scene s = cracked_plate();
  ASSERT_EQ(s.model.cracks.size(), 1u);
  // The bare model: with ghosts and gradient weights, bonds of zero weight leave the family
  // whether a crack crosses them or not, and the count below would not add up.
  pd::ModelSpec spec = s.model;
  spec.surface_correction = pd::SurfaceCorrection::none;
  spec.volume_correction = pd::VolumeCorrection::none;
  const pd::Model with = pd::build_model(spec);
  pd::ModelSpec uncracked = spec;
  uncracked.cracks.clear();
  const pd::Model without = pd::build_model(uncracked);
  ASSERT_EQ(with.bonds_cut_by_crack.size(), 1u);
  EXPECT_GT(with.bonds_cut_by_crack[0], 0u);
  EXPECT_EQ(with.family.bond_count() + with.bonds_cut_by_crack[0], without.family.bond_count());
}

// Issue 36: a bond that crosses the crack behind its front but ends beyond it is kept, as a crack
// grown by breaking bonds leaves it; cutting it too made the pre-crack sharper than a grown crack
// (its first bonds broke 4–13 % below the running crack's K) and its faces too compliant.
TEST(SceneGeometry, CrackKeepsTheBondsThatReachPastItsFront) {
  const pd::Scene s = cracked_plate();
  pd::ModelSpec spec = s.model;
  spec.surface_correction = pd::SurfaceCorrection::none;
  spec.volume_correction = pd::VolumeCorrection::none;
  const pd::Model m = pd::build_model(spec);
  const auto& x = m.particles.position;
  const auto at = [&](double px, double py) {
    for (std::size_t i = 0; i < m.body_particle_count(); ++i) {
      if (std::abs(x[i][0] - px) < 1e-9 && std::abs(x[i][1] - py) < 1e-9) {
        return i;
      }
    }
    ADD_FAILURE() << "no particle at " << px << ", " << py;
    return std::size_t{0};
  };
  const auto bonded = [&](std::size_t i, std::size_t j) {
    for (std::size_t k = m.family.offsets[i]; k < m.family.offsets[i + 1]; ++k) {
      if (m.family.neighbour[k] == j) {
        return true;
      }
    }
    return false;
  };
  // Crosses y = 0.05 at x = 0.145, behind the front at 0.15, and ends at x = 0.155 beyond it.
  EXPECT_TRUE(bonded(at(0.135, 0.045), at(0.155, 0.055)));
  EXPECT_TRUE(bonded(at(0.155, 0.055), at(0.135, 0.045)));
  // Crosses at x = 0.135 with both ends over the crack: cut.
  EXPECT_FALSE(bonded(at(0.125, 0.045), at(0.145, 0.055)));
  // The straight bond across the front's last cell: both ends at x = 0.145, cut.
  EXPECT_FALSE(bonded(at(0.145, 0.045), at(0.145, 0.055)));
}

// Issue 38, item 11: a crack outside every body was accepted without a word (it cuts nothing).
TEST(SceneGeometry, CrackOutsideEveryBodyIsAWarning) {
  const pd::Scene inside = cracked_plate();
  EXPECT_TRUE(inside.warnings.empty()) << inside.warnings.front();
  const pd::Scene outside = pd::parse_scene(plate(R"(cracks:
  - name: c
    segment: [[5, 5], [15, 5]]
)") + solver,
                                            "s.yaml");
  ASSERT_EQ(outside.warnings.size(), 1u);
  EXPECT_NE(outside.warnings[0].find("crack 'c' lies outside every body"), std::string::npos)
      << outside.warnings[0];
}

TEST(SceneGeometry, CrackSegmentNeedsTwoPoints) {
  EXPECT_TRUE(fails_at(plate(R"(cracks:
  - name: c
    segment: [[0.05, 0.05]]
)") + solver,
                       16, 14, "must be a list of two points"));
}

TEST(SceneGeometry, CrackPolygonMustBePlanar) {
  EXPECT_TRUE(fails_at(yaml(R"(
dimension: 3
lattice:
  spacing: 0.01
materials:
  m:
    youngs_modulus: 1e9
    density: 1000
bodies:
  - name: b
    material: m
    box: [[0, 0, 0], [0.1, 0.1, 0.1]]
cracks:
  - name: c
    polygon: [[0, 0, 0.05], [0.1, 0, 0.05], [0.1, 0.1, 0.05], [0, 0.1, 0.06]]
solver:
  integrator: static
)"),
                       14, 14, "is not planar"));
}

TEST(SceneGeometry, PointLoadSharedByTheNearestParticles) {
  const pd::Scene s = pd::parse_scene(plate(R"(supports:
  - name: clamp
    box: [[0, 0], [0.01, 0.1]]
    fixed: [x, y]
loads:
  - name: p
    point: [0.2, 0.05]
    value: [0, -100]
)") + solver,
                                      "s.yaml");
  EXPECT_EQ(s.model.loads[0].load.kind, pd::BoxRegionLoad::Kind::point);
  const pd::Model m = pd::build_model(s);
  // (0.2, 0.05) lies on the face between the particles at y = 0.045 and 0.055.
  const auto members =
      pd::load_particles(s.model, m.particles, s.model.loads[0], m.body_particle_count());
  ASSERT_EQ(members.size(), 2u);
  double total = 0;
  for (std::size_t i = 0; i < m.body_particle_count(); ++i) {
    total += m.external_force_density[3 * i + 1] * m.particles.volume[i];
  }
  EXPECT_NEAR(total, -100, 1e-9);
}

TEST(SceneGeometry, PointLoadOfAnotherType) {
  EXPECT_TRUE(fails_at(plate(R"(loads:
  - name: p
    point: [0.2, 0.05]
    type: per_area
    value: [0, -100]
)") + solver,
                       17, 11, "its type is 'point'"));
}

TEST(SceneGeometry, PointLoadFarFromTheBody) {
  EXPECT_TRUE(fails_at(plate(R"(loads:
  - name: p
    point: [0.5, 0.05]
    value: [0, -100]
)") + solver,
                       16, 12, "point load 'p' is"));
}

TEST(SceneGeometry, ReactionProbeNeedsASupport) {
  EXPECT_TRUE(fails_at(plate(R"(probes:
  - name: r
    point: [0.1, 0.05]
    quantity: reaction
)") + solver,
                       17, 15, "records a reaction but names no 'support'"));
}

TEST(SceneGeometry, ReactionProbeOfAnUnknownSupport) {
  EXPECT_TRUE(fails_at(plate(R"(supports:
  - name: clamp
    box: [[0, 0], [0.01, 0.1]]
    fixed: [x, y]
probes:
  - name: r
    support: clamb
)") + solver,
                       20, 14, "unknown support 'clamb'"));
}

TEST(SceneGeometry, ReactionProbeOfAMirrorSupport) {
  EXPECT_TRUE(fails_at(plate(R"(  - name: grip
    material: steel
    box: [[-0.04, 0], [0, 0.1]]
supports:
  - name: clamp
    box: [[-0.04, 0], [0, 0.1]]
    mirror: {x: 0}
probes:
  - name: r
    support: clamp
)") + solver,
                       23, 14, "mirror or symmetry support"));
}

TEST(SceneGeometry, DamageProbeNeedsDamage) {
  EXPECT_TRUE(fails_at(plate(R"(probes:
  - name: d
    point: [0.1, 0.05]
    quantity: damage
)") + solver,
                       17, 15, "a damage probe needs the damage effect"));
}

TEST(SceneGeometry, SymmetrySupportNeedsNoRegionButNothingElse) {
  const pd::Scene s = pd::parse_scene(plate(R"(supports:
  - name: sym
    symmetry: {x: 0}
  - name: pin
    box: [[0, 0], [0.2, 0.01]]
    fixed: [y]
)") + solver,
                                      "s.yaml");
  EXPECT_TRUE(s.model.supports[0].symmetric());
  EXPECT_TRUE(fails_at(plate(R"(supports:
  - name: sym
    symmetry: {x: 0}
    fixed: [y]
)") + solver,
                       16, 15, "is a symmetry plane and also fixes"));
  EXPECT_TRUE(fails_at(plate(R"(supports:
  - name: clamp
    fixed: [y]
)") + solver,
                       15, 5, "missing 'box' or 'boxes' in support 'clamp'"));
}

TEST(SceneGeometry, SymmetryNeedsGhosts) {
  EXPECT_TRUE(fails_at(plate(R"(supports:
  - name: sym
    symmetry: {x: 0}
model:
  surface_correction: none
)") + solver,
                       16, 15, "needs the ghost surface correction"));
}

TEST(SceneGeometry, StopWhenWatchesAKnownProbe) {
  EXPECT_TRUE(fails_at(plate(R"(solver:
  integrator: static
  stop_when: {probe: forse, drops_below: 0.5}
probes:
  - name: force
    point: [0.1, 0.05]
)"),
                       16, 22, "watches unknown probe 'forse'"));
  EXPECT_TRUE(fails_at(plate(R"(solver:
  integrator: static
  stop_when: {probe: force, drops_below: 1.5}
probes:
  - name: force
    point: [0.1, 0.05]
)"),
                       16, 42, "drops_below"));
}

/// stop_when.drops_below takes a drop for a failure only when bonds broke since the peak: a grip
/// moved in one step makes the undamped plate's reaction swing (633 kN in the first step, 41 kN
/// two steps later, no bond broken), which is not a failure; the same grip ramped on a plate whose
/// bonds break near it is.
TEST(SceneGeometry, StopWhenDropNeedsBrokenBonds) {
  const auto status = [](const char* fracture_energy, const char* ramp) {
    const std::string text = plate(R"(supports:
  - name: left
    box: [[0, 0], [0.01, 0.1]]
    fixed: [x, y]
  - name: right
    box: [[0.19, 0], [0.2, 0.1]]
    displacement: {x: 1e-5}
    fixed: [y]
effects: [damage]
solver:
  integrator: verlet
  end_time: 2e-4
  ramp_time: )" + std::string(ramp) +
                                   R"(
  stop_when: {probe: force, drops_below: 0.5}
probes:
  - name: force
    support: right
    component: x
)");
    std::string scene = text;
    scene.replace(scene.find("density: 7800"), 13,
                  "density: 7800\n    fracture_energy: " + std::string(fracture_energy));
    return pd::run_scene(pd::parse_scene(scene, "s.yaml"), pd::RunOptions{}).result.status;
  };
  EXPECT_EQ(status("1e9", "0"), pd::RunStatus::end_time);
  EXPECT_EQ(status("20", "1e-4"), pd::RunStatus::failed);
}

/// `integrator: static` with damage is quasi-static fracture: the plate pulled apart by its grips
/// fails (stop_when) with its load curve in the summary, and `load_steps` is refused where it
/// means nothing.
TEST(SceneGeometry, StaticWithDamageIsQuasiStaticFracture) {
  const std::string supports = R"(supports:
  - name: left
    box: [[0, 0], [0.01, 0.1]]
    fixed: [x, y]
  - name: right
    box: [[0.19, 0], [0.2, 0.1]]
    displacement: {x: 1e-4}
    fixed: [y]
cracks:
  - name: notch
    segment: [[0.1, 0.03], [0.1, 0.07]]
effects: [damage]
)";
  const std::string probes = R"(probes:
  - name: force
    support: right
    component: x
output:
  history_every: 1
)";
  std::string scene = plate(supports + R"(solver:
  integrator: static
  load_steps: 4
  stop_when: {probe: force, drops_below: 0.5}
)" + probes);
  scene.replace(scene.find("density: 7800"), 13, "density: 7800\n    fracture_energy: 50");
  const pd::RunOutcome out = pd::run_scene(pd::parse_scene(scene, "s.yaml"), pd::RunOptions{});
  EXPECT_EQ(out.result.status, pd::RunStatus::failed) << out.result.message;
  const pd::Json* q = out.summary.find("quasi_static");
  ASSERT_TRUE(q != nullptr);
  EXPECT_GT(*q->find("bonds_broken")->number(), 0);
  EXPECT_GT(*q->find("dissipated_energy")->number(), 0);
  // The history's time is the load factor: after the initial row, levels of 1/4 and the
  // critical states between them.
  ASSERT_GE(out.history.time.size(), 3u);
  for (std::size_t r = 1; r < out.history.time.size(); ++r) {
    EXPECT_GT(out.history.time[r], 0);
    EXPECT_LE(out.history.time[r], 1.0);
  }
  EXPECT_GT(out.stop_peak, 0);

  std::string adr = plate(supports + R"(solver:
  integrator: adr
  end_time: 1
  load_steps: 4
)" + probes);
  adr.replace(adr.find("density: 7800"), 13, "density: 7800\n    fracture_energy: 50");
  EXPECT_TRUE(fails_at(adr, 30, 15, "needs 'integrator: static'"));
}

/// A half plate with a symmetry plane gives the full plate's answer: a plate stretched by grips
/// at both ends, against its right half with the plane x = 0 (on cell faces, as the lattice puts
/// a box's faces) and one grip.
TEST(SceneGeometry, SymmetryHalfModelMatchesTheFullModel) {
  const auto run = [](const std::string& body_and_supports) {
    const std::string text = yaml(R"(
dimension: 2
plane: stress
thickness: 0.01
lattice:
  spacing: 0.01
materials:
  steel: {youngs_modulus: 200e9, density: 7800}
bodies:
  - name: plate
    material: steel
)") + body_and_supports + R"(  - name: right-grip
    box: [[0.19, 0], [0.2, 0.1]]
    displacement: {x: 1e-5}
    fixed: [y]
solver:
  integrator: static
probes:
  - name: u
    point: [0.105, 0.075]
    component: x
  - name: v
    point: [0.055, 0.095]
    component: y
  - name: force
    support: right-grip
    component: x
)";
    return pd::run_scene(pd::parse_scene(text, "s.yaml"), pd::RunOptions{}).probes;
  };
  const auto full = run(R"(    box: [[-0.2, 0], [0.2, 0.1]]
supports:
  - name: left-grip
    box: [[-0.2, 0], [-0.19, 0.1]]
    displacement: {x: -1e-5}
    fixed: [y]
)");
  const auto half = run(R"(    box: [[0, 0], [0.2, 0.1]]
supports:
  - name: plane
    symmetry: {x: 0}
)");
  // Issue 19 asks for 0.1 %; what remains is the full model's own asymmetry (a ghost's fit is
  // centred on its nearest source, the lowest index among equals).
  for (const char* probe : {"u", "v", "force"}) {
    EXPECT_NEAR(half.at(probe) / full.at(probe), 1.0, 1e-3) << probe;
    std::printf("half / full - 1 for %s: %.3g\n", probe, half.at(probe) / full.at(probe) - 1);
  }
}

} // namespace

namespace {

TEST(SceneGeometry, BoxOffTheCellFacesWarnsWithTheRepresentedVolume) {
  std::string text = plate(solver);
  text.replace(text.find("[[0, 0], [0.2, 0.1]]"), 20, "[[0, 0], [0.205, 0.1]]");
  const pd::Scene s = pd::parse_scene(text, "s.yaml");
  ASSERT_EQ(s.warnings.size(), 1u);
  // 21 columns of cells (the centre at x = 0.205 lies on the face) for a 0.205 m box.
  EXPECT_NE(s.warnings[0].find("s.yaml:13:10: warning: a box of body 'plate' has faces between"),
            std::string::npos)
      << s.warnings[0];
  EXPECT_NE(s.warnings[0].find("(+2.44 %)"), std::string::npos) << s.warnings[0];
}

// ---- Library defaults -------------------------------------------------------------------------

/// A ModelSpec{} given the scene's geometry (dimension, lattice, materials, bodies, supports,
/// loads, cracks) and nothing else: the model options are the library's own defaults.
pd::ModelSpec default_spec_with_geometry_of(const pd::ModelSpec& scene) {
  pd::ModelSpec spec;
  spec.dimension = scene.dimension;
  spec.lattice = scene.lattice;
  spec.materials = scene.materials;
  spec.bodies = scene.bodies;
  spec.supports = scene.supports;
  spec.loads = scene.loads;
  spec.cracks = scene.cracks;
  return spec;
}

void expect_same_options(const pd::ModelSpec& a, const pd::ModelSpec& b) {
  EXPECT_EQ(a.horizon_rule, b.horizon_rule);
  EXPECT_EQ(a.surface_correction, b.surface_correction);
  EXPECT_EQ(a.volume_correction, b.volume_correction);
  EXPECT_EQ(a.mirror_coupling, b.mirror_coupling);
  EXPECT_EQ(a.effects.bond_model, b.effects.bond_model);
  EXPECT_EQ(a.effects.stretch, b.effects.stretch);
  EXPECT_EQ(a.effects.damage, b.effects.damage);
  EXPECT_EQ(a.effects.plasticity, b.effects.plasticity);
  EXPECT_EQ(a.effects.per_bond_field, b.effects.per_bond_field);
  EXPECT_EQ(a.effects.damping, b.effects.damping);
  EXPECT_EQ(a.effects.body_force, b.effects.body_force);
  EXPECT_EQ(a.fibre_kernel.exponent, b.fibre_kernel.exponent);
  EXPECT_EQ(a.fibre_kernel.alpha, b.fibre_kernel.alpha);
  EXPECT_EQ(a.fibre_kernel.size_neighbours, b.fibre_kernel.size_neighbours);
}

bool same_constraints(const std::vector<pd::Constraint>& a, const std::vector<pd::Constraint>& b) {
  return std::equal(a.begin(), a.end(), b.begin(), b.end(), [](const auto& x, const auto& y) {
    return x.particle == y.particle && x.component == y.component && x.value == y.value &&
           x.mirror_of == y.mirror_of && x.mirror_sign == y.mirror_sign;
  });
}

/// Bitwise the same model: particles, bonds, bond field, corrections (in the per-bond
/// stiffness), constraints and extrapolated particles.
void expect_same_model(const pd::Model& a, const pd::Model& b) {
  EXPECT_EQ(a.ghost_count, b.ghost_count);
  EXPECT_EQ(a.particles.position, b.particles.position);
  EXPECT_EQ(a.particles.volume, b.particles.volume);
  EXPECT_EQ(a.family.offsets, b.family.offsets);
  EXPECT_EQ(a.family.neighbour, b.family.neighbour);
  EXPECT_EQ(a.family.inverse_length, b.family.inverse_length);
  EXPECT_EQ(a.effects.per_bond_field, b.effects.per_bond_field);
  EXPECT_EQ(a.field.stiffness, b.field.stiffness);
  EXPECT_EQ(a.field.bond_stiffness, b.field.bond_stiffness);
  EXPECT_EQ(a.field.bond_critical_stretch, b.field.bond_critical_stretch);
  EXPECT_EQ(a.field.bond_yield_stretch, b.field.bond_yield_stretch);
  EXPECT_EQ(a.density, b.density);
  EXPECT_EQ(a.external_force_density, b.external_force_density);
  EXPECT_TRUE(same_constraints(a.constraints, b.constraints));
  EXPECT_EQ(a.extrapolated.particle, b.extrapolated.particle);
  EXPECT_EQ(a.extrapolated.offsets, b.extrapolated.offsets);
  EXPECT_EQ(a.extrapolated.source, b.extrapolated.source);
  EXPECT_EQ(a.extrapolated.coefficient, b.extrapolated.coefficient);
  EXPECT_EQ(a.extrapolated.negated, b.extrapolated.negated);
}

TEST(LibraryDefaults, AreGhostGradientQuadratic) {
  const pd::ModelSpec spec{};
  EXPECT_EQ(spec.surface_correction, pd::SurfaceCorrection::ghost);
  EXPECT_EQ(spec.volume_correction, pd::VolumeCorrection::gradient);
  EXPECT_EQ(spec.mirror_coupling, pd::MirrorCoupling::quadratic);
  EXPECT_EQ(spec.effects.bond_model, pd::BondModel::micro_elastic);
}

// A scene that names no key under `model` builds the model a ModelSpec{} of the same geometry
// builds: the scene reader has no defaults of its own.
TEST(LibraryDefaults, AnEmptyModelSectionIsModelSpecDefaults) {
  const std::string box_3d = yaml(R"(
dimension: 3
lattice:
  spacing: 0.01
materials:
  steel:
    youngs_modulus: 200e9
    density: 7800
bodies:
  - name: block
    material: steel
    box: [[0, 0, 0], [0.06, 0.04, 0.03]]
loads:
  - name: pull
    box: [[0.05, 0, 0], [0.06, 0.04, 0.03]]
    type: total
    value: [1e3, 0, 0]
)");
  const std::string plane_strain = yaml(R"(
dimension: 2
plane: strain
thickness: 0.01
lattice:
  spacing: 0.01
materials:
  steel:
    youngs_modulus: 200e9
    density: 7800
bodies:
  - name: plate
    material: steel
    box: [[0, 0], [0.1, 0.05]]
supports:
  - name: pin
    box: [[0, 0], [0.01, 0.05]]
    fixed: [x, y]
)");
  const std::string bar_1d = yaml(R"(
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
    box: [[0], [2]]
supports:
  - name: clamp
    box: [[0], [0.1]]
    fixed: [x]
)");
  const std::string mirrored_2d = yaml(R"(
dimension: 2
plane: stress
thickness: 0.1
lattice:
  spacing: 0.05
materials:
  steel:
    youngs_modulus: 200e9
    poisson_ratio: 0
    density: 7800
bodies:
  - name: bar
    material: steel
    box: [[0, 0], [1, 0.2]]
  - name: clamp
    material: steel
    box: [[-0.2, 0], [0, 0.2]]
supports:
  - name: clamp
    box: [[-0.2, 0], [0, 0.2]]
    mirror: {x: 0}
)");
  const std::string mirrored_3d = yaml(R"(
dimension: 3
lattice:
  spacing: 0.01
materials:
  steel:
    youngs_modulus: 200e9
    density: 7800
bodies:
  - name: beam
    material: steel
    box: [[-0.03, 0, 0], [0.1, 0.03, 0.03]]
supports:
  - name: clamp
    box: [[-0.03, 0, 0], [0, 0.03, 0.03]]
    mirror: {x: 0}
)");
  const std::string symmetric = plate(R"(supports:
  - name: sym
    symmetry: {x: 0}
  - name: pin
    box: [[0, 0], [0.2, 0.01]]
    fixed: [y]
)");
  const std::string solver_section = "solver:\n  end_time: 1\n";
  for (const std::string& text :
       {box_3d, plate(""), plane_strain, bar_1d, mirrored_2d, mirrored_3d, symmetric}) {
    const pd::Scene scene = pd::parse_scene(text + solver_section, "s.yaml");
    const pd::ModelSpec library = default_spec_with_geometry_of(scene.model);
    SCOPED_TRACE(text);
    expect_same_options(scene.model, library);
    expect_same_model(pd::build_model(scene.model), pd::build_model(library));
  }
}

} // namespace
