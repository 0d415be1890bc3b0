// Bonds that must not exist: across a pre-crack, or through a hole of a body (issue 19).
#include "libpd/discretisation/bond_cuts.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace pd {

namespace {

/// Whether the bond between body particles a and b passes through a hole: a point of it, sampled
/// every λ/8, lies in some body's `minus` shape and in no body. A notch narrower than the horizon
/// would otherwise be bridged by the bonds across it.
bool passes_through_hole(int dim, double spacing, const std::vector<BodySpec>& bodies,
                         const Vec3& a, const Vec3& b) {
  const double tol = 1e-6 * spacing;
  double length = 0;
  for (std::size_t k = 0; k < 3; ++k) {
    length += (b[k] - a[k]) * (b[k] - a[k]);
  }
  const auto samples = static_cast<int>(std::ceil(std::sqrt(length) / (0.125 * spacing)));
  for (int s = 1; s < samples; ++s) {
    const double t = static_cast<double>(s) / samples;
    const Vec3 p{a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), a[2] + t * (b[2] - a[2])};
    bool in_hole = false;
    for (const BodySpec& body : bodies) {
      for (const Shape& hole : body.region.minus) {
        in_hole = in_hole || hole.contains(p, dim, -tol);
      }
    }
    if (in_hole && std::none_of(bodies.begin(), bodies.end(), [&](const BodySpec& body) {
          return body.region.contains(p, dim, tol);
        })) {
      return true;
    }
  }
  return false;
}

} // namespace

std::vector<std::size_t>
cut_bonds_across_cracks_and_holes(int dim, double spacing, const std::vector<Crack>& cracks,
                                  const std::vector<BodySpec>& bodies, const ParticleSet& ps,
                                  std::size_t body_count, BondFamily& family) {
  std::vector<std::size_t> cut(cracks.size(), 0);
  const bool holes = std::any_of(bodies.begin(), bodies.end(),
                                 [](const BodySpec& b) { return !b.region.minus.empty(); });
  if (cracks.empty() && !holes) {
    return cut;
  }
  // Each ghost's nearest body particle (lowest index among equals), which it stands for.
  std::vector<std::size_t> stands_for(ps.size());
  for (std::size_t g = 0; g < ps.size(); ++g) {
    stands_for[g] = g;
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t k = family.offsets[g]; g >= body_count && k < family.offsets[g + 1]; ++k) {
      const double r = 1.0 / family.inverse_length[k];
      if (family.neighbour[k] < body_count && r < best * (1 - 1e-12)) {
        best = r;
        stands_for[g] = family.neighbour[k];
      }
    }
  }
  BondFamily kept;
  kept.offsets.reserve(family.offsets.size());
  kept.offsets.push_back(0);
  for (std::size_t i = 0; i + 1 < family.offsets.size(); ++i) {
    for (std::size_t k = family.offsets[i]; k < family.offsets[i + 1]; ++k) {
      const std::size_t j = family.neighbour[k];
      bool crossed = false;
      for (std::size_t c = 0; c < cracks.size() && !crossed; ++c) {
        // A bond that crosses the crack but reaches past its front (one end not over the crack)
        // is kept: a crack grown by breaking bonds leaves such bonds whole behind its tip until
        // the tip has moved on (lattice_toughness.cpp watches it grow), so a pre-crack cut this
        // way starts as the grown crack runs, at the same K; cutting them too made the pre-crack
        // sharper than any grown one, its first bonds breaking 4–13 % below the running crack's
        // K (with the weightings), and its faces more compliant (issue 36). A ghost is over the
        // crack when the body particle it stands for is.
        const Crack& crack = cracks[c];
        if (crack.cuts(ps.position[i], ps.position[j], dim) &&
            crack.covers(ps.position[stands_for[i]], dim) &&
            crack.covers(ps.position[stands_for[j]], dim)) {
          crossed = true;
          cut[c] += i < j ? 1 : 0;
        }
      }
      const std::size_t a = stands_for[i];
      const std::size_t b = stands_for[j];
      crossed =
          crossed || (holes && a != b && a < body_count && b < body_count &&
                      passes_through_hole(dim, spacing, bodies, ps.position[a], ps.position[b]));
      if (!crossed) {
        kept.neighbour.push_back(family.neighbour[k]);
        kept.inverse_length.push_back(family.inverse_length[k]);
      }
    }
    kept.offsets.push_back(kept.neighbour.size());
  }
  family = std::move(kept);
  return cut;
}

} // namespace pd
