// Builds a 1D bar through the installed headers and library and prints its bond count.
#include <iostream>
#include <libpd/discretisation/model.hpp>

int main() {
  pd::ModelSpec spec;
  spec.surface_correction = pd::SurfaceCorrection::none; // the bare model
  spec.volume_correction = pd::VolumeCorrection::none;
  spec.dimension.dim = 1;
  spec.lattice.spacing = 0.1;
  spec.lattice.horizon_factor = 3.015;
  pd::Material steel;
  steel.name = "steel";
  steel.youngs_modulus = 200e9;
  steel.density = 7850;
  spec.materials = {steel};
  pd::BodySpec bar;
  bar.name = "bar";
  bar.region.boxes = {pd::Box{{0, 0, 0}, {1, 0, 0}}};
  spec.bodies = {bar};
  const pd::Model model = pd::build_model(spec);
  // 10 particles, each bonded to up to 3 neighbours per side: 9 + 8 + 7 = 24 bonds.
  std::cout << "particles " << model.size() << " bonds " << model.family.bond_count() << "\n";
  return model.size() == 10 && model.family.bond_count() == 24 ? 0 : 1;
}
