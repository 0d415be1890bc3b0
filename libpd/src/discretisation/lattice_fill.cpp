#include "libpd/discretisation/lattice_fill.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <map>
#include <tuple>

namespace pd {

void for_each_site_in_simplices(
    int dim, const LatticeSpec& lattice, const PointCloud& mesh,
    const std::function<void(const std::array<long long, 3>& site, std::size_t simplex)>& visit) {
  const auto d = static_cast<std::size_t>(dim);
  // Barycentric coordinates within round-off of the lattice count as inside, so that a site on a
  // face shared by two simplices is not lost to both.
  const double tolerance = 1e-9;
  for (std::size_t s = 0; s + d < mesh.simplex.size(); s += d + 1) {
    std::array<Vec3, 4> c{};
    std::array<long long, 3> first{0, 0, 0}, last{0, 0, 0};
    for (std::size_t k = 0; k <= d; ++k) {
      c[k] = mesh.corner[mesh.simplex[s + k]];
    }
    for (std::size_t a = 0; a < d; ++a) {
      double lo = c[0][a], hi = c[0][a];
      for (std::size_t k = 1; k <= d; ++k) {
        lo = std::min(lo, c[k][a]);
        hi = std::max(hi, c[k][a]);
      }
      std::tie(first[a], last[a]) = index_range(lattice, static_cast<int>(a), lo, hi);
    }
    // x = c0 + E b, b the barycentric coordinates of corners 1..d.
    Eigen::Matrix3d e = Eigen::Matrix3d::Identity();
    for (std::size_t k = 1; k <= d; ++k) {
      for (std::size_t a = 0; a < d; ++a) {
        e(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(k - 1)) = c[k][a] - c[0][a];
      }
    }
    const Eigen::Matrix3d inverse = e.inverse();
    std::array<long long, 3> site{0, 0, 0};
    for (site[2] = first[2]; site[2] <= last[2]; ++site[2]) {
      for (site[1] = first[1]; site[1] <= last[1]; ++site[1]) {
        for (site[0] = first[0]; site[0] <= last[0]; ++site[0]) {
          Eigen::Vector3d x = Eigen::Vector3d::Zero();
          for (std::size_t a = 0; a < d; ++a) {
            x(static_cast<Eigen::Index>(a)) =
                lattice_coordinate(lattice, static_cast<int>(a), site[a]) - c[0][a];
          }
          const Eigen::Vector3d b = inverse * x;
          double rest = 1;
          bool inside = true;
          for (std::size_t k = 0; k < d; ++k) {
            inside = inside && b(static_cast<Eigen::Index>(k)) >= -tolerance;
            rest -= b(static_cast<Eigen::Index>(k));
          }
          if (inside && rest >= -tolerance) {
            visit(site, s / (d + 1));
          }
        }
      }
    }
  }
}

LatticeFill fill_with_lattice(const ModelDimension& dimension, const LatticeSpec& lattice,
                              const PointCloud& mesh) {
  const int dim = dimension.dim;
  // Ordered z, y, x (x fastest), as generate_lattice orders a box's particles.
  const auto later = [](const std::array<long long, 3>& a, const std::array<long long, 3>& b) {
    return std::tie(a[2], a[1], a[0]) < std::tie(b[2], b[1], b[0]);
  };
  std::map<std::array<long long, 3>, std::uint32_t, decltype(later)> owner(later);
  for_each_site_in_simplices(dim, lattice, mesh, [&](const auto& site, std::size_t simplex) {
    const std::uint32_t element = mesh.simplex_particle.at(simplex);
    const auto [it, added] = owner.emplace(site, element);
    if (!added) {
      it->second = std::min(it->second, element);
    }
  });
  LatticeFill out;
  out.cloud.corner = mesh.corner;
  out.cloud.simplex = mesh.simplex; // simplex_particle stays empty: the sites are not elements
  const double volume = cell_volume(dimension, lattice.spacing);
  // Axes beyond the dimension keep the mesh's own coordinate (0 for a plane mesh).
  const Vec3 unused = mesh.position.empty() ? Vec3{0, 0, 0} : mesh.position.front();
  for (const auto& [site, element] : owner) {
    Vec3 p = unused;
    for (int a = 0; a < dim; ++a) {
      p[static_cast<std::size_t>(a)] =
          lattice_coordinate(lattice, a, site[static_cast<std::size_t>(a)]);
    }
    out.cloud.position.push_back(p);
    out.cloud.volume.push_back(volume);
    out.element.push_back(element);
  }
  return out;
}

} // namespace pd
