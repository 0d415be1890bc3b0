// Regular particle lattices filling unions of boxes.
//
// Two conventions are offered:
//  * cell-centered (default): the box is cut into cells of edge λ and a particle sits at each
//    cell centre, so the body's surfaces lie half a spacing outside the outer particles and the
//    particles' volumes tile the box exactly. The PD body is then the same continuum as an FE body
//    of the same box.
//  * node-based: particles on the lattice nodes including the box's corners and edges, as in
//    Miranda et al. 2019 (Model A is 83 × 9 × 7 nodes for a 4.1 × 0.4 × 0.3 m box at λ = 0.05 m).
// All bodies share one lattice anchored at `origin`, so touching boxes never produce duplicate or
// misaligned particles.
#pragma once

#include "libpd/core/geometry.hpp"
#include "libpd/core/names.hpp"
#include "libpd/discretisation/bond_family.hpp"
#include "libpd/discretisation/point_cloud.hpp"
#include "libpd/physics/material.hpp"

#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace pd {

enum class LatticeConvention { cell_centered, node_based };

template <>
struct EnumName<LatticeConvention> {
  static constexpr NameTable<LatticeConvention, 2> table{{
      {"cell-centered", LatticeConvention::cell_centered,
       "particles at cell centres, surfaces λ/2 outside the outer particles"},
      {"node-based", LatticeConvention::node_based,
       "particles on the lattice nodes, including the box's corners"},
  }};
};

/// What a mesh or geometry body's particles are (docs/scenes.md, meshes).
enum class MeshFill { elements, lattice };

template <>
struct EnumName<MeshFill> {
  static constexpr NameTable<MeshFill, 2> table{{
      {"elements", MeshFill::elements,
       "one particle per element at its centroid with its volume (an unstructured set)"},
      {"lattice", MeshFill::lattice,
       "the lattice sites inside the elements (the lattice's weights and accuracy)"},
  }};
};

/// The `fill` of a body a scene gives as `mesh: FILE`: the user's own elements, as the peers take
/// them (Peridigm, PeriLab).
inline constexpr MeshFill mesh_file_fill = MeshFill::elements;
/// The `fill` of a body given as `geometry: FILE` (CAD): the lattice, whose weights and ghost
/// layers make it as accurate as a box body; one particle per element of Gmsh's mesh bends a
/// part two elements deep 30–36 % too stiffly (lattice_fill.hpp, fem_reference/README.md).
inline constexpr MeshFill geometry_file_fill = MeshFill::lattice;

struct LatticeSpec {
  double spacing = 0;                               ///< λ [m]
  double horizon_factor = 2.0 * 1.7320508075688772; ///< m = δ/λ; default 2√3 (Miranda §4)
  LatticeConvention convention = LatticeConvention::cell_centered;
  Vec3 origin{0, 0, 0};
  /// Irregular particle sets (stability tests): each coordinate is moved by a uniform random
  /// amount in [-jitter, jitter]·λ and each volume scaled by a factor in [1-v, 1+v].
  double position_jitter = 0;
  double volume_variation = 0;
  std::uint64_t seed = 1;

  double horizon() const { return horizon_factor * spacing; }
  bool operator==(const LatticeSpec&) const = default;
};

/// A body: a region of the lattice made of one material.
struct BodySpec {
  std::string name;
  Region region;
  int material = 0;
  /// A body of given particles (a particle file) instead of the lattice points of `region`.
  std::shared_ptr<const PointCloud> points;
  /// `points` are a mesh's elements (io/mesh_file.hpp): under the bond-based model they take the
  /// lattice's horizon, as lattice particles do, instead of one of their own.
  bool mesh = false;
  /// A mesh body's file (a mesh, or the geometry Gmsh meshed), as the scene resolved it: the FE
  /// reference builds its domain from the same file.
  std::string mesh_file;
  bool mesh_is_geometry = false; ///< `mesh_file` is a geometry file meshed at lattice.spacing
  /// A mesh body's particles: its elements, or the lattice sites inside them (then `points` are
  /// lattice points and the body takes the lattice's corrections; lattice_fill.hpp). Unless the
  /// scene says: mesh_file_fill or geometry_file_fill.
  MeshFill fill = MeshFill::elements;

  bool operator==(const BodySpec&) const = default;
};

/// Particles in the reference configuration, in a deterministic order (x fastest).
struct ParticleSet {
  std::vector<Vec3> position;
  std::vector<double> volume;
  std::vector<std::uint16_t> material;
  std::vector<std::uint16_t> body;
  /// Particle size h where a body is a point cloud: the file's h, NaN where it is to be derived
  /// (eq. 115), 0 for lattice particles (h = δ/α). Empty when every body is a lattice region.
  std::vector<double> particle_size;

  std::size_t size() const { return position.size(); }
};

/// Volume of one lattice cell: λ³, λ²·t (2D) or λ·A (1D).
double cell_volume(const ModelDimension& d, double spacing);

/// Lattice coordinate of index n along one axis.
double lattice_coordinate(const LatticeSpec& l, int axis, long long n);

/// The lattice site nearest x: its indices along the first `dim` axes (the inverse of
/// lattice_coordinate), 0 along the others.
std::array<long long, 3> nearest_lattice_site(const LatticeSpec& l, int dim, const Vec3& x);

/// Index range [first, last] of lattice points inside [lo, hi] along one axis.
/// A point on a face counts as inside (within 1e-6 λ, against round-off in box corners). For boxes
/// aligned with the lattice this never matters for cell-centred lattices (their points sit half a
/// spacing from the faces); for node-based lattices it puts the nodes on the faces in the box.
std::pair<long long, long long> index_range(const LatticeSpec& l, int axis, double lo, double hi);

/// Cut cells: where a body's surface is curved (a cylinder, a sphere, an inclined plane, added or
/// taken out), a lattice cell the surface crosses becomes a particle at the cell's site whose
/// volume is the share of the cell the body holds, if that share is at least min_cell_share. A
/// smaller share (a sliver) joins the particle next to it towards its centroid instead: as a
/// particle of its own, its stiffness would outweigh its mass by 1/share and shorten the stable
/// time step. With whole cells a curved surface was a staircase that lay up to half a spacing off
/// it, by an amount that changed with the surface's position against the lattice, so errors near a
/// hole did not fall with the spacing (a plate with two holes, λ = 2 mm: the displacement at a
/// hole's rim −11.8 % to +8.4 % of FE as the holes moved by λ/8). Faces of boxes keep whole cells.
/// How the model weighs a cut cell: model.cpp (energy_weights, scale_bonds_of_cut_cells).
inline constexpr double min_cell_share = 0.25;

/// The share of a lattice cell a region holds, and the centroid of that part relative to the
/// cell's centre (zero for a whole cell or none).
struct CellShare {
  double share = 0;
  Vec3 centroid_offset{0, 0, 0};
};

/// The share of the lattice cell centred on `centre` that `region` holds (cut cells): boxes
/// decide at the centre, curved surfaces cut the cell.
CellShare cell_share(const Region& region, int dim, const Vec3& centre, double spacing);

/// Whether the region has a surface that does not run along lattice cell faces: a cylinder, a
/// sphere or an inclined plane, added or taken out.
bool has_curved_surface(const Region& region);

/// Fill the bodies with lattice particles. A point shared by two bodies goes to the first one
/// listed (the scene checks that overlapping bodies have the same material); a cut cell two bodies
/// share goes to the one holding more of it, with both shares as its volume.
ParticleSet generate_lattice(const ModelDimension& d, const LatticeSpec& lattice,
                             const std::vector<BodySpec>& bodies);

/// Number of lattice points of `lattice` that fall inside `region` (used to reject empty regions).
std::size_t count_lattice_points(const ModelDimension& d, const LatticeSpec& lattice,
                                 const Region& region);

/// Visit every lattice offset o ≠ 0 of a bulk family, in units of λ (components beyond `dim`
/// zero): the offsets whose length lies inside the horizon m = `horizon_factor` by `rule`, in a
/// fixed order (x fastest), so that sums over them are reproducible. The lengths are tested
/// exactly (|o|² is an integer), with the guard band of InHorizon. Work (2⌈m⌉ + 3)^dim.
template <class Visit>
void for_each_offset_within(double horizon_factor, int dim, HorizonRule rule, Visit&& visit) {
  const InHorizon inside(horizon_factor, rule);
  const auto r = static_cast<long long>(std::ceil(horizon_factor)) + 1;
  const long long rj = dim > 1 ? r : 0;
  const long long rk = dim > 2 ? r : 0;
  for (long long k = -rk; k <= rk; ++k) {
    for (long long j = -rj; j <= rj; ++j) {
      for (long long i = -r; i <= r; ++i) {
        const auto s2 = static_cast<double>(i * i + j * j + k * k);
        if (s2 > 0 && inside(s2)) {
          visit(std::array<long long, 3>{i, j, k});
        }
      }
    }
  }
}

} // namespace pd
