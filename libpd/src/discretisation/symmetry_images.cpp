#include "symmetry_images.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>

namespace pd::detail {

std::vector<SymmetryPlane> symmetry_planes(const ModelSpec& spec, const ParticleSet& particles,
                                           std::size_t body_count) {
  std::vector<SymmetryPlane> planes;
  for (const SupportSpec& sup : spec.supports) {
    for (std::size_t a = 0; a < 3; ++a) {
      if (sup.symmetry[a]) {
        double mean = 0;
        for (std::size_t i = 0; i < body_count; ++i) {
          mean += particles.position[i][a] - sup.symmetry_at[a];
        }
        planes.push_back({static_cast<int>(a), sup.symmetry_at[a], mean >= 0 ? 1.0 : -1.0});
      }
    }
  }
  return planes;
}

ExtrapolatedParticles symmetry_images(const ModelSpec& spec, const ParticleSet& particles,
                                      std::size_t body_count, double tol,
                                      const std::vector<SymmetryPlane>& sides,
                                      const std::vector<Constraint>& constraints,
                                      ExtrapolatedParticles fitted) {
  struct Plane {
    std::size_t axis;
    double at;
    double side; // the body's side: sign of x_axis − at
    Region region;
  };
  std::vector<Plane> planes;
  const int dim = spec.dimension.dim;
  std::size_t next = 0; // `sides` lists the planes in this order
  for (const SupportSpec& sup : spec.supports) {
    for (std::size_t a = 0; a < 3; ++a) {
      if (sup.symmetry[a]) {
        planes.push_back({a, sup.symmetry_at[a], sides[next++].side, sup.region});
      }
    }
  }
  if (planes.empty() || fitted.empty()) {
    return fitted;
  }
  // Sites by lattice cell, to find an image.
  const double h = spec.lattice.spacing;
  const auto key = [h](const Vec3& p) {
    return std::array<long long, 3>{std::llround(p[0] / h * 2), std::llround(p[1] / h * 2),
                                    std::llround(p[2] / h * 2)};
  };
  std::map<std::array<long long, 3>, std::uint32_t> index;
  for (std::size_t i = 0; i < particles.size(); ++i) {
    index.emplace(key(particles.position[i]), static_cast<std::uint32_t>(i));
  }
  std::vector<std::ptrdiff_t> slot(particles.size(), -1); // dependant index of a particle
  for (std::size_t d = 0; d < fitted.size(); ++d) {
    slot[fitted.particle[d]] = static_cast<std::ptrdiff_t>(d);
  }
  // A mirror support's particle: u_c = ±u_c(source), the signs as negated bits.
  std::vector<std::uint32_t> mirror_source(particles.size(), Constraint::no_mirror);
  std::vector<std::uint8_t> mirror_negated(particles.size(), 0);
  for (const Constraint& c : constraints) {
    if (c.mirror_of != Constraint::no_mirror) {
      mirror_source[c.particle] = c.mirror_of;
      if (c.mirror_sign < 0) {
        mirror_negated[c.particle] =
            static_cast<std::uint8_t>(mirror_negated[c.particle] | (1U << c.component));
      }
    }
  }
  ExtrapolatedParticles out;
  for (std::size_t d = 0; d < fitted.size(); ++d) {
    const std::uint32_t p = fitted.particle[d];
    Vec3 image = particles.position[p];
    std::uint8_t negated = 0;
    for (const Plane& pl : planes) {
      const bool beyond = pl.side * (image[pl.axis] - pl.at) < -tol &&
                          (pl.region.boxes.empty() || pl.region.contains(image, dim, h));
      if (beyond) {
        image[pl.axis] = 2 * pl.at - image[pl.axis];
        negated = static_cast<std::uint8_t>(negated | (1U << pl.axis));
      }
    }
    const auto found = negated != 0 ? index.find(key(image)) : index.end();
    std::size_t from = d; // whose terms p takes
    if (found != index.end() && slot[found->second] < 0 &&
        (found->second < body_count || mirror_source[found->second] != Constraint::no_mirror)) {
      const std::uint32_t q = found->second;
      const bool mirrored = mirror_source[q] != Constraint::no_mirror;
      out.particle.push_back(p);
      out.source.push_back(mirrored ? mirror_source[q] : q);
      out.coefficient.push_back(1.0);
      out.negated.push_back(
          static_cast<std::uint8_t>(negated ^ (mirrored ? mirror_negated[q] : 0U)));
      out.offsets.push_back(out.source.size());
      continue;
    }
    if (found != index.end() && slot[found->second] >= 0) {
      from = static_cast<std::size_t>(slot[found->second]);
    } else {
      negated = 0; // no image: the site keeps its own fit
    }
    out.particle.push_back(p);
    for (std::size_t t = fitted.offsets[from]; t < fitted.offsets[from + 1]; ++t) {
      out.source.push_back(fitted.source[t]);
      out.coefficient.push_back(fitted.coefficient[t]);
      const std::uint8_t own = fitted.negated.empty() ? 0 : fitted.negated[t];
      out.negated.push_back(static_cast<std::uint8_t>(own ^ negated));
    }
    out.offsets.push_back(out.source.size());
  }
  if (std::all_of(out.negated.begin(), out.negated.end(), [](std::uint8_t n) { return n == 0; })) {
    out.negated.clear();
  }
  return out;
}

} // namespace pd::detail
