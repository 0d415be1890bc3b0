// Mesh and geometry files (io/mesh_file.hpp): Gmsh does the reading in a plug-in
// (io/mesh_file_gmsh.cpp), loaded on the first mesh body, so that runs without one do not load
// Gmsh and OpenCASCADE.
#include "libpd/io/mesh_file.hpp"

#include <fmt/format.h>

#ifdef LIBPD_HAVE_GMSH
#include "libpd/core/plugin.hpp"
#include "mesh_plugin.h"

#include <filesystem>
#include <memory>
#endif

namespace pd {

const std::vector<std::uint32_t>& MeshBody::group(const std::string& name) const {
  const auto found = groups.find(name);
  if (found == groups.end()) {
    std::string names;
    for (const auto& [n, particles] : groups) {
      names += fmt::format("{}'{}'", names.empty() ? "" : ", ", n);
    }
    throw MeshFileError(
        fmt::format("{}: no physical group '{}' ({})", path, name,
                    names.empty() ? "the mesh has no physical groups" : "its groups: " + names));
  }
  return found->second;
}

#ifndef LIBPD_HAVE_GMSH

bool mesh_files_supported() {
  return false;
}

namespace {
[[noreturn]] void refuse(const std::string& path) {
  throw MeshFileError(fmt::format("{}: this libpd was built without Gmsh, which reads meshes and "
                                  "geometry files",
                                  path));
}
} // namespace

MeshBody read_mesh_file(const std::string& path, int, double) {
  refuse(path);
}
MeshBody mesh_geometry_file(const std::string& path, int, double, double) {
  refuse(path);
}

#else

bool mesh_files_supported() {
  return true;
}

namespace {

const pd_mesh_plugin& plugin() {
  return *static_cast<const pd_mesh_plugin*>(
      load_plugin({"bodies from meshes and geometry files (Gmsh)", pd_mesh_plugin_module,
                   pd_mesh_plugin_entry, pd_mesh_plugin_version}));
}

void require_file(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    throw MeshFileError(fmt::format("{}: no such file", path));
  }
}

/// The plug-in's flat body as a MeshBody (or its error thrown), released either way.
MeshBody take(const std::string& path, int dim, pd_mesh_body* flat) {
  const std::unique_ptr<pd_mesh_body, void (*)(pd_mesh_body*)> owner(flat, plugin().release);
  if (flat->error) {
    if (flat->mesh_error) {
      throw MeshFileError(flat->error);
    }
    throw std::runtime_error(flat->error);
  }
  MeshBody body;
  body.path = path;
  body.cloud.position.resize(flat->particles);
  for (std::size_t p = 0; p < flat->particles; ++p) {
    body.cloud.position[p] = {flat->position[3 * p], flat->position[3 * p + 1],
                              flat->position[3 * p + 2]};
  }
  body.cloud.volume.assign(flat->volume, flat->volume + flat->particles);
  for (std::size_t g = 0; g < flat->groups; ++g) {
    body.groups[flat->group_name[g]].assign(flat->group_particle + flat->group_begin[g],
                                            flat->group_particle + flat->group_begin[g + 1]);
  }
  body.warnings.assign(flat->warning, flat->warning + flat->warnings);
  body.cloud.corner.resize(flat->corners);
  for (std::size_t c = 0; c < flat->corners; ++c) {
    body.cloud.corner[c] = {flat->corner[3 * c], flat->corner[3 * c + 1], flat->corner[3 * c + 2]};
  }
  body.cloud.simplex.assign(flat->simplex, flat->simplex + flat->simplex_indices);
  body.cloud.simplex_particle.assign(
      flat->simplex_particle,
      flat->simplex_particle + body.cloud.simplex.size() / static_cast<std::size_t>(dim + 1));
  return body;
}

} // namespace

MeshBody read_mesh_file(const std::string& path, int dim, double thickness) {
  require_file(path);
  return take(path, dim, plugin().read_mesh_file(path.c_str(), dim, thickness));
}

MeshBody mesh_geometry_file(const std::string& path, int dim, double thickness, double size) {
  require_file(path);
  return take(path, dim, plugin().mesh_geometry_file(path.c_str(), dim, thickness, size));
}

#endif

} // namespace pd
