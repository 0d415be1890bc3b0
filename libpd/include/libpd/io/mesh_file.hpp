// Bodies from meshes and CAD geometry, read through Gmsh (optional: LIBPD_HAVE_GMSH).
//
// A mesh becomes particles as the peers do it (Peridigm, PeriLab): one particle per element of
// the scene's dimension, at the element's centroid, with the element's volume (2D: area ×
// thickness). Any element type Gmsh knows counts: tetrahedra, hexahedra, prisms and pyramids in
// 3D, triangles and quadrangles in 2D, of any order; volumes and centroids are Gauss sums of the
// element's own Jacobian. A geometry file (.geo, .step, .iges, .brep, .stl) is first meshed by
// Gmsh with elements no larger than a given size. (A scene may fill the elements with lattice
// sites instead, the default for geometry files: discretisation/lattice_fill.hpp.)
//
// Physical groups name sets of particles: a group of the body's dimension holds the particles of
// its elements; a group of lower dimension (faces, edges, points) holds the particles whose
// element has a node on it (a face group: the layer of elements along that face, those touching
// it at an edge or a corner included). Only the elements with a whole facet on the face would
// leave gaps between them: on an unstructured mesh a support on those held a comb, the material
// between its teeth slipped, and a plate of triangles in tension stretched 10 % too far (a
// lattice support holds a whole column of cells).
//
// A mesh that cannot be a body is refused with MeshFileError naming the file and the element or
// group: inverted or zero-volume elements, no element of the scene's dimension, a 2D mesh off the
// plane z = 0, an STL surface that is not closed, anything Gmsh itself reports as an error.
#pragma once

#include "libpd/discretisation/point_cloud.hpp"

#include <cstddef>
#include <cstdint>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace pd {

class MeshFileError : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

struct MeshBody {
  std::string path; ///< the file, as given (for messages)
  PointCloud cloud; ///< one particle per element, in Gmsh's element order; no sizes
  /// Physical group name → its particles (indices into cloud, ascending). Unnamed groups are
  /// listed as "DIM:TAG" (e.g. "2:5").
  std::map<std::string, std::vector<std::uint32_t>> groups;
  std::vector<std::string> warnings; ///< Gmsh's warnings, as it wrote them

  /// The particles of the physical group `name`; MeshFileError naming the file, the group and
  /// the groups it has if there is none of that name.
  const std::vector<std::uint32_t>& group(const std::string& name) const;
};

/// Whether libpd was built with Gmsh: without it, the functions below throw MeshFileError.
bool mesh_files_supported();

/// Read a mesh file (.msh, or any mesh format Gmsh reads) as a body of dimension `dim` (2 or 3);
/// 2D volumes are areas × `thickness`.
MeshBody read_mesh_file(const std::string& path, int dim, double thickness);

/// Mesh a geometry file with elements of size at most `size` [m] (Gmsh's Mesh.MeshSizeMax) and
/// read the mesh as read_mesh_file does. An STL file is a closed triangulated surface (3D) whose
/// inside is meshed.
MeshBody mesh_geometry_file(const std::string& path, int dim, double thickness, double size);

} // namespace pd
