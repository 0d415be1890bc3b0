// Meshes written as .msh text (format 2.2) for the mesh-body tests, so that element counts and
// volumes are known without Gmsh, and the fixture that skips them where libpd has no Gmsh.
#pragma once

#include "libpd/io/mesh_file.hpp"

#include <algorithm>
#include <array>
#include <filesystem>
#include <fstream>
#include <gtest/gtest.h>
#include <numeric>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

namespace mesh_test {

namespace fs = std::filesystem;

/// A fresh folder for one test's files.
inline fs::path temp_folder(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("libpd_mesh_test_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

inline std::string write(const fs::path& path, const std::string& text) {
  std::ofstream(path) << text;
  return path.string();
}

struct Element {
  int type; // Gmsh: 1 line, 2 triangle, 3 quadrangle, 4 tetrahedron, 5 hexahedron
  int physical;
  std::vector<std::size_t> nodes; // 1-based
};

/// A .msh 2.2 file of these nodes, elements and physical names ({dim, tag, name}).
struct Msh {
  std::vector<std::array<double, 3>> nodes;
  std::vector<Element> elements;
  std::vector<std::tuple<int, int, std::string>> names;

  std::string text() const {
    std::ostringstream s;
    s.precision(17);
    s << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n";
    if (!names.empty()) {
      s << "$PhysicalNames\n" << names.size() << "\n";
      for (const auto& [dim, tag, name] : names) {
        s << dim << " " << tag << " \"" << name << "\"\n";
      }
      s << "$EndPhysicalNames\n";
    }
    s << "$Nodes\n" << nodes.size() << "\n";
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      s << i + 1 << " " << nodes[i][0] << " " << nodes[i][1] << " " << nodes[i][2] << "\n";
    }
    s << "$EndNodes\n$Elements\n" << elements.size() << "\n";
    for (std::size_t i = 0; i < elements.size(); ++i) {
      const Element& e = elements[i];
      // Elementary entity = physical tag: one entity per group keeps the file valid.
      s << i + 1 << " " << e.type << " 2 " << e.physical << " " << e.physical;
      for (const std::size_t n : e.nodes) {
        s << " " << n;
      }
      s << "\n";
    }
    s << "$EndElements\n";
    return s.str();
  }
};

inline double det3(const std::array<double, 3>& a, const std::array<double, 3>& b,
                   const std::array<double, 3>& c) {
  return a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
         a[2] * (b[0] * c[1] - b[1] * c[0]);
}

/// A box [0, size]³ cut into n³ cells: hexahedra, or six tetrahedra per cell (Kuhn's split, each
/// written with a positive volume). Physical groups: 3 "front" (3D: the first layer of cells
/// along x), 4 "back" (the last layer), 1 "body" (the others), 2 "left" (the quadrangles of the
/// face x = 0, hexahedra only).
inline Msh box_mesh(std::size_t n, double size, bool tets) {
  Msh m;
  const double h = size / static_cast<double>(n);
  const auto id = [n](std::size_t i, std::size_t j, std::size_t k) {
    return 1 + i + (n + 1) * (j + (n + 1) * k);
  };
  for (std::size_t k = 0; k <= n; ++k) {
    for (std::size_t j = 0; j <= n; ++j) {
      for (std::size_t i = 0; i <= n; ++i) {
        m.nodes.push_back(
            {static_cast<double>(i) * h, static_cast<double>(j) * h, static_cast<double>(k) * h});
      }
    }
  }
  for (std::size_t k = 0; k < n; ++k) {
    for (std::size_t j = 0; j < n; ++j) {
      for (std::size_t i = 0; i < n; ++i) {
        const int group = i == 0 ? 3 : i + 1 == n ? 4 : 1;
        const std::array<std::size_t, 8> c{
            id(i, j, k),     id(i + 1, j, k),     id(i + 1, j + 1, k),     id(i, j + 1, k),
            id(i, j, k + 1), id(i + 1, j, k + 1), id(i + 1, j + 1, k + 1), id(i, j + 1, k + 1)};
        if (!tets) {
          m.elements.push_back({5, group, std::vector<std::size_t>(c.begin(), c.end())});
          continue;
        }
        // Kuhn: the paths from (i, j, k) to (i+1, j+1, k+1) along the axes in every order.
        std::array<int, 3> order{0, 1, 2};
        do {
          std::array<std::size_t, 3> at{i, j, k};
          std::vector<std::size_t> t{id(at[0], at[1], at[2])};
          for (const int a : order) {
            ++at[static_cast<std::size_t>(a)];
            t.push_back(id(at[0], at[1], at[2]));
          }
          const auto& p0 = m.nodes[t[0] - 1];
          std::array<std::array<double, 3>, 3> e{};
          for (std::size_t q = 0; q < 3; ++q) {
            for (std::size_t a = 0; a < 3; ++a) {
              e[q][a] = m.nodes[t[q + 1] - 1][a] - p0[a];
            }
          }
          if (det3(e[0], e[1], e[2]) < 0) {
            std::swap(t[2], t[3]);
          }
          m.elements.push_back({4, group, t});
        } while (std::next_permutation(order.begin(), order.end()));
      }
    }
  }
  if (!tets) {
    for (std::size_t k = 0; k < n; ++k) {
      for (std::size_t j = 0; j < n; ++j) {
        m.elements.push_back(
            {3, 2, {id(0, j, k), id(0, j, k + 1), id(0, j + 1, k + 1), id(0, j + 1, k)}});
      }
    }
    m.names.emplace_back(2, 2, "left");
  }
  m.names.emplace_back(3, 1, "body");
  m.names.emplace_back(3, 3, "front");
  m.names.emplace_back(3, 4, "back");
  return m;
}

/// The rectangle [0, a] × [0, b] cut into nx × ny quadrangles, or two triangles each; groups:
/// 1 "plate" (2D), 2 "right" (the lines of the edge x = a).
inline Msh plate_mesh(std::size_t nx, std::size_t ny, double a, double b, bool triangles) {
  Msh m;
  const auto id = [nx](std::size_t i, std::size_t j) { return 1 + i + (nx + 1) * j; };
  for (std::size_t j = 0; j <= ny; ++j) {
    for (std::size_t i = 0; i <= nx; ++i) {
      m.nodes.push_back({a * static_cast<double>(i) / static_cast<double>(nx),
                         b * static_cast<double>(j) / static_cast<double>(ny), 0});
    }
  }
  for (std::size_t j = 0; j < ny; ++j) {
    for (std::size_t i = 0; i < nx; ++i) {
      if (triangles) {
        m.elements.push_back({2, 1, {id(i, j), id(i + 1, j), id(i + 1, j + 1)}});
        m.elements.push_back({2, 1, {id(i, j), id(i + 1, j + 1), id(i, j + 1)}});
      } else {
        m.elements.push_back({3, 1, {id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)}});
      }
    }
  }
  for (std::size_t j = 0; j < ny; ++j) {
    m.elements.push_back({1, 2, {id(nx, j), id(nx, j + 1)}});
  }
  m.names = {{2, 1, "plate"}, {1, 2, "right"}};
  return m;
}

inline double total(const std::vector<double>& v) {
  return std::accumulate(v.begin(), v.end(), 0.0);
}

inline std::size_t count_of(const Msh& m, int type) {
  return static_cast<std::size_t>(std::count_if(
      m.elements.begin(), m.elements.end(), [type](const Element& e) { return e.type == type; }));
}

/// The message of the MeshFileError `read` raises, or "" if it succeeds.
template <class F>
inline std::string error_of(F read) {
  try {
    read();
  } catch (const pd::MeshFileError& e) {
    return e.what();
  }
  return "";
}

inline bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

class MeshFile : public ::testing::Test {
protected:
  void SetUp() override {
    if (!pd::mesh_files_supported()) {
      GTEST_SKIP() << "libpd built without Gmsh";
    }
  }
};

/// A 3D scene of one mesh body `mesh` (steel, ν = 1/4, λ = 0.1) clamped on its group "left" and
/// pushed on "back", with `model` inserted after the lattice.
inline std::string scene_text(const std::string& mesh, const std::string& model) {
  return "dimension: 3\n"
         "lattice:\n  spacing: 0.1\n" +
         model +
         "materials:\n  steel: {youngs_modulus: 200e9, poisson_ratio: 0.25, density: 7800}\n"
         "bodies:\n  - {name: part, material: steel, mesh: " +
         mesh +
         "}\n"
         "supports:\n  - {name: clamp, group: left, fixed: [x, y, z]}\n"
         "loads:\n  - {name: push, group: back, value: [0, 0, -1000]}\n"
         "solver: {integrator: static}\n"
         "probes:\n  - {name: back_uz, group: back, component: z}\n";
}

} // namespace mesh_test
