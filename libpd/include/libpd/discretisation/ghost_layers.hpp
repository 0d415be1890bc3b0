// Quadratic-exact surfaces and clamps (issue 14, item 2).
//
// A particle near a free surface misses the part of its horizon that lies outside the body, so
// under any strain it stores too little energy; every per-bond correction calibrated under
// uniform strain (corrections.hpp) gets tension right but not bending, because bonds sample the
// strain at their midpoints and a surface particle's remaining bonds all point into the body.
//
// Ghost layers give every body particle its whole horizon instead. The lattice sites outside the
// bodies within δ of a body particle become ghost particles whose displacement is extrapolated
// from the body: for each ghost, the quadratic polynomial (per component) that fits, in the
// least-squares sense, the displacements of the free body particles around the nearest one is
// evaluated at the ghost. The fit reproduces every quadratic field exactly, so under any uniform
// or linearly varying strain (tension, shear, bending, twist) each body particle sees the field
// it would see inside an infinite body. With the energy
//   W_c(u_f) = Σ_{body–body bonds} w + ½ Σ_{body–ghost bonds} w,   u_ghost = A u_f,
// (ghost–ghost bonds carry nothing, as between a mirror support's particles) each body particle
// then stores exactly the bulk energy density of the field at its own position, and the body's
// energy is the bulk lattice rule applied cell by cell. Forces are −∂W_c/∂u_f: the ghosts' forces
// are folded back onto their sources through Aᵀ, so the operator Aᵀ K A stays symmetric.
//
// A clamped face is the same construction with the polynomials restricted to those that vanish on
// the face: for a site behind the plane x_a = c the basis is (x_a − c)·{1, x, y, z} (the
// quadratics that are zero on the plane), behind two planes (x_a − c)(x_b − d), behind three the
// displacement is zero. Every quadratic field that satisfies the clamp is then reproduced, which
// the odd mirror image does only for fields odd in x_a: a beam's deflection near a clamp,
// u_z ∝ x², is continued by the mirror as −sign(x)·x², with a kink in the curvature at the face
// that the crossing bonds feel (+1.2 % stiffness on the clamped beam at the paper's resolution,
// measured).
//
// What stays: the bulk lattice's own response to a strain gradient (its sixth moments), which
// ghosts do not change. The `gradient` bond weights (corrections.hpp) set it to what each
// particle's cell holds.
#pragma once

#include "libpd/core/geometry.hpp"
#include "libpd/discretisation/bond_family.hpp"
#include "libpd/discretisation/constraint.hpp"
#include "libpd/discretisation/lattice.hpp"
#include "libpd/discretisation/point_cloud.hpp"

#include <cstdint>
#include <functional>
#include <vector>

namespace pd {

/// A plane x_axis = at on which a clamp holds the displacement at zero; the clamp's own
/// particles lie on the side sign(x_axis − at) = side.
struct ClampPlane {
  int axis = 0;
  double at = 0;
  double side = -1;

  /// Whether p lies strictly on the clamp's side (beyond round-off of the lattice).
  bool behind(const Vec3& p, double tolerance) const {
    return side * (p[static_cast<std::size_t>(axis)] - at) > tolerance;
  }
};

/// A symmetry plane x_axis = at of a half model (SupportSpec::symmetry): the body lies on the side
/// sign(x_axis − at) = side, and the field beyond it is the body's mirror image with the normal
/// component negated.
struct SymmetryPlane {
  int axis = 0;
  double at = 0;
  double side = 1;
};

/// x mirrored across the planes of `planes` whose bits are set in `mask` (bit k: planes[k]).
inline Vec3 mirrored(Vec3 x, const std::vector<SymmetryPlane>& planes, unsigned mask) {
  for (std::size_t k = 0; k < planes.size(); ++k) {
    if (((mask >> k) & 1U) != 0) {
      const auto axis = static_cast<std::size_t>(planes[k].axis);
      x[axis] = 2 * planes[k].at - x[axis];
    }
  }
  return x;
}

/// The lattice sites that are not particles of `body` but lie within the horizon of one of them:
/// where ghost particles go. A particle's own site is its position rounded to the lattice, so
/// jittered particle sets keep their ghosts on the regular lattice. Deterministic order (sorted
/// by site, x fastest).
///
/// Mesh bodies (mesh_of_body[b] for body b, null for a lattice body; body_of[i] is particle i's)
/// are not a lattice: their particles are denser and irregular, so a cell may hold none of them and
/// still lie inside the part. For them a site is inside when its centre lies in one of the mesh's
/// simplices (PointCloud::simplex): the sites whose cells the mesh fills are never ghosts, the
/// others within reach are, and the part's faces are as exact as the lattice's on faces that lie
/// on cell faces (a box drawn from lattice multiples), a staircase of cells elsewhere, as for a
/// lattice body minus a shape.
std::vector<Vec3> ghost_sites(int dim, const LatticeSpec& lattice, HorizonRule rule,
                              const std::vector<Vec3>& body,
                              const std::vector<const PointCloud*>& mesh_of_body = {},
                              const std::vector<std::uint16_t>& body_of = {});

/// The radius, in lattice spacings, of the cloud each dependant's quadratic is fitted to: the
/// smallest that gives a particle in a corner of a box enough neighbours for the whole quadratic
/// (3D: 20 for 10 terms, three positions along each axis; 2D: 8 for 6). √6.
inline constexpr double ghost_fit_radius = 2.449489742783178;

/// Extrapolation coefficients for every particle listed in `fitted` (ascending), from the
/// particles with dependent[i] = 0 (the sources; every fitted particle is dependent too): each
/// dependant is fitted around the nearest source among its bond family, from the free particles
/// within ghost_fit_radius λ of it (of the centroid of the nearest sources where several are
/// equally near, so that a symmetric body gets symmetric fits), with the quadratic basis
/// restricted by the clamp planes the dependant lies behind (see above). A dependant with no source
/// within the horizon, or behind three planes, gets no term (its displacement stays zero). Axes
/// along which the sources do not vary enough for a linear (two positions) or quadratic (three)
/// term drop those terms, so thin bodies extrapolate with what they can resolve. Beside a symmetry
/// plane the fit also takes the sources' mirror images within the fit radius as data (each a term
/// of its source with the normal component negated), so that a ghost beside the plane is fitted
/// from both sides as in the full model: the images the full model's family of the nearest source
/// would hold, those that `bonded` (the nearest source's position, the image's; null: all) allows,
/// as a hole cuts the full model's bonds (bond_cuts.hpp).
ExtrapolatedParticles
extrapolation_ties(int dim, double spacing, const std::vector<Vec3>& position,
                   const BondFamily& family, const std::vector<std::uint8_t>& dependent,
                   const std::vector<std::uint32_t>& fitted, const std::vector<ClampPlane>& planes,
                   const std::vector<SymmetryPlane>& symmetry = {},
                   const std::function<bool(const Vec3&, const Vec3&)>& bonded = nullptr);

/// The same dependants fitted again, each from only the part of its data (its terms' sources, seen
/// through the symmetry planes their negated bits name) within `fit_radius` λ < ghost_fit_radius of
/// its nearest datum, with the basis restricted as above: fewer sources per dependant and a less
/// exact extrapolation (linear where the smaller cloud holds two positions along an axis). The
/// static solver factors the operator of these as its preconditioner.
ExtrapolatedParticles refit_within(int dim, double spacing, const std::vector<Vec3>& position,
                                   const ExtrapolatedParticles& ties,
                                   const std::vector<ClampPlane>& planes,
                                   const std::vector<SymmetryPlane>& symmetry, double fit_radius);

} // namespace pd
