// A mesh body's region filled with the lattice (`fill: lattice`, docs/scenes.md, meshes): the
// lattice sites inside its elements become the particles, so that a part drawn in CAD gets the
// lattice's weights and ghost layers, and with them the lattice's accuracy. One particle per
// element (the peers' way, the default for `mesh:`) leaves an unstructured set, which the
// lattice's gradient weights cannot serve: a strip two elements deep bends ~36 % too stiffly
// (verification/scenes/user/thin-strip-tri.yaml).
#pragma once

#include "libpd/discretisation/lattice.hpp"
#include "libpd/discretisation/point_cloud.hpp"

#include <array>
#include <cstdint>
#include <functional>
#include <vector>

namespace pd {

/// Calls visit(site, simplex) for every lattice site whose point lies in a simplex of `mesh`
/// (PointCloud::simplex; within round-off of a face counts as in, so a site on a face two
/// simplices share is visited for both), simplices in order.
void for_each_site_in_simplices(
    int dim, const LatticeSpec& lattice, const PointCloud& mesh,
    const std::function<void(const std::array<long long, 3>& site, std::size_t simplex)>& visit);

/// The lattice sites inside `mesh`'s elements, x fastest, each a particle of the lattice's cell
/// volume; `corner` and `simplex` are the mesh's (the region, for the ghost sites outside it) and
/// `element` holds each site's element, the lowest-numbered of those that hold it.
struct LatticeFill {
  PointCloud cloud;
  std::vector<std::uint32_t> element;
};
LatticeFill fill_with_lattice(const ModelDimension& dimension, const LatticeSpec& lattice,
                              const PointCloud& mesh);

} // namespace pd
