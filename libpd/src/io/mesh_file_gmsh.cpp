// The Gmsh plug-in (io/mesh_plugin.h): mesh and geometry files read through Gmsh's C++ API. A
// module of its own, loaded by io/mesh_file.cpp on the first mesh body, so that libpd and the
// programs linking it do not load Gmsh (and OpenCASCADE) at start-up. It uses libpd's headers
// for the body's types but calls nothing compiled into libpd.
#include "libpd/io/mesh_file.hpp"
#include "mesh_plugin.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <filesystem>
#include <fmt/format.h>
#include <gmsh.h>
#include <memory>
#include <mutex>
#include <string_view>
#include <unordered_map>
#include <utility>

namespace pd {
namespace {

/// Gmsh keeps one model in global state between gmsh::initialize and gmsh::finalize: every use
/// holds this lock from start to end, so two bodies read on two threads cannot meet in it.
std::mutex gmsh_mutex;

/// One use of Gmsh: initialised silent (it writes to stdout by default), its log collected so
/// that its errors become MeshFileError and its warnings the body's, finalised on the way out.
class GmshSession {
public:
  explicit GmshSession(std::string path) : lock_(gmsh_mutex), path_(std::move(path)) {
    gmsh::initialize(0, nullptr, false);
    gmsh::option::setNumber("General.Terminal", 0);
    // One thread: the mesh of a geometry file is then the same on every run.
    gmsh::option::setNumber("General.NumThreads", 1);
    gmsh::logger::start();
  }
  GmshSession(const GmshSession&) = delete;
  GmshSession& operator=(const GmshSession&) = delete;
  ~GmshSession() {
    gmsh::logger::stop();
    gmsh::finalize();
  }

  const std::string& path() const { return path_; }

  /// Run Gmsh calls; what Gmsh reports as an error (thrown or only logged) is thrown as
  /// MeshFileError "FILE: while DOING: Gmsh: MESSAGE".
  template <class F>
  void run(std::string_view doing, F&& calls) {
    bool threw = false;
    try {
      calls();
    } catch (...) {
      threw = true; // Gmsh 4.8 throws bare values: the message is in its log
    }
    std::vector<std::string> log;
    gmsh::logger::get(log);
    std::string error;
    for (std::size_t i = seen_; i < log.size(); ++i) {
      const std::string& line = log[i];
      if (line.starts_with("Error")) {
        error = error.empty() ? line : error;
      } else if (line.starts_with("Warning")) {
        warnings.push_back(fmt::format("{}: Gmsh: {}", path_, line));
      }
    }
    seen_ = log.size();
    if (threw || !error.empty()) {
      if (error.empty()) {
        gmsh::logger::getLastError(error);
      }
      fail(fmt::format("while {}: Gmsh: {}", doing, error.empty() ? "failed" : error));
    }
  }

  [[noreturn]] void fail(const std::string& what) const {
    throw MeshFileError(fmt::format("{}: {}", path_, what));
  }

  std::vector<std::string> warnings;

private:
  std::lock_guard<std::mutex> lock_;
  std::string path_;
  std::size_t seen_ = 0;
};

std::string point_text(const Vec3& p) {
  return fmt::format("[{:.6g}, {:.6g}, {:.6g}]", p[0], p[1], p[2]);
}

/// Signed area of the polygon of an element's corner nodes in the xy plane (shoelace).
double signed_area(const std::vector<Vec3>& corners) {
  double twice = 0;
  for (std::size_t a = 0; a < corners.size(); ++a) {
    const Vec3& p = corners[a];
    const Vec3& q = corners[(a + 1) % corners.size()];
    twice += p[0] * q[1] - q[0] * p[1];
  }
  return 0.5 * twice;
}

/// The particles of the current model's elements of dimension `dim`, and its physical groups.
/// A mesh's elements of the body's dimension, in particle order: what the checks and the
/// physical groups need besides the particles.
struct Elements {
  struct Element {
    std::size_t tag;
    std::string type;
    double orientation; // 3D: the signed volume; 2D: the corners' signed area
  };
  std::vector<Element> list;
  std::vector<std::size_t> nodes;      // every node of every element, in particle order
  std::vector<std::size_t> offsets{0}; // element p's nodes: [offsets[p], offsets[p + 1])
  std::unordered_map<std::size_t, std::uint32_t> particle_of_element;
};

/// An element with `corners` corner nodes (Gmsh's order) cut into simplices, as local corner
/// indices: quadrangles into two triangles, hexahedra into six tetrahedra around the diagonal
/// 0–6, prisms into three, pyramids into two. Curved high-order elements become straight-sided.
std::vector<std::array<std::size_t, 4>> simplices_of(int dim, int corners) {
  if (dim == 2) {
    return corners == 3 ? std::vector<std::array<std::size_t, 4>>{{0, 1, 2, 0}}
                        : std::vector<std::array<std::size_t, 4>>{{0, 1, 2, 0}, {0, 2, 3, 0}};
  }
  switch (corners) {
  case 4:
    return {{0, 1, 2, 3}};
  case 5:
    return {{0, 1, 2, 4}, {0, 2, 3, 4}};
  case 6:
    return {{0, 1, 2, 3}, {1, 2, 3, 4}, {2, 3, 4, 5}};
  default:
    return {{0, 1, 2, 6}, {0, 2, 3, 6}, {0, 3, 7, 6}, {0, 7, 4, 6}, {0, 4, 5, 6}, {0, 5, 1, 6}};
  }
}

/// One particle per element of dimension `dim`: its centroid and volume from Gauss sums of the
/// element's own Jacobian; and the elements cut into simplices (PointCloud::simplex).
Elements read_elements(GmshSession& s, int dim, double thickness,
                       const std::unordered_map<std::size_t, Vec3>& node, MeshBody& body) {
  std::vector<int> types;
  s.run("listing the elements", [&] { gmsh::model::mesh::getElementTypes(types, dim); });
  if (types.empty()) {
    s.fail(fmt::format("has no {}D elements (a body needs {})", dim,
                       dim == 3 ? "tetrahedra, hexahedra, prisms or pyramids"
                                : "triangles or quadrangles"));
  }
  Elements out;
  std::unordered_map<std::size_t, std::uint32_t> corner_of_node;
  for (const int type : types) {
    std::string name;
    int type_dim = 0, order = 0, nodes_per = 0, primary = 0;
    std::vector<double> local;
    std::vector<std::size_t> tags, nodes;
    std::vector<double> points, weights, jacobians, det, at;
    s.run("reading the elements", [&] {
      gmsh::model::mesh::getElementProperties(type, name, type_dim, order, nodes_per, local,
                                              primary);
      gmsh::model::mesh::getElementsByType(type, tags, nodes);
      // Exact for the volume and the first moment of elements up to this order.
      gmsh::model::mesh::getIntegrationPoints(type, fmt::format("Gauss{}", std::max(2, 3 * order)),
                                              points, weights);
      gmsh::model::mesh::getJacobians(type, points, jacobians, det, at);
    });
    const std::size_t g = weights.size();
    const auto n = static_cast<std::size_t>(nodes_per);
    for (std::size_t e = 0; e < tags.size(); ++e) {
      double v = 0;
      Vec3 moment{0, 0, 0};
      for (std::size_t q = 0; q < g; ++q) {
        const double w = weights[q] * det[e * g + q];
        v += w;
        for (std::size_t a = 0; a < 3; ++a) {
          moment[a] += w * at[3 * (e * g + q) + a];
        }
      }
      double orientation = v;
      if (dim == 2) {
        std::vector<Vec3> corners;
        for (std::size_t c = 0; c < static_cast<std::size_t>(primary); ++c) {
          corners.push_back(node.at(nodes[e * n + c]));
        }
        orientation = signed_area(corners);
      }
      out.particle_of_element.emplace(tags[e], static_cast<std::uint32_t>(out.list.size()));
      out.list.push_back({tags[e], name, orientation});
      body.cloud.position.push_back({moment[0] / v, moment[1] / v, moment[2] / v});
      body.cloud.volume.push_back(dim == 2 ? std::abs(v) * thickness : v);
      out.nodes.insert(out.nodes.end(), nodes.begin() + static_cast<long>(e * n),
                       nodes.begin() + static_cast<long>((e + 1) * n));
      for (const auto& piece : simplices_of(dim, primary)) {
        for (std::size_t c = 0; c < static_cast<std::size_t>(dim) + 1; ++c) {
          const std::size_t tag = nodes[e * n + piece[c]];
          const auto [known, added] =
              corner_of_node.emplace(tag, static_cast<std::uint32_t>(body.cloud.corner.size()));
          if (added) {
            body.cloud.corner.push_back(node.at(tag));
          }
          body.cloud.simplex.push_back(known->second);
        }
        body.cloud.simplex_particle.push_back(static_cast<std::uint32_t>(out.list.size() - 1));
      }
      out.offsets.push_back(out.nodes.size());
    }
  }
  return out;
}

/// Inverted and degenerate elements. In 3D Gmsh's Jacobian is signed; in 2D it is not, and a
/// plane mesh may run either way round, so an element turned against the mesh's majority is the
/// inverted one.
void check_orientation(GmshSession& s, int dim, const Elements& elements, const MeshBody& body) {
  const auto count = static_cast<double>(elements.list.size());
  double mean = 0;
  long long positive = 0;
  for (const auto& e : elements.list) {
    mean += std::abs(e.orientation) / count;
    positive += e.orientation > 0 ? 1 : 0;
  }
  const double sign = dim == 3 || 2 * static_cast<double>(positive) >= count ? 1 : -1;
  const double zero = 1e-9 * mean;
  for (std::size_t i = 0; i < elements.list.size(); ++i) {
    const auto& e = elements.list[i];
    const Vec3& at = body.cloud.position[i];
    if (!(std::abs(e.orientation) > zero) || !std::isfinite(at[0])) {
      s.fail(fmt::format("element {} ({}) at {} has zero {}", e.tag, e.type, point_text(at),
                         dim == 3 ? "volume" : "area"));
    }
    if (sign * e.orientation < 0) {
      s.fail(fmt::format("element {} ({}) at {} is inverted ({} {:.6g}{})", e.tag, e.type,
                         point_text(at), dim == 3 ? "signed volume" : "signed area", e.orientation,
                         dim == 3 ? "" : ", against the orientation of the mesh's other elements"));
    }
  }
}

/// The physical groups of dimension up to `dim` as particle sets (mesh_file.hpp).
void read_groups(GmshSession& s, int dim, const Elements& elements, MeshBody& body) {
  std::vector<std::pair<int, int>> groups;
  s.run("reading the physical groups", [&] { gmsh::model::getPhysicalGroups(groups); });
  std::unordered_map<std::size_t, std::vector<std::uint32_t>> particles_at_node;
  if (std::any_of(groups.begin(), groups.end(), [&](const auto& g) { return g.first < dim; })) {
    for (std::uint32_t p = 0; p < elements.list.size(); ++p) {
      for (std::size_t k = elements.offsets[p]; k < elements.offsets[p + 1]; ++k) {
        auto& list = particles_at_node[elements.nodes[k]];
        if (list.empty() || list.back() != p) {
          list.push_back(p);
        }
      }
    }
  }
  for (const auto& [group_dim, group_tag] : groups) {
    if (group_dim > dim) {
      continue;
    }
    std::string name;
    std::vector<int> entities;
    s.run("reading the physical groups", [&] {
      gmsh::model::getPhysicalName(group_dim, group_tag, name);
      gmsh::model::getEntitiesForPhysicalGroup(group_dim, group_tag, entities);
    });
    if (name.empty()) {
      name = fmt::format("{}:{}", group_dim, group_tag);
    }
    std::vector<std::uint32_t>& selected = body.groups[name];
    for (const int entity : entities) {
      std::vector<int> entity_types;
      std::vector<std::vector<std::size_t>> tags, nodes;
      s.run("reading the physical groups",
            [&] { gmsh::model::mesh::getElements(entity_types, tags, nodes, group_dim, entity); });
      for (std::size_t t = 0; t < entity_types.size(); ++t) {
        if (group_dim == dim) {
          for (const std::size_t tag : tags[t]) {
            selected.push_back(elements.particle_of_element.at(tag));
          }
          continue;
        }
        // Every element with a node on the group (mesh_file.hpp): the elements with a whole
        // facet on it alone leave gaps between them, and a support on those held a comb.
        for (const std::size_t v : nodes[t]) {
          const auto found = particles_at_node.find(v);
          if (found != particles_at_node.end()) {
            selected.insert(selected.end(), found->second.begin(), found->second.end());
          }
        }
      }
    }
    std::sort(selected.begin(), selected.end());
    selected.erase(std::unique(selected.begin(), selected.end()), selected.end());
  }
}

/// The particles of the current model's elements of dimension `dim`, and its physical groups.
MeshBody extract_body(GmshSession& s, int dim, double thickness) {
  MeshBody body;
  body.path = s.path();
  int model_dim = -1;
  s.run("reading the model", [&] { model_dim = gmsh::model::getDimension(); });
  if (model_dim != dim) {
    s.fail(model_dim < 0 ? fmt::format("holds no mesh or geometry Gmsh can read")
                         : fmt::format("is a {}D model, the scene is {}D", model_dim, dim));
  }
  std::vector<std::size_t> node_tags;
  std::vector<double> coord, parametric;
  s.run("reading the nodes",
        [&] { gmsh::model::mesh::getNodes(node_tags, coord, parametric, -1, -1, false, false); });
  std::unordered_map<std::size_t, Vec3> node;
  node.reserve(node_tags.size());
  double extent = 0;
  for (std::size_t i = 0; i < node_tags.size(); ++i) {
    const Vec3 p{coord[3 * i], coord[3 * i + 1], coord[3 * i + 2]};
    node.emplace(node_tags[i], p);
    extent = std::max({extent, std::abs(p[0]), std::abs(p[1]), std::abs(p[2])});
  }
  if (dim == 2) {
    for (std::size_t i = 0; i < node_tags.size(); ++i) {
      if (std::abs(coord[3 * i + 2]) > 1e-9 * extent) {
        s.fail(fmt::format("node {} is at z = {:.6g}: a 2D body's mesh lies in the plane z = 0",
                           node_tags[i], coord[3 * i + 2]));
      }
    }
  }
  const Elements elements = read_elements(s, dim, thickness, node, body);
  check_orientation(s, dim, elements, body);
  read_groups(s, dim, elements, body);
  body.warnings = std::move(s.warnings);
  return body;
}

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

/// An STL surface bounds a solid only if every edge is shared by exactly two triangles.
void require_closed_surface(GmshSession& s) {
  std::vector<int> types;
  std::vector<std::vector<std::size_t>> tags, nodes;
  s.run("reading the surface", [&] { gmsh::model::mesh::getElements(types, tags, nodes, 2); });
  std::map<std::pair<std::size_t, std::size_t>, int> edges;
  for (std::size_t t = 0; t < types.size(); ++t) {
    const std::size_t per = tags[t].empty() ? 0 : nodes[t].size() / tags[t].size();
    for (std::size_t e = 0; e < tags[t].size(); ++e) {
      for (std::size_t a = 0; a < per; ++a) {
        std::size_t u = nodes[t][e * per + a], v = nodes[t][e * per + (a + 1) % per];
        ++edges[{std::min(u, v), std::max(u, v)}];
      }
    }
  }
  if (edges.empty()) {
    s.fail("holds no triangles");
  }
  for (const auto& [edge, count] : edges) {
    if (count != 2) {
      std::vector<double> a, b, parametric;
      s.run("reading the surface", [&] {
        gmsh::model::mesh::getNode(edge.first, a, parametric);
        gmsh::model::mesh::getNode(edge.second, b, parametric);
      });
      s.fail(fmt::format("the surface is not closed: the edge from [{:.6g}, {:.6g}, {:.6g}] to "
                         "[{:.6g}, {:.6g}, {:.6g}] belongs to {} triangle{} (a closed surface: "
                         "2)",
                         a[0], a[1], a[2], b[0], b[1], b[2], count, count == 1 ? "" : "s"));
    }
  }
}

MeshBody read_mesh(const std::string& path, int dim, double thickness) {
  GmshSession s(path);
  s.run("reading the file", [&] { gmsh::open(path); });
  return extract_body(s, dim, thickness);
}

MeshBody mesh_geometry(const std::string& path, int dim, double thickness, double size) {
  GmshSession s(path);
  if (lower_extension(path) == ".stl") {
    if (dim != 3) {
      s.fail("an STL surface bounds a 3D body; the scene is 2D");
    }
    s.run("reading the file", [&] { gmsh::merge(path); });
    require_closed_surface(s);
    s.run("making a volume of the surface", [&] {
      // The triangles stay as they are (no reparametrisation): the volume is meshed inside them.
      gmsh::model::mesh::classifySurfaces(M_PI, true, false, M_PI);
      gmsh::model::mesh::createGeometry();
      std::vector<std::pair<int, int>> surfaces;
      gmsh::model::getEntities(surfaces, 2);
      std::vector<int> tags;
      for (const auto& [d, t] : surfaces) {
        tags.push_back(t);
      }
      const int loop = gmsh::model::geo::addSurfaceLoop(tags);
      gmsh::model::geo::addVolume({loop});
      gmsh::model::geo::synchronize();
    });
  } else {
    s.run("reading the file", [&] { gmsh::open(path); });
  }
  s.run("meshing", [&] {
    gmsh::option::setNumber("Mesh.MeshSizeMax", size);
    gmsh::model::mesh::generate(dim);
  });
  return extract_body(s, dim, thickness);
}

/// A MeshBody flattened for libpd (io/mesh_plugin.h), with the storage its pointers point into.
struct FlatBody {
  pd_mesh_body flat{};
  std::string error;
  std::vector<double> position, volume;
  std::vector<std::string> names, warnings;
  std::vector<const char*> name_pointers, warning_pointers;
  std::vector<std::size_t> group_begin{0};
  std::vector<std::uint32_t> group_particle;
  std::vector<double> corner;
  std::vector<std::uint32_t> simplex;
  std::vector<std::uint32_t> simplex_particle;
};

std::unique_ptr<FlatBody> flatten(MeshBody&& body) {
  auto out = std::make_unique<FlatBody>();
  for (const Vec3& p : body.cloud.position) {
    out->position.insert(out->position.end(), {p[0], p[1], p[2]});
  }
  out->volume = std::move(body.cloud.volume);
  for (const Vec3& c : body.cloud.corner) {
    out->corner.insert(out->corner.end(), {c[0], c[1], c[2]});
  }
  out->simplex = std::move(body.cloud.simplex);
  out->simplex_particle = std::move(body.cloud.simplex_particle);
  for (auto& [name, particles] : body.groups) {
    out->names.push_back(name);
    out->group_particle.insert(out->group_particle.end(), particles.begin(), particles.end());
    out->group_begin.push_back(out->group_particle.size());
  }
  out->warnings = std::move(body.warnings);
  for (const std::string& n : out->names) {
    out->name_pointers.push_back(n.c_str());
  }
  for (const std::string& w : out->warnings) {
    out->warning_pointers.push_back(w.c_str());
  }
  pd_mesh_body& f = out->flat;
  f.particles = out->volume.size();
  f.position = out->position.data();
  f.volume = out->volume.data();
  f.groups = out->names.size();
  f.group_name = out->name_pointers.data();
  f.group_begin = out->group_begin.data();
  f.group_particle = out->group_particle.data();
  f.warnings = out->warnings.size();
  f.warning = out->warning_pointers.data();
  f.corners = out->corner.size() / 3;
  f.corner = out->corner.data();
  f.simplex_indices = out->simplex.size();
  f.simplex = out->simplex.data();
  f.simplex_particle = out->simplex_particle.data();
  return out;
}

/// Nothing may be thrown across the C boundary: errors travel as text.
template <class F>
pd_mesh_body* guarded(F&& read) noexcept {
  try {
    std::unique_ptr<FlatBody> out;
    try {
      out = flatten(read());
    } catch (const MeshFileError& e) {
      out = std::make_unique<FlatBody>();
      out->error = e.what();
      out->flat.mesh_error = 1;
    } catch (const std::exception& e) {
      out = std::make_unique<FlatBody>();
      out->error = e.what();
    }
    if (!out->error.empty()) {
      out->flat.error = out->error.c_str();
    }
    out->flat.owner = out.get();
    return &out.release()->flat;
  } catch (...) {
    static pd_mesh_body failed{};
    failed.error = "the Gmsh plug-in failed with an unknown error";
    return &failed;
  }
}

pd_mesh_body* read_mesh_entry(const char* path, int dim, double thickness) {
  return guarded([&] { return read_mesh(path, dim, thickness); });
}

pd_mesh_body* mesh_geometry_entry(const char* path, int dim, double thickness, double size) {
  return guarded([&] { return mesh_geometry(path, dim, thickness, size); });
}

void release_entry(pd_mesh_body* body) {
  delete static_cast<FlatBody*>(body->owner); // null for the static one of `guarded`
}

} // namespace
} // namespace pd

extern "C" __attribute__((visibility("default"))) const pd_mesh_plugin* libpd_mesh_plugin() {
  static const pd_mesh_plugin table{pd_mesh_plugin_version, pd::read_mesh_entry,
                                    pd::mesh_geometry_entry, pd::release_entry};
  return &table;
}
