// Section-stiffness error budget (verification/cases/section_stiffness.hpp): the relaxed stiffness
// of a PD cross-section against the continuum it discretises.
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

TEST(SectionStiffness, RejectsEqualAxes) {
  const auto spec = unit_lattice(3.0, pd::SurfaceCorrection::none, pd::VolumeCorrection::none);
  EXPECT_THROW(section_stiffness(spec, section(4, 4), 2, 2, false), std::runtime_error);
}

} // namespace
