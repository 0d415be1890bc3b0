// The interface between libpd and its Gmsh plug-in (io/mesh_file.cpp loads it through
// core/plugin.hpp; io/mesh_file_gmsh.cpp is the plug-in). Plain C types only, so that what
// crosses the boundary does not depend on either side's C++ library details; raise the version
// whenever anything here changes.
#pragma once

#include <cstddef>
#include <cstdint>

extern "C" {

/// A body read by the plug-in (io/mesh_file.hpp's MeshBody, flattened), or its error. The
/// plug-in owns the memory until `release`.
struct pd_mesh_body {
  const char* error; ///< null on success; else the message (for a MeshFileError if mesh_error)
  int mesh_error;    ///< 1: the file cannot be a body (MeshFileError); 0: anything else
  std::size_t particles;
  const double* position; ///< x, y, z of each particle, in Gmsh's element order
  const double* volume;   ///< per particle
  std::size_t groups;     ///< physical groups, in ascending order of their names
  const char* const* group_name;
  const std::size_t* group_begin; ///< groups + 1 offsets into group_particle
  const std::uint32_t* group_particle;
  std::size_t warnings;
  const char* const* warning;
  std::size_t corners;          ///< the elements' corner nodes
  const double* corner;         ///< x, y, z of each
  std::size_t simplex_indices;  ///< (dim + 1) × the simplices the elements are cut into
  const std::uint32_t* simplex; ///< each simplex's corners: triangles (2D), tetrahedra (3D)
  const std::uint32_t* simplex_particle; ///< each simplex's element (particle)
  void* owner;                           ///< the plug-in's own, for release
};

struct pd_mesh_plugin {
  std::uint32_t version; ///< pd_mesh_plugin_version
  /// read_mesh_file and mesh_geometry_file of io/mesh_file.hpp; never null, never throw.
  pd_mesh_body* (*read_mesh_file)(const char* path, int dim, double thickness);
  pd_mesh_body* (*mesh_geometry_file)(const char* path, int dim, double thickness, double size);
  void (*release)(pd_mesh_body* body);
};

/// The plug-in's one exported symbol.
const pd_mesh_plugin* libpd_mesh_plugin();
}

inline constexpr std::uint32_t pd_mesh_plugin_version = 3;
inline constexpr const char* pd_mesh_plugin_module = "libpd_gmsh.so";
inline constexpr const char* pd_mesh_plugin_entry = "libpd_mesh_plugin";
