// Bodies from meshes and geometry files (io/mesh_file.hpp): one particle per element with its
// volume, physical groups as particle sets and as scene regions, and each bad input refused with
// the file and the element or group named. The meshes are written here as .msh text (format 2.2),
// so the element counts and volumes are known without Gmsh.
#include "libpd/io/mesh_file.hpp"
#include "libpd/io/scene.hpp"
#include "libpd/kernel/force_kernel.hpp"
#include "mesh_fixtures.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <gtest/gtest.h>
#include <numeric>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#ifdef LIBPD_TEST_GMSH
#include <dlfcn.h>
#include <gmshc.h>
#endif

namespace {

namespace fs = std::filesystem;
using namespace mesh_test;

TEST_F(MeshFile, HexahedraAndTetrahedraGiveOneParticlePerElementWithTheirVolume) {
  const fs::path dir = temp_folder("solids");
  for (const bool tets : {false, true}) {
    const double size = 0.3;
    const Msh m = box_mesh(3, size, tets);
    const std::string path = write(dir / (tets ? "tets.msh" : "hexes.msh"), m.text());
    const pd::MeshBody body = pd::read_mesh_file(path, 3, 1.0);
    const std::size_t elements = count_of(m, tets ? 4 : 5);
    EXPECT_EQ(elements, tets ? 162U : 27U);
    ASSERT_EQ(body.cloud.count(), elements);
    EXPECT_NEAR(total(body.cloud.volume), size * size * size, 1e-12 * size * size * size);
    // Every particle inside the box, each cell's particles centred on it.
    pd::Vec3 mean{0, 0, 0};
    for (std::size_t i = 0; i < body.cloud.count(); ++i) {
      for (std::size_t a = 0; a < 3; ++a) {
        EXPECT_GT(body.cloud.position[i][a], 0);
        EXPECT_LT(body.cloud.position[i][a], size);
        mean[a] += body.cloud.position[i][a] * body.cloud.volume[i];
      }
    }
    for (std::size_t a = 0; a < 3; ++a) {
      EXPECT_NEAR(mean[a] / (size * size * size), size / 2, 1e-12 * size);
    }
    if (!tets) { // each hexahedron's particle at its cell's centre, with the cell's volume
      const double h = size / 3;
      for (std::size_t i = 0; i < body.cloud.count(); ++i) {
        for (std::size_t a = 0; a < 3; ++a) {
          const double cells = body.cloud.position[i][a] / h - 0.5;
          EXPECT_NEAR(cells, std::round(cells), 1e-12);
        }
        EXPECT_NEAR(body.cloud.volume[i], h * h * h, 1e-12 * h * h * h);
      }
    }
  }
}

TEST_F(MeshFile, TrianglesAndQuadranglesGiveAreaTimesThickness) {
  const fs::path dir = temp_folder("plates");
  const double a = 0.4, b = 0.1, thickness = 0.01;
  for (const bool triangles : {false, true}) {
    const Msh m = plate_mesh(8, 2, a, b, triangles);
    const std::string path = write(dir / (triangles ? "tris.msh" : "quads.msh"), m.text());
    const pd::MeshBody body = pd::read_mesh_file(path, 2, thickness);
    ASSERT_EQ(body.cloud.count(), count_of(m, triangles ? 2 : 3));
    EXPECT_EQ(body.cloud.count(), triangles ? 32U : 16U);
    EXPECT_NEAR(total(body.cloud.volume), a * b * thickness, 1e-12 * a * b * thickness);
  }
  // The same plate wound the other way round (every element clockwise) is as good.
  Msh flipped = plate_mesh(8, 2, a, b, true);
  for (Element& e : flipped.elements) {
    std::reverse(e.nodes.begin(), e.nodes.end());
  }
  const pd::MeshBody body = pd::read_mesh_file(write(dir / "cw.msh", flipped.text()), 2, thickness);
  EXPECT_NEAR(total(body.cloud.volume), a * b * thickness, 1e-12 * a * b * thickness);
}

TEST_F(MeshFile, PhysicalGroupsNameTheirElementsParticles) {
  const fs::path dir = temp_folder("groups");
  const double size = 0.3;
  const pd::MeshBody body =
      pd::read_mesh_file(write(dir / "hexes.msh", box_mesh(3, size, false).text()), 3, 1.0);
  // A face group: the particles of the elements with a node on that face (x index 0: 9 of 27).
  const auto& left = body.group("left");
  ASSERT_EQ(left.size(), 9U);
  for (const std::uint32_t p : left) {
    EXPECT_NEAR(body.cloud.position[p][0], size / 6, 1e-15);
  }
  // Volume groups: their elements' particles, a layer of 9 each.
  EXPECT_EQ(body.group("front"), left);
  EXPECT_EQ(body.group("back").size(), 9U);
  EXPECT_EQ(body.group("body").size(), 9U);
  // 2D: an edge group.
  const pd::MeshBody plate =
      pd::read_mesh_file(write(dir / "tris.msh", plate_mesh(8, 2, 0.4, 0.1, true).text()), 2, 0.01);
  const auto& right = plate.group("right");
  // Both triangles of each of the two cells at x = a: one has an edge on it, the other a corner.
  ASSERT_EQ(right.size(), 4U);
  for (const std::uint32_t p : right) {
    EXPECT_GT(plate.cloud.position[p][0], 0.4 - 0.05);
  }
  const std::string missing = error_of([&] { (void)plate.group("left"); });
  EXPECT_TRUE(contains(missing, "tris.msh")) << missing;
  EXPECT_TRUE(contains(missing, "'left'")) << missing;
  EXPECT_TRUE(contains(missing, "'right'")) << missing; // the groups it has
}

TEST_F(MeshFile, BadMeshesAreRefusedNamingTheFileAndTheElement) {
  const fs::path dir = temp_folder("bad");
  EXPECT_EQ(error_of([&] { (void)pd::read_mesh_file((dir / "none.msh").string(), 3, 1.0); }),
            (dir / "none.msh").string() + ": no such file");

  Msh inverted = box_mesh(2, 1.0, true);
  std::swap(inverted.elements[5].nodes[2], inverted.elements[5].nodes[3]);
  const std::string inv = write(dir / "inverted.msh", inverted.text());
  const std::string inverted_error = error_of([&] { (void)pd::read_mesh_file(inv, 3, 1.0); });
  EXPECT_TRUE(contains(inverted_error, inv + ": element 6 ")) << inverted_error;
  EXPECT_TRUE(contains(inverted_error, "inverted")) << inverted_error;

  Msh flat = box_mesh(2, 1.0, true);
  flat.nodes.push_back({0.5, 0.5, 0.0}); // four points of the plane z = 0
  flat.elements.push_back({4, 1, {1, 2, 3, flat.nodes.size()}});
  const std::string zero = write(dir / "zero.msh", flat.text());
  const std::string zero_error = error_of([&] { (void)pd::read_mesh_file(zero, 3, 1.0); });
  EXPECT_TRUE(contains(zero_error, zero + ": element 49 ")) << zero_error;
  EXPECT_TRUE(contains(zero_error, "zero volume")) << zero_error;

  // 2D: one triangle wound against all the others.
  Msh turned = plate_mesh(4, 2, 1.0, 0.5, true);
  std::reverse(turned.elements[3].nodes.begin(), turned.elements[3].nodes.end());
  const std::string turn = write(dir / "turned.msh", turned.text());
  const std::string turned_error = error_of([&] { (void)pd::read_mesh_file(turn, 2, 1.0); });
  EXPECT_TRUE(contains(turned_error, turn + ": element 4 ")) << turned_error;
  EXPECT_TRUE(contains(turned_error, "inverted")) << turned_error;

  // The scene's dimension is not the mesh's.
  const std::string hexes = write(dir / "hexes.msh", box_mesh(2, 1.0, false).text());
  EXPECT_TRUE(contains(error_of([&] { (void)pd::read_mesh_file(hexes, 2, 1.0); }),
                       hexes + ": is a 3D model, the scene is 2D"));

  // An STL surface with a hole: a tetrahedron's surface less one facet.
  const std::string stl = write(dir / "open.stl", "solid open\n"
                                                  "facet normal 0 0 -1\nouter loop\n"
                                                  "vertex 0 0 0\nvertex 0 1 0\nvertex 1 0 0\n"
                                                  "endloop\nendfacet\n"
                                                  "facet normal 0 -1 0\nouter loop\n"
                                                  "vertex 0 0 0\nvertex 1 0 0\nvertex 0 0 1\n"
                                                  "endloop\nendfacet\n"
                                                  "facet normal -1 0 0\nouter loop\n"
                                                  "vertex 0 0 0\nvertex 0 0 1\nvertex 0 1 0\n"
                                                  "endloop\nendfacet\n"
                                                  "endsolid open\n");
  const std::string open_error = error_of([&] { (void)pd::mesh_geometry_file(stl, 3, 1.0, 0.2); });
  EXPECT_TRUE(contains(open_error, stl + ": the surface is not closed")) << open_error;
  EXPECT_TRUE(contains(open_error, "belongs to 1 triangle")) << open_error;
}

/// A 2D plate 0.1 × 0.05 with a hole of radius 0.01 at (0.05, 0.025), OpenCASCADE kernel.
const char* plate_with_hole_geo = R"(SetFactory("OpenCASCADE");
Rectangle(1) = {0, 0, 0, 0.1, 0.05};
Disk(2) = {0.05, 0.025, 0, 0.01};
BooleanDifference(3) = {Surface{1}; Delete;}{Surface{2}; Delete;};
Physical Surface("plate") = {3};
)";

#ifdef LIBPD_TEST_GMSH
/// A symbol of Gmsh's C API, the library opened at run time: this test binary does not link Gmsh,
/// so that it starts without loading it, as pd does (tests/cli/plugins.py).
template <class F>
F* gmsh_function(const char* name) {
  static void* const gmsh = dlopen(LIBPD_TEST_GMSH, RTLD_NOW | RTLD_LOCAL);
  if (!gmsh) {
    throw std::runtime_error(std::string("cannot open Gmsh: ") + dlerror());
  }
  void* f = dlsym(gmsh, name);
  if (!f) {
    throw std::runtime_error(std::string("Gmsh has no ") + name);
  }
  return reinterpret_cast<F*>(f);
}
#define GMSH(name) gmsh_function<decltype(name)>(#name)

/// The number of elements of dimension `dim` Gmsh itself makes of `geo` at elements of size at
/// most `size`, independently of libpd.
std::size_t gmsh_element_count(const std::string& geo, int dim, double size) {
  int ierr = 0;
  GMSH(gmshInitialize)(0, nullptr, 0, &ierr);
  GMSH(gmshOptionSetNumber)("General.Terminal", 0, &ierr);
  GMSH(gmshOptionSetNumber)("General.NumThreads", 1, &ierr);
  GMSH(gmshOpen)(geo.c_str(), &ierr);
  GMSH(gmshOptionSetNumber)("Mesh.MeshSizeMax", size, &ierr);
  GMSH(gmshModelMeshGenerate)(dim, &ierr);
  int* types = nullptr;
  std::size_t types_n = 0, tags_nn = 0, nodes_nn = 0;
  std::size_t **tags = nullptr, **nodes = nullptr;
  std::size_t *tags_n = nullptr, *nodes_n = nullptr;
  GMSH(gmshModelMeshGetElements)
  (&types, &types_n, &tags, &tags_n, &tags_nn, &nodes, &nodes_n, &nodes_nn, dim, -1, &ierr);
  EXPECT_EQ(ierr, 0);
  std::size_t count = 0;
  const auto free = GMSH(gmshFree);
  for (std::size_t t = 0; t < tags_nn; ++t) {
    count += tags_n[t];
    free(tags[t]);
  }
  for (std::size_t t = 0; t < nodes_nn; ++t) {
    free(nodes[t]);
  }
  free(types);
  free(tags);
  free(tags_n);
  free(nodes);
  free(nodes_n);
  GMSH(gmshFinalize)(&ierr);
  return count;
}
#endif

TEST_F(MeshFile, GeometryWithAHoleIsMeshedAtTheSpacing) {
  const fs::path dir = temp_folder("geo");
  const std::string geo = write(dir / "plate.geo", plate_with_hole_geo);
  const double spacing = 0.0025, thickness = 0.01;
  const pd::MeshBody body = pd::mesh_geometry_file(geo, 2, thickness, spacing);
  // The hole's wall is a polygon inscribed in the circle: the area lies between the plate less
  // the circle and the plate less the inscribed square.
  const double r = 0.01;
  const double area = total(body.cloud.volume) / thickness;
  EXPECT_GT(area, 0.1 * 0.05 - M_PI * r * r);
  EXPECT_LT(area, 0.1 * 0.05 - 2 * r * r);
  // Elements no larger than the spacing: at least the area over that of a triangle of side λ.
  EXPECT_GT(static_cast<double>(body.cloud.count()),
            area / (std::sqrt(3.0) / 4 * spacing * spacing));
  for (const pd::Vec3& p : body.cloud.position) {
    EXPECT_GT(std::hypot(p[0] - 0.05, p[1] - 0.025), r); // no particle in the hole
  }
  EXPECT_EQ(body.group("plate").size(), body.cloud.count());
  // Meshed twice, the same particles: one thread, the same mesh.
  const pd::MeshBody again = pd::mesh_geometry_file(geo, 2, thickness, spacing);
  EXPECT_EQ(again.cloud.position, body.cloud.position);
  EXPECT_EQ(again.cloud.volume, body.cloud.volume);
#ifdef LIBPD_TEST_GMSH
  // The element count Gmsh itself makes of the file at that size.
  const std::size_t count = gmsh_element_count(geo, 2, spacing);
  EXPECT_EQ(body.cloud.count(), count);
#endif
}

// The lattice sites inside a rectangle's triangles are the rectangle's lattice, ghosts and all;
// a face group holds the sites inside the elements along the face.
TEST_F(MeshFile, AGeometryFilledWithTheLatticeIsTheLatticeOfItsRegion) {
  const fs::path dir = temp_folder("fill");
  write(dir / "plate.geo", "SetFactory(\"OpenCASCADE\");\nRectangle(1) = {0, 0, 0, 0.1, 0.05};\n"
                           "Physical Curve(\"left\") = {4};\n");
  const std::string text = "dimension: 2\nplane: stress\nthickness: 0.01\n"
                           "lattice: {spacing: 0.005}\n"
                           "materials: {steel: {youngs_modulus: 200e9, density: 7800}}\n"
                           "bodies: [{name: plate, material: steel, geometry: plate.geo, "
                           "fill: lattice}]\n"
                           "supports: [{name: grip, group: left, fixed: [x, y]}]\n"
                           "solver: {integrator: static}\n";
  const pd::Scene scene = pd::load_scene(write(dir / "plate.yaml", text));
  EXPECT_EQ(scene.model.volume_correction, pd::ModelSpec{}.volume_correction);
  EXPECT_EQ(scene.model.surface_correction, pd::ModelSpec{}.surface_correction);
  EXPECT_TRUE(pd::mesh_corrections_note(scene.model).empty());
  const pd::Model model = pd::build_model(scene);
  std::string plain = text;
  plain.replace(plain.find("geometry: plate.geo, fill: lattice"), 34, "box: [[0, 0], [0.1, 0.05]]");
  plain.erase(plain.find("supports:"), plain.find("solver:") - plain.find("supports:"));
  const pd::Model box = pd::build_model(pd::load_scene(write(dir / "box.yaml", plain)));
  ASSERT_EQ(model.size() - model.ghost_count, 200U);
  ASSERT_EQ(model.size(), box.size());
  for (std::size_t i = 0; i < model.size(); ++i) {
    for (std::size_t a = 0; a < 3; ++a) {
      ASSERT_EQ(model.particles.position[i][a], box.particles.position[i][a]) << i;
    }
    ASSERT_EQ(model.particles.volume[i], box.particles.volume[i]) << i;
  }
  std::set<std::uint32_t> held;
  for (const pd::Constraint& c : model.constraints) {
    if (c.particle < model.size() - model.ghost_count) {
      held.insert(c.particle);
      EXPECT_LT(model.particles.position[c.particle][0], 0.0075);
    }
  }
  EXPECT_GE(held.size(), 10U); // the first column at least

  std::string boxed = text;
  boxed.replace(boxed.find("geometry: plate.geo, "), 21, "box: [[0, 0], [0.1, 0.05]], ");
  try {
    (void)pd::load_scene(write(dir / "boxed.yaml", boxed));
    ADD_FAILURE() << "'fill' on a box body was accepted";
  } catch (const pd::SceneError& e) {
    EXPECT_TRUE(contains(e.what(), "'fill' applies to 'mesh' and 'geometry' bodies")) << e.what();
  }
}

TEST_F(MeshFile, PhysicalGroupsAreSceneRegionsAndMeshBodiesTakeLatticeFreeCorrections) {
  const fs::path dir = temp_folder("scene");
  write(dir / "hexes.msh", box_mesh(3, 0.3, false).text());
  const std::string path = write(dir / "part.yaml", scene_text("hexes.msh", ""));
  const pd::Scene scene = pd::load_scene(path);
  EXPECT_EQ(scene.model.surface_correction, pd::mesh_surface_correction);
  EXPECT_EQ(scene.model.volume_correction, pd::mesh_volume_correction);
  const pd::Model model = pd::build_model(scene);
  ASSERT_EQ(model.size() - model.ghost_count, 27U);
  // These hexahedra are the lattice's cells: the mesh body has the ghost sites (ghost_layers.hpp)
  // that the same cube filled with the lattice has, none inside it. Compared over the whole
  // horizon (`volume_correction: none`): under `gradient` a mesh body's ghosts reach one spacing
  // further than the lattice's (stiff_bond_reach).
  pd::Scene whole_horizon = scene;
  whole_horizon.model.volume_correction = pd::VolumeCorrection::none;
  const pd::Model mesh_ghosts = pd::build_model(whole_horizon);
  pd::ModelSpec lattice = whole_horizon.model;
  lattice.bodies[0].points = nullptr;
  lattice.bodies[0].mesh = false;
  lattice.bodies[0].region.boxes = {pd::Box{{0, 0, 0}, {0.3, 0.3, 0.3}}};
  lattice.supports.clear(); // their groups are the mesh's particles
  lattice.loads.clear();
  const pd::Model cube = pd::build_model(lattice);
  ASSERT_EQ(cube.size(), mesh_ghosts.size());
  EXPECT_GT(mesh_ghosts.ghost_count, 27U);
  for (std::size_t g = 27; g < mesh_ghosts.size(); ++g) {
    for (std::size_t a = 0; a < 3; ++a) {
      EXPECT_NEAR(mesh_ghosts.particles.position[g][a], cube.particles.position[g][a], 1e-12);
    }
  }
  std::set<std::uint32_t> held;
  for (const pd::Constraint& c : model.constraints) {
    held.insert(c.particle);
    EXPECT_NEAR(model.particles.position[c.particle][0], 0.05, 1e-15);
  }
  EXPECT_EQ(held.size(), 9U);
  EXPECT_EQ(model.constraints.size(), 27U);
  double fz = 0;
  std::size_t loaded = 0;
  for (std::size_t i = 0; i < model.size(); ++i) {
    const double f = model.external_force_density[3 * i + 2] * model.particles.volume[i];
    fz += f;
    loaded += f != 0 ? 1 : 0;
    if (f != 0) {
      EXPECT_NEAR(model.particles.position[i][0], 0.25, 1e-15);
    }
  }
  EXPECT_EQ(loaded, 9U);
  EXPECT_NEAR(fz, -1000, 1e-9);
  EXPECT_FALSE(pd::mesh_corrections_note(scene.model).empty());

  // Lattice-only corrections named on a mesh body, and groups the mesh lacks, are scene errors.
  const auto scene_error = [](const std::string& file) {
    try {
      (void)pd::load_scene(file);
    } catch (const pd::SceneError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const std::string moment = scene_error(
      write(dir / "moment.yaml", scene_text("hexes.msh", "model: {volume_correction: moment}\n")));
  EXPECT_TRUE(contains(moment, "volume_correction 'moment' needs a lattice")) << moment;
  std::string text = scene_text("hexes.msh", "");
  text.replace(text.find("group: left"), 11, "group: side");
  const std::string missing = scene_error(write(dir / "missing.yaml", text));
  EXPECT_TRUE(contains(missing, "no physical group 'side'")) << missing;
  EXPECT_TRUE(contains(missing, "hexes.msh")) << missing;
  const std::string no_file = scene_error(write(dir / "nofile.yaml", scene_text("gone.msh", "")));
  EXPECT_TRUE(contains(no_file, "gone.msh: no such file")) << no_file;
}

} // namespace
