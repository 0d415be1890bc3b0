// Meshes of a scene's continuum body (scene_problem.h), by one of two routes:
//  * box_grid: every shape a box. A tensor-product grid through every box face of bodies,
//    supports and loaded cells, each interval cut into round(length / h) cells, the cells whose
//    centre lies outside the body removed. Refining it globally halves h exactly.
//  * gmsh_mesh: cylinders, spheres, half-spaces, holes. The body is built by OpenCASCADE
//    constructive solid geometry in Gmsh (union of each body's parts, less its holes, less the
//    mirror supports' regions), fragmented by the supports' and region loads' boxes so that
//    their faces are mesh faces (not by point loads' cells: their integrals resolve them by
//    quadrature), and meshed with all quadrilaterals (2D: Frontal-Delaunay, recombined and
//    subdivided) or all hexahedra (3D: tetrahedra subdivided into four hexes). Level k is the
//    level-0 mesh split k times by Gmsh, which puts the new boundary nodes on the CAD surfaces:
//    cells halve per level everywhere, also where small features set the size. Boundary faces on
//    a sphere or cylinder get it as their manifold, and the solver maps with MappingQ(2): the
//    geometric error is O(h³); Mesh.MeshSizeFromCurvature puts 16 cells around each circle on
//    level 0, 16·2^k on level k.
#pragma once

#include "scene_problem.h"

#include <deal.II/grid/tria.h>
#include <filesystem>

namespace pdfem {
using namespace dealii;

// The level-0 target cell size before the budget enlarges it: the smallest side of any body box
// and the smallest radius of a cylinder or sphere (body or hole), so the thinnest part of the
// body gets a cell across; for Gmsh also the smallest side of a support or region-load box.
double base_cell_size(const SceneProblem& problem, bool gmsh);

template <int dim>
void box_grid(const SceneProblem& problem, double h, Triangulation<dim>& triangulation);

// Level `level` of the Gmsh sequence whose level 0 has target size h0; `msh_file` receives it.
template <int dim>
void gmsh_mesh(const SceneProblem& problem, double h0, unsigned int level,
               const std::filesystem::path& msh_file, Triangulation<dim>& triangulation);
// Whether a cell's vertices make it inverted or flat (a corner's Jacobian of the d-linear map is
// not positive). Gmsh's tetrahedra subdivided into hexahedra can be: a 3D plate 1 cm thick with
// a hole, meshed at 2 cm, had 8 such hexahedra of 828, and its stiffness matrix was indefinite.
template <int dim>
bool has_inverted_cells(const Triangulation<dim>& triangulation);
// Level `level` of a mesh body's sequence (SceneProblem::mesh_body): its elements, as libpd
// made the particles of them, split `level` times by Gmsh; `msh_file` receives it. Simplices.
template <int dim>
void mesh_body_level(const SceneProblem& problem, unsigned int level,
                     const std::filesystem::path& msh_file, Triangulation<dim>& triangulation);
} // namespace pdfem
