// A pressure on the surface of a shape (a hole's wall, a cylinder's or box's outer face), where
// that surface bounds a body: the traction −p n (n the body's outward normal) as forces on the
// particles next to it. The FE reference (fem_reference/) applies the same traction on the mesh
// faces that lie on the surface, found with surface_patches.
#pragma once

#include "libpd/core/geometry.hpp"
#include "libpd/discretisation/lattice.hpp"
#include "libpd/physics/material.hpp"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace pd {

/// The parts of a shape's surface a point lies on, within `tol`, as bits: bit 0 a sphere's or a
/// cylinder's curved wall, bits 1 and 2 a cylinder's ends (3D, finite length), bit 2a (2a + 1)
/// the low (high) face of a box normal to axis a; 0 off the surface and for half-spaces. A mesh
/// face lies on the surface where its vertices share a bit.
unsigned surface_patches(const Shape& s, const Vec3& p, int dim, double tol);

/// The forces of a pressure load on particles.
struct SurfaceForces {
  std::vector<std::uint32_t> particle; ///< ascending
  std::vector<Vec3> force;             ///< [N], one per particle
  double area = 0;                     ///< loaded area [m²] (2D: length × thickness)
};

/// The forces of pressure `p` [Pa] (positive pushes into the body) on the part of the surface of
/// `surface` that bounds the bodies (a body on one side, none on the other), shared among the
/// first `body_count` particles (spacing `spacing`).
SurfaceForces pressure_forces(const ModelDimension& dimension, double spacing,
                              const std::vector<BodySpec>& bodies, const ParticleSet& particles,
                              std::size_t body_count, const Shape& surface, double p);

} // namespace pd
