// A generated graded particle set (Olsson, Ander & Williams 2021, §10.2, Figs. 6–8): a grid of
// zones over the body, each zone filled with the same p × p pattern, so that the particles are as
// fine as the zones are small; then a Monte Carlo relaxation that moves each particle by a random
// step and keeps the move only if the particle stays in the body, on its side of the crack, and at
// least the minimum spacing from its neighbours (Fig. 8), the sizes h_a being refreshed from the n
// nearest neighbours (eq. 115) every fifth sweep, as the paper does.
//
// Two zone grids: the paper's ellipse in elliptical coordinates (eq. 114),
//   x = c cosh ξ cos η,  y = c sinh ξ sin η,  ξ ∈ (0, ξ_max], η ∈ [0, 2π),
// uniform in ξ and η, so that zones shrink towards the focal points (the tips of the crack
// between them, ξ = 0), and a box whose zone widths along x grow geometrically. The result is a
// point cloud (discretisation/point_cloud.hpp) like a particle file's. Each particle's volume is
// its sub-cell's area (its zone's over p², times the 2D thickness) in the regular pattern and,
// once the Monte Carlo moves have carried it off that sub-cell, the area of the body nearer to it
// than to any other particle on its side of the crack (its Voronoi cell). Deterministic for a
// given seed.
#pragma once

#include "libpd/core/geometry.hpp"
#include "libpd/core/names.hpp"
#include "libpd/discretisation/point_cloud.hpp"

#include <array>
#include <cstdint>

namespace pd {

enum class GradedShape { ellipse, box };

template <>
struct EnumName<GradedShape> {
  static constexpr NameTable<GradedShape, 2> table{{
      {"ellipse", GradedShape::ellipse,
       "the ellipse x = c cosh ξ cos η, y = c sinh ξ sin η, ξ ≤ ξ_max (eq. 114), zones uniform "
       "in ξ and η: finest at the focal points"},
      {"box", GradedShape::box,
       "a box, zone widths along x growing geometrically by 'grading', each column of particles "
       "as many rows as keep them about as far apart across as along"},
  }};
};

struct GradedSetSpec {
  GradedShape shape = GradedShape::ellipse;
  double focal_half_distance = 0;   ///< c [m] (ellipse)
  double xi_max = 2.0;              ///< ξ of the outer boundary (ellipse)
  Box box{};                        ///< [lo, hi] (box)
  double grading = 1.0;             ///< last zone's width over the first's, along x (box)
  std::array<int, 2> zones{40, 20}; ///< zones along ξ and η (ellipse), x and y (box: see cpp)
  int pattern = 5;                  ///< p: each zone holds p × p particles
  double noise = 0.3;               ///< Monte Carlo step, a fraction of the particle's size h
  double min_spacing = 0.35;        ///< least distance between two particles over h_a + h_b
  int sweeps = 20;                  ///< Monte Carlo sweeps over all particles
  int size_neighbours = 5;          ///< n of eq. 115
  std::uint64_t seed = 1;
};

/// How many particles generate_graded_set(spec) makes, counted in floating point without making
/// them (infinite when the grading leaves a zone no width): what the memory guard and the 32-bit
/// limit are checked against first.
double graded_set_size(const GradedSetSpec& spec);

/// Above this many particles a graded set is refused before it is made: its relaxation sweeps
/// (nearest neighbours of every particle, several times) take minutes at this size already (80,000
/// particles: 20 s with the model), the sets of the paper have 10^4 to 10^5, and counting up to
/// it costs at most this many cheap column evaluations.
constexpr double max_graded_particles = 1e6;

/// Memory the generation of a graded set takes per particle, beyond the particles themselves:
/// position, volume, size and the twelve neighbours its relaxation checks.
constexpr double graded_bytes_per_particle = 3 * 8 + 8 + 8 + 12 * 4;

/// The particles of `spec` in 2D (z = 0), volumes × `thickness`, sizes h from eq. 115 after the
/// relaxation. Throws std::invalid_argument for a spec that describes no body.
PointCloud generate_graded_set(const GradedSetSpec& spec, double thickness);

} // namespace pd
