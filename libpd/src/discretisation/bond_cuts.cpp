// Bonds that must not exist: across a pre-crack, or through a hole of a body (issue 19).
#include "libpd/discretisation/bond_cuts.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace pd {

namespace {

/// Whether p lies inside the lattice cell centred on x (not on its faces).
bool in_cell(const Vec3& p, const Vec3& x, int dim, double spacing) {
  for (std::size_t k = 0; k < static_cast<std::size_t>(dim); ++k) {
    if (std::abs(p[k] - x[k]) >= 0.5 * spacing * (1 - 1e-9)) {
      return false;
    }
  }
  return true;
}

/// Whether p lies in some body's `minus` shape and in no body.
bool in_a_hole(int dim, double spacing, const std::vector<BodySpec>& bodies, const Vec3& p) {
  const double tol = 1e-6 * spacing;
  bool in_hole = false;
  for (const BodySpec& body : bodies) {
    for (const Shape& hole : body.region.minus) {
      in_hole = in_hole || hole.contains(p, dim, -tol);
    }
  }
  return in_hole && std::none_of(bodies.begin(), bodies.end(), [&](const BodySpec& body) {
           return body.region.contains(p, dim, tol);
         });
}

} // namespace

/// Whether the bond between body particles a and b passes through a hole: a point of it, sampled
/// every λ/8, lies in some body's `minus` shape and in no body. A notch narrower than the horizon
/// would otherwise be bridged by the bonds across it. Points inside either end's own lattice cell
/// do not count: a cut cell (lattice.hpp) whose site lies in the hole still holds material.
bool bond_passes_through_hole(int dim, double spacing, const std::vector<BodySpec>& bodies,
                              const Vec3& a, const Vec3& b) {
  double length = 0;
  for (std::size_t k = 0; k < 3; ++k) {
    length += (b[k] - a[k]) * (b[k] - a[k]);
  }
  const auto samples = static_cast<int>(std::ceil(std::sqrt(length) / (0.125 * spacing)));
  for (int s = 1; s < samples; ++s) {
    const double t = static_cast<double>(s) / samples;
    const Vec3 p{a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), a[2] + t * (b[2] - a[2])};
    if (in_cell(p, a, dim, spacing) || in_cell(p, b, dim, spacing)) {
      continue;
    }
    if (in_a_hole(dim, spacing, bodies, p)) {
      return true;
    }
  }
  return false;
}

std::vector<std::size_t> cut_bonds_across_cracks_and_holes(
    int dim, double spacing, const std::vector<Crack>& cracks, const std::vector<BodySpec>& bodies,
    const ParticleSet& ps, std::size_t body_count, const std::vector<std::uint8_t>& mirror_image,
    BondFamily& family) {
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
  // For the holes, a ghost inside a hole stands for all its equally near body particles (a ghost
  // in a hole often has several, and a choice by index would make a symmetric body's ghosts lose
  // bonds on one side only); the mirror images of body particles beyond symmetry planes count as
  // body particles, as in the full model. Any other ghost (beyond a face, or such an image) stands
  // for itself, as the body particle it continues or mirrors would.
  const auto body_like = [&](std::size_t k) {
    return k < body_count || (!mirror_image.empty() && mirror_image[k] != 0);
  };
  std::vector<std::vector<std::size_t>> seen_as(holes ? ps.size() : 0);
  for (std::size_t g = 0; g < seen_as.size(); ++g) {
    if (body_like(g) || !in_a_hole(dim, spacing, bodies, ps.position[g])) {
      seen_as[g].push_back(g);
      continue;
    }
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t k = family.offsets[g]; k < family.offsets[g + 1]; ++k) {
      if (body_like(family.neighbour[k])) {
        best = std::min(best, 1.0 / family.inverse_length[k]);
      }
    }
    for (std::size_t k = family.offsets[g]; k < family.offsets[g + 1]; ++k) {
      if (body_like(family.neighbour[k]) && 1.0 / family.inverse_length[k] <= best * (1 + 1e-9)) {
        seen_as[g].push_back(family.neighbour[k]);
      }
    }
  }
  // A bond passes through a hole when it does for every choice among what its ends stand for.
  const auto through_hole = [&](std::size_t i, std::size_t j) {
    if (seen_as[i].empty() || seen_as[j].empty()) {
      return false; // a ghost in a hole with no body particle near: no bond to judge by
    }
    for (const std::size_t a : seen_as[i]) {
      for (const std::size_t b : seen_as[j]) {
        if (a == b ||
            !bond_passes_through_hole(dim, spacing, bodies, ps.position[a], ps.position[b])) {
          return false;
        }
      }
    }
    return true;
  };
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
      crossed = crossed || (holes && through_hole(i, j));
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
