// Default accuracy of mesh bodies (issue 39): the `gradient` weights solved per particle of an
// unstructured set (particle_gradient_weights, corrections.hpp) against the continuum. Each
// check displaces every particle, ghosts included, by a field the ghosts' quadratic fits
// reproduce, so the energy W_c is the sum of the body particles' own energies.
#include "libpd/io/scene.hpp"
#include "libpd/kernel/force_kernel.hpp"
#include "mesh_fixtures.hpp"

#include <array>
#include <cmath>
#include <gtest/gtest.h>
#include <string>
#include <vector>

namespace {

using namespace mesh_test;

/// The positions of `model`'s particles displaced by u(x).
template <class Field>
std::vector<double> displaced(const pd::Model& model, Field u) {
  std::vector<double> y(3 * model.size());
  for (std::size_t i = 0; i < model.size(); ++i) {
    const pd::Vec3& x = model.particles.position[i];
    const pd::Vec3 d = u(x);
    for (std::size_t a = 0; a < 3; ++a) {
      y[3 * i + a] = x[a] + d[a];
    }
  }
  return y;
}

template <class Field>
double energy_under(pd::Model& model, Field u) {
  return pd::make_force_evaluator(model)->strain_energy(displaced(model, u).data());
}

double body_volume(const pd::Model& model) {
  double volume = 0;
  for (std::size_t i = 0; i < model.body_particle_count(); ++i) {
    volume += model.particles.volume[i];
  }
  return volume;
}

// The patch test on an unstructured set: a plate of Gmsh's triangles under uniform strain, with
// the mesh bodies' default corrections (ghost layers outside its elements, `gradient` weights
// solved per particle for its irregular quadrature). Every ghost is displaced exactly (its
// quadratic fit reproduces a linear field), so the energy W_c is Σ over the body particles of their
// own energies; the continuum's is ½ε:C:ε over the plate's area.
struct UniformStrain {
  double xx, yy, xy;
  double energy_density; ///< of the continuum [J/m³]
};

double energy_ratio_of_triangle_plate(const fs::path& dir, const UniformStrain& s,
                                      const std::string& fill = "elements") {
  write(dir / "plate.geo", "SetFactory(\"OpenCASCADE\");\nRectangle(1) = {0, 0, 0, 0.1, 0.05};\n"
                           "Physical Surface(\"plate\") = {1};\n");
  const std::string path = write(
      dir / "plate.yaml", "dimension: 2\nplane: stress\nthickness: 0.01\n"
                          "lattice: {spacing: 0.0025}\n"
                          "materials: {steel: {youngs_modulus: 200e9, density: 7800}}\n"
                          "bodies: [{name: plate, material: steel, geometry: plate.geo, fill: " +
                              fill + "}]\nsolver: {integrator: static}\n");
  pd::Model model = pd::build_model(pd::load_scene(path));
  EXPECT_GT(model.ghost_count, 0U);
  return energy_under(model,
                      [&](const pd::Vec3& x) {
                        return pd::Vec3{s.xx * x[0] + s.xy * x[1], s.xy * x[0] + s.yy * x[1], 0};
                      }) /
         (s.energy_density * body_volume(model));
}

constexpr double patch_strain = 1e-4, patch_young = 200e9, patch_nu = 1.0 / 3;

TEST_F(MeshFile, UnstructuredTrianglesStoreTheContinuumEnergyUnderUniaxialStress) {
  const fs::path dir = temp_folder("patch");
  const double e = patch_strain, w = 0.5 * patch_young * e * e;
  EXPECT_NEAR(energy_ratio_of_triangle_plate(dir, {e, -patch_nu * e, 0, w}), 1.0, 1e-3);
  EXPECT_NEAR(energy_ratio_of_triangle_plate(dir, {-patch_nu * e, e, 0, w}), 1.0, 1e-3);
}

// Shear loads the bonds' n_x²n_y² moment, which `tensor`'s axis factors alone do not reach (they
// left +1.5 %); the per-particle `gradient` weights match every 4th moment before a pair's two
// ends share their weight.
TEST_F(MeshFile, UnstructuredTrianglesStoreTheContinuumEnergyUnderShear) {
  const fs::path dir = temp_folder("patch-shear");
  const double e = patch_strain;
  const double w = 0.5 * patch_young / (2 * (1 + patch_nu)) * e * e; // ½Gγ²
  EXPECT_NEAR(energy_ratio_of_triangle_plate(dir, {0, 0, e / 2, w}), 1.0, 1e-3);
}

// `fill: lattice` turns the same part into lattice particles, which take the lattice's default
// weights (gradient_weights.cpp): uniaxial stress and shear alike.
TEST_F(MeshFile, APartFilledWithTheLatticeStoresTheContinuumEnergyUnderAnyUniformStrain) {
  const fs::path dir = temp_folder("patch-lattice");
  const double e = patch_strain, w = 0.5 * patch_young * e * e;
  EXPECT_NEAR(energy_ratio_of_triangle_plate(dir, {e, -patch_nu * e, 0, w}, "lattice"), 1.0, 1e-3);
  EXPECT_NEAR(energy_ratio_of_triangle_plate(dir, {-patch_nu * e, e, 0, w}, "lattice"), 1.0, 1e-3);
  const double shear = 0.5 * patch_young / (2 * (1 + patch_nu)) * e * e;
  EXPECT_NEAR(energy_ratio_of_triangle_plate(dir, {0, 0, e / 2, shear}, "lattice"), 1.0, 1e-3);
}

// A mesh body's `gradient` weights are solved per particle (particle_gradient_weights). On
// hexahedra that are the lattice's cells every particle's equations are the lattice's, whose orbit
// weights are their unique closest-to-uniform solution: the mesh body must store the lattice cube's
// energy under a quadratic field (bending and a varying stretch), to round-off.
TEST_F(MeshFile, PerParticleGradientWeightsOnLatticeCellsAreTheLatticeWeights) {
  const fs::path dir = temp_folder("per-particle");
  write(dir / "hexes.msh", box_mesh(6, 0.6, false).text());
  const pd::Scene scene = pd::load_scene(write(dir / "part.yaml", scene_text("hexes.msh", "")));
  ASSERT_EQ(scene.model.volume_correction, pd::VolumeCorrection::gradient);
  ASSERT_TRUE(scene.model.corrections().unstructured);
  pd::Model mesh = pd::build_model(scene);
  pd::ModelSpec lattice = scene.model;
  lattice.bodies[0].points = nullptr;
  lattice.bodies[0].mesh = false;
  lattice.bodies[0].region.boxes = {pd::Box{{0, 0, 0}, {0.6, 0.6, 0.6}}};
  lattice.supports.clear();
  lattice.loads.clear();
  ASSERT_FALSE(lattice.corrections().unstructured);
  pd::Model cube = pd::build_model(lattice);
  // The mesh body's ghosts reach a spacing further (stiff_bond_reach); their bonds take no
  // stiffness here, so they leave the family.
  ASSERT_GT(mesh.size(), cube.size());
  ASSERT_EQ(mesh.family.directed_bond_count(), cube.family.directed_bond_count());
  // Every particle met the lattice's equations, as the report says; the lattice ran no such solve.
  EXPECT_EQ(mesh.particle_weights.matched, mesh.body_particle_count());
  EXPECT_EQ(mesh.particle_weights.moments_only + mesh.particle_weights.unmatched, 0U);
  EXPECT_LT(mesh.particle_weights.residual, 1e-10);
  EXPECT_GT(mesh.particle_weights.seconds, 0.0);
  EXPECT_EQ(cube.particle_weights.seconds, 0.0);
  const auto energy = [](pd::Model m) {
    return energy_under(m, [](const pd::Vec3& x) {
      return pd::Vec3{1e-4 * (x[0] * x[2] + 0.5 * x[1] * x[1]), 1e-4 * x[0] * x[1],
                      -0.5e-4 * x[0] * x[0]};
    });
  };
  const double lattice_energy = energy(cube);
  EXPECT_NEAR(energy(mesh) / lattice_energy, 1.0, 1e-9);
  // The same mesh with the per-particle solve replaced by `tensor` alone (the former default)
  // stores a different energy (by 0.6 %): the check can fail.
  pd::Scene tensor = scene;
  tensor.model.volume_correction = pd::VolumeCorrection::tensor;
  EXPECT_GT(std::abs(energy(pd::build_model(tensor)) / lattice_energy - 1.0), 1e-3);
}

// The patch test in 3D: a cube of tetrahedra (each lattice cell split into tetrahedra of two
// shapes and volumes) under uniform strain stores the continuum's energy, in tension and in shear.
TEST_F(MeshFile, UnstructuredTetrahedraStoreTheContinuumEnergyUnderUniformStrain) {
  const fs::path dir = temp_folder("patch-tets");
  write(dir / "tets.msh", box_mesh(6, 0.6, true).text());
  pd::Model model = pd::build_model(pd::load_scene(
      write(dir / "part.yaml", "dimension: 3\nlattice: {spacing: 0.1}\n"
                               "materials: {steel: {youngs_modulus: 200e9, density: 7800}}\n"
                               "bodies: [{name: part, material: steel, mesh: tets.msh}]\n"
                               "solver: {integrator: static}\n")));
  ASSERT_GT(model.ghost_count, 0U);
  const pd::ParticleGradientWeights& solved = model.particle_weights;
  EXPECT_EQ(solved.matched + solved.moments_only + solved.unmatched, model.body_particle_count());
  EXPECT_GT(solved.matched, 0U);
  const double volume = body_volume(model);
  const double e = patch_strain, nu = 0.25, young = 200e9;
  const auto ratio = [&](const std::array<std::array<double, 3>, 3>& eps, double w) {
    return energy_under(model,
                        [&](const pd::Vec3& x) {
                          pd::Vec3 u{0, 0, 0};
                          for (std::size_t a = 0; a < 3; ++a) {
                            for (std::size_t b = 0; b < 3; ++b) {
                              u[a] += eps[a][b] * x[b];
                            }
                          }
                          return u;
                        }) /
           (w * volume);
  };
  const double tension = 0.5 * young * e * e, shear = 0.5 * young / (2 * (1 + nu)) * e * e;
  EXPECT_NEAR(ratio({{{e, 0, 0}, {0, -nu * e, 0}, {0, 0, -nu * e}}}, tension), 1.0, 1e-3);
  EXPECT_NEAR(ratio({{{-nu * e, 0, 0}, {0, -nu * e, 0}, {0, 0, e}}}, tension), 1.0, 1e-3);
  EXPECT_NEAR(ratio({{{0, e / 2, 0}, {e / 2, 0, 0}, {0, 0, 0}}}, shear), 1.0, 1e-3);
  EXPECT_NEAR(ratio({{{0, 0, 0}, {0, 0, e / 2}, {0, e / 2, 0}}}, shear), 1.0, 1e-3);
}

// ---- strain gradients and forces on tetrahedra --------------------------------------------------
//
// A cube of side L (steel, ν = 1/4: C₁₁ = 1.2 E, μ = 0.4 E) bent about the mid-plane z = L/2 with
// curvature κ, u = (−κ z'x', 0, κ x'²/2) (x', z' about the centre: uniaxial strain ε_xx = −κ z'),
// stores ½ C₁₁ κ² ∫ z'² dV; twisted, u = (−κ z'y', −κ z'x', κ x'y') (ε_xy = −κ z'), 2μ κ² ∫ z'² dV.
struct Bending {
  double bend;  ///< energy under bending over the continuum's
  double twist; ///< energy under twist over the continuum's
};

Bending bending_of(pd::Model& model, double side) {
  const double k = 1e-4, c = side / 2, young = 200e9;
  const double inertia = side * side * side * side * side / 12; // ∫ z'² dV
  const double bend = energy_under(model, [&](const pd::Vec3& x) {
    return pd::Vec3{-k * (x[2] - c) * (x[0] - c), 0, 0.5 * k * (x[0] - c) * (x[0] - c)};
  });
  const double twist = energy_under(model, [&](const pd::Vec3& x) {
    return pd::Vec3{-k * (x[2] - c) * (x[1] - c), -k * (x[2] - c) * (x[0] - c),
                    k * (x[0] - c) * (x[1] - c)};
  });
  return {bend / (0.6 * young * k * k * inertia), twist / (0.8 * young * k * k * inertia)};
}

/// The largest force a uniform strain ε_xx = e leaves on a body particle at least `inset` from
/// every face of the cube [0, side]³, as |b_i| V_i over E e V_i^(2/3) (the stress on its face).
double largest_force_under_uniform_strain(pd::Model& model, double side, double inset) {
  const double e = 1e-4, young = 200e9;
  std::vector<double> y = displaced(model, [&](const pd::Vec3& x) {
    return pd::Vec3{e * x[0], 0, 0};
  });
  std::vector<double> b(y.size(), 0.0);
  pd::make_force_evaluator(model)->compute(y.data(), b.data());
  double largest = 0;
  for (std::size_t i = 0; i < model.body_particle_count(); ++i) {
    const pd::Vec3& x = model.particles.position[i];
    bool inside = true;
    for (std::size_t a = 0; a < 3; ++a) {
      inside = inside && x[a] > inset && x[a] < side - inset;
    }
    if (inside) {
      const double v = model.particles.volume[i];
      const double f = std::sqrt(b[3 * i] * b[3 * i] + b[3 * i + 1] * b[3 * i + 1] +
                                 b[3 * i + 2] * b[3 * i + 2]);
      largest = std::max(largest, f * v / (young * e * std::cbrt(v * v)));
    }
  }
  return largest;
}

pd::Model lattice_cube(const fs::path& dir, double side) {
  return pd::build_model(pd::load_scene(
      write(dir / "cube.yaml", "dimension: 3\nlattice: {spacing: 0.1}\n"
                               "materials: {steel: {youngs_modulus: 200e9, density: 7800}}\n"
                               "bodies: [{name: cube, material: steel, box: [[0, 0, 0], [" +
                                   std::to_string(side) + ", " + std::to_string(side) + ", " +
                                   std::to_string(side) + "]]}]\nsolver: {integrator: static}\n")));
}

pd::Model kuhn_cube(const fs::path& dir, std::size_t cells) {
  write(dir / "tets.msh", box_mesh(cells, 0.1 * static_cast<double>(cells), true).text());
  return pd::build_model(pd::load_scene(
      write(dir / "part.yaml", "dimension: 3\nlattice: {spacing: 0.1}\n"
                               "materials: {steel: {youngs_modulus: 200e9, density: 7800}}\n"
                               "bodies: [{name: part, material: steel, mesh: tets.msh}]\n"
                               "solver: {integrator: static}\n")));
}

// What the tetrahedra are held to: the lattice's own `gradient` weights and ghosts store the
// continuum's energy under bending and twist, even six cells deep, and leave no force inside
// under a uniform strain.
TEST(LatticeCube, StoresTheContinuumEnergyUnderBendingAndLeavesNoForceUnderUniformStrain) {
  const fs::path dir = temp_folder("lattice-bending");
  pd::Model six = lattice_cube(dir, 0.6);
  const Bending b = bending_of(six, 0.6);
  EXPECT_NEAR(b.bend, 1.0, 1e-3);
  EXPECT_NEAR(b.twist, 1.0, 1e-3);
  pd::Model eight = lattice_cube(dir, 0.8);
  EXPECT_LT(largest_force_under_uniform_strain(eight, 0.8, 0.3), 1e-9);
}

// Not met (issue 39): the 6th-moment rows copy the lattice cell's strain-gradient energy,
// (λ²/24) Σ_c G_c : C : G_c, but a tetrahedron's material spreads about its centroid about half
// as far as a cell's (∫ |x − x_i|² dV over its volume), so the quadrature already holds most of
// what the cell term adds. Matching each element's own spread instead has no non-negative
// solution over the bonds within 3λ (none of the 2,623 particles of the 0.1 m cantilever-tet).
// Measured: bending +1.20 %, twist +1.29 % on these Kuhn tetrahedra six cells deep; +12.2 % in
// bending on Gmsh's tetrahedra of the plate of verification/scenes/user/plate-3clamped-tet.yaml
// (two elements deep), where the lattice plate stores the continuum's to 1e-4.
TEST_F(MeshFile, DISABLED_UnstructuredTetrahedraStoreTheContinuumEnergyUnderBending) {
  pd::Model model = kuhn_cube(temp_folder("tets-bending"), 6);
  const Bending b = bending_of(model, 0.6);
  EXPECT_NEAR(b.bend, 1.0, 1e-3);
  EXPECT_NEAR(b.twist, 1.0, 1e-3);
}

// Not met (issue 39): each particle's own weights have no 3rd moment, but a pair takes the mean
// of its two ends' weights, which leaves each end one: a uniform strain then leaves forces, and
// under load the particles relax against them, so the set is softer than the continuum it stores
// exactly under the uniform strain.
// Measured: 0.0147 on these Kuhn tetrahedra; on Gmsh's tetrahedra of a 1 m cube (λ = 0.1 m) 0.33,
// root mean square 0.13.
TEST_F(MeshFile, DISABLED_UnstructuredTetrahedraLeaveNoForceUnderUniformStrain) {
  pd::Model model = kuhn_cube(temp_folder("tets-force"), 8);
  EXPECT_LT(largest_force_under_uniform_strain(model, 0.8, 0.3), 1e-9);
}

} // namespace
