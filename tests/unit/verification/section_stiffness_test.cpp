// Section-stiffness error budget (verification/runner/section_stiffness.hpp): the relaxed stiffness
// of a PD cross-section against the continuum it discretises.
#include "libpd/io/scene.hpp"
#include "section_stiffness.hpp"

#include <gtest/gtest.h>

namespace {

using pd::verification::section_stiffness;

/// A 3D body of E = 1, ν = 1/4 on a unit lattice (spacing 1) with the given corrections.
pd::ModelSpec unit_lattice(double horizon_factor, pd::SurfaceCorrection surface,
                           pd::VolumeCorrection volume) {
  pd::ModelSpec spec;
  spec.dimension.dim = 3;
  spec.lattice.spacing = 1.0;
  spec.lattice.horizon_factor = horizon_factor;
  pd::Material m;
  m.name = "unit";
  m.youngs_modulus = 1.0;
  m.poisson_ratio = 0.25;
  m.density = 1.0;
  spec.materials = {m};
  spec.surface_correction = surface;
  spec.volume_correction = volume;
  spec.effects.per_bond_field = true;
  return spec;
}

pd::BodySpec section(double width, double depth) {
  pd::BodySpec b;
  b.name = "section";
  b.region.boxes = {pd::Box{{0, 0, 0}, {1, width, depth}}};
  return b;
}

// `moment` weights give the bulk the continuum's constants and `tensor` restores each surface
// particle's energy under uniaxial stress (block-tension: +0.35 %), so a beam's axial stiffness is
// right. Bending is not: the through-thickness sampling loss is not a uniform-strain property.
TEST(SectionStiffness, TensorMomentBeamHasTheContinuumAxialStiffness) {
  const auto spec = unit_lattice(2 * 1.7320508075688772, pd::SurfaceCorrection::tensor,
                                 pd::VolumeCorrection::moment);
  const auto s = section_stiffness(spec, section(6, 8), 0, 2, false);
  EXPECT_EQ(s.section_particles, 48U);
  EXPECT_NEAR(s.membrane, 1.0, 0.02);
  EXPECT_LT(s.bending, 0.95 * s.membrane);
}

// A bond's stretch is the strain at its midpoint, so with δ comparable to the thickness the bonds
// crossing it sample the curvature too near the neutral axis: bending relative to axial stiffness
// falls as the plate gets thinner in units of δ, and recovers as it gets thicker.
TEST(SectionStiffness, BendingLossGrowsAsThePlateThinsRelativeToTheHorizon) {
  const auto spec = unit_lattice(2 * 1.7320508075688772, pd::SurfaceCorrection::volume,
                                 pd::VolumeCorrection::linear);
  double previous = 0;
  for (int layers : {4, 8, 16}) {
    const auto s = section_stiffness(spec, section(1, layers), 0, 2, true);
    EXPECT_EQ(s.section_particles, static_cast<std::size_t>(layers));
    const double bending_over_axial = s.bending / s.membrane;
    EXPECT_GT(bending_over_axial, previous) << layers << " layers";
    previous = bending_over_axial;
    if (layers == 4) { // δ = 0.87 t, as in Miranda's plate at λ = t/4
      EXPECT_LT(bending_over_axial, 0.8);
    }
  }
  EXPECT_NEAR(previous, 1.0, 0.03); // 16 layers: δ = 0.22 t
}

// Uniform fields: a rigid translation of the section costs nothing, so relaxing the transverse
// displacements can only lower the energy of the imposed state; with no correction a section
// whose every particle lacks bonds is softer than the continuum in every mode.
TEST(SectionStiffness, UncorrectedSectionIsSofterInEveryMode) {
  const auto spec = unit_lattice(3.0, pd::SurfaceCorrection::none, pd::VolumeCorrection::moment);
  const auto s = section_stiffness(spec, section(4, 4), 0, 2, false);
  EXPECT_GT(s.bending, 0.0);
  EXPECT_LT(s.bending, 1.0);
  EXPECT_LT(s.shear, 1.0);
  EXPECT_LT(s.membrane, 1.0);
}

/// A 2D body (plane stress unless told, thickness 0.5) on a unit lattice with the given treatment.
pd::ModelSpec unit_lattice_2d(double horizon_factor, pd::SurfaceCorrection surface,
                              pd::VolumeCorrection volume,
                              pd::PlaneMode plane = pd::PlaneMode::plane_stress) {
  auto spec = unit_lattice(horizon_factor, surface, volume);
  spec.dimension.dim = 2;
  spec.dimension.plane = plane;
  spec.dimension.thickness = 0.5;
  spec.materials.front().poisson_ratio = plane == pd::PlaneMode::plane_stress ? 1.0 / 3.0 : 0.25;
  return spec;
}

pd::BodySpec strip(double depth) {
  pd::BodySpec b;
  b.name = "strip";
  b.region.boxes = {pd::Box{{0, 0, 0}, {1, depth, 0}}};
  return b;
}

constexpr double pi = 3.141592653589793;

// By hand, without corrections (m = 3, bonds at 1, 2, 3 spacings along the span, c = 9E/(π t δ³)):
// one layer under axial strain ε stores ¼·Σ_j c V_j |ξ| ε² per unit volume, 2·(1 + 2 + 3) bonds,
// so the layer's axial stiffness is c t λ³·6/E = 54/(27π) = 2/π of E·t·λ, and nothing resists
// curvature or shear (every bond lies along the span, on the neutral axis). Two layers: each
// layer is a chain at strain ±κλ/2 and the bonds between them sample d̄ = 0, so the bending
// stiffness is 2·(κλ/2)²·c t λ³·6 against E t (2λ)³/12 κ²: 3/(2π).
TEST(SectionStiffness, TwoDimensionalStripsWithoutCorrectionsAsByHand) {
  const auto spec = unit_lattice_2d(3.0, pd::SurfaceCorrection::none, pd::VolumeCorrection::none);
  const auto one = section_stiffness(spec, strip(1), 0, 1, false);
  EXPECT_EQ(one.section_particles, 1U);
  EXPECT_NEAR(one.membrane, 2 / pi, 1e-12);
  EXPECT_NEAR(one.bending, 0.0, 1e-12);
  EXPECT_NEAR(one.shear, 0.0, 1e-12);
  const auto two = section_stiffness(spec, strip(2), 0, 1, false);
  EXPECT_EQ(two.section_particles, 2U);
  EXPECT_NEAR(two.bending, 3 / (2 * pi), 1e-12);
  EXPECT_NEAR(two.bending_reference, 1.0 * 0.5 * 8 / 12, 1e-15); // E t h³/12
}

// The default treatment in 2D: ghosts complete every horizon, so a uniform shear costs each
// particle the bulk energy and the bulk's weights match the continuum; bending is within 0.2 %
// (measured 0.9990) and tension within 0.1 % (0.9997) at 8 layers, m = 2√3. Plane strain is plane
// stress with E/(1 − ν²) and ν/(1 − ν) for ν = 1/4: the same lattice sums against the same
// continuum, so the same factors.
TEST(SectionStiffness, TwoDimensionalDefaultTreatment) {
  const double m = 2 * 1.7320508075688772;
  const auto stress = section_stiffness(
      unit_lattice_2d(m, pd::SurfaceCorrection::ghost, pd::VolumeCorrection::gradient), strip(8), 0,
      1, false);
  const auto strain = section_stiffness(unit_lattice_2d(m, pd::SurfaceCorrection::ghost,
                                                        pd::VolumeCorrection::gradient,
                                                        pd::PlaneMode::plane_strain),
                                        strip(8), 0, 1, false);
  EXPECT_EQ(stress.section_particles, 8U);
  EXPECT_NEAR(stress.shear, 1.0, 1e-9);
  EXPECT_NEAR(stress.bending, 1.0, 2e-3);
  EXPECT_NEAR(stress.membrane, 1.0, 1e-3);
  EXPECT_NEAR(strain.bending, stress.bending, 1e-12);
  EXPECT_NEAR(strain.shear, stress.shear, 1e-12);
  EXPECT_NEAR(strain.membrane, stress.membrane, 1e-12);
}

// The default treatment in 3D, on the shipped beams' section (6 × 8 spacings, m = 2√3). Its
// ghosts are extrapolated from the relaxed body as in a run; treated as free particles instead
// they would let the surface relax where a run's cannot (bending factor about 0.98).
TEST(SectionStiffness, DefaultTreatmentBeamSection) {
  const auto spec = unit_lattice(2 * 1.7320508075688772, pd::SurfaceCorrection::ghost,
                                 pd::VolumeCorrection::gradient);
  const auto s = section_stiffness(spec, section(6, 8), 0, 2, false);
  EXPECT_EQ(s.section_particles, 48U);
  EXPECT_NEAR(s.shear, 1.0, 1e-9);
  EXPECT_NEAR(s.bending, 1.0, 2e-3);
  EXPECT_NEAR(s.membrane, 1.0, 1e-3);
}

// Timoshenko's split for the shipped cantilever (0.3 × 0.4 m, L = 3.5 m, E = 20 GPa, ν = 1/4):
// shear / bending deflection = 4 EI/(κ GA L²) = 4·3.2e7/(5/6·8e9·0.12·12.25) = 0.0130612…, as the
// FE reference's theory block has it ((5.93838 − 5.86182)/5.86182 mm).
TEST(SectionStiffness, TimoshenkoSplitOfTheShippedCantilever) {
  auto spec = unit_lattice(2 * 1.7320508075688772, pd::SurfaceCorrection::ghost,
                           pd::VolumeCorrection::gradient);
  spec.lattice.spacing = 0.05;
  spec.materials.front().youngs_modulus = 20e9;
  pd::BodySpec beam;
  beam.name = "beam";
  beam.region.boxes = {pd::Box{{0, 0, 0}, {3.5, 0.3, 0.4}}};
  const auto s = section_stiffness(spec, beam, 0, 2, false);
  EXPECT_NEAR(s.bending_reference, 20e9 * 0.3 * 0.064 / 12, 1e-3);
  EXPECT_NEAR(s.shear_reference, 8e9 * 0.12, 1e-3);
  const double r = pd::verification::timoshenko_shear_ratio(
      s, pd::verification::BeamCase::cantilever_uniform, 3.5);
  EXPECT_NEAR(r, 4 * 3.2e7 / (5.0 / 6.0 * 8e9 * 0.12 * 12.25), 1e-15);
  EXPECT_NEAR(r, (5.938378906250001e-3 - 5.86181640625e-3) / 5.86181640625e-3, 1e-12);
  EXPECT_NEAR(pd::verification::deflection_factor(s, r), (1 / s.bending + r / s.shear) / (1 + r),
              1e-15);
  // Clamped at both ends under a uniform load: 48 instead of 4.
  EXPECT_NEAR(
      pd::verification::timoshenko_shear_ratio(s, pd::verification::BeamCase::clamped_uniform, 3.5),
      12 * r, 1e-14);
}

// pd section finds the beam case in the scene: the shipped cantilever and clamped beam, and the
// same cantilever with a tip load or turned into a simply supported beam.
TEST(SectionStiffness, BeamCaseFromTheScenesSupportsAndLoads) {
  using pd::verification::beam_case_of;
  using pd::verification::BeamCase;
  const auto load = [](const std::string& name) {
    return pd::load_scene(std::string(PD_CASES_DIR) + "/" + name + "/" + name + ".yaml").model;
  };
  auto cantilever = load("cantilever");
  EXPECT_EQ(beam_case_of(cantilever, 0, 2), BeamCase::cantilever_uniform);
  EXPECT_EQ(beam_case_of(load("clamped-beam"), 0, 2), BeamCase::clamped_uniform);
  auto tip = cantilever;
  tip.loads.front().load.region.boxes.front().lo[0] = 3.45;
  EXPECT_EQ(beam_case_of(tip, 0, 2), BeamCase::cantilever_tip);
  auto root = cantilever; // a point load next to the clamp is none of the cases
  root.loads.front().load.region.boxes.front().hi[0] = 0.05;
  EXPECT_EQ(beam_case_of(root, 0, 2), std::nullopt);
  auto simple = cantilever;
  pd::SupportSpec roller;
  roller.name = "roller";
  roller.region.boxes = {pd::Box{{0, 0, 0}, {0.05, 0.3, 0.05}}};
  roller.fixed = {false, false, true};
  simple.supports = {roller, roller};
  simple.supports.back().region.boxes = {pd::Box{{3.45, 0, 0}, {3.5, 0.3, 0.05}}};
  EXPECT_EQ(beam_case_of(simple, 0, 2), BeamCase::simple_uniform);
}

TEST(SectionStiffness, RejectsEqualAxes) {
  const auto spec = unit_lattice(3.0, pd::SurfaceCorrection::none, pd::VolumeCorrection::none);
  EXPECT_THROW(section_stiffness(spec, section(4, 4), 2, 2, false), std::runtime_error);
}

} // namespace
