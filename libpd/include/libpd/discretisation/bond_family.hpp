// Bond families in compressed sparse row (CSR) form (Pasupathy, Fig. 3: "Array 1" holds every
// particle's family members one after the other, "Array 2" where each family starts).
//
// Each bond is stored in both directions (i→j in i's row and j→i in j's row). The force kernel
// then gathers each particle's force from its own row only: no atomic updates, and the summation
// order per particle is fixed, so results are identical for any number of threads. The family knows
// nothing about materials or bond laws.
#pragma once

#include "libpd/core/geometry.hpp"
#include "libpd/core/names.hpp"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace pd {

/// Which bonds of length exactly δ exist.
/// On a lattice many distances equal δ exactly in exact arithmetic (e.g. the (2,2,2) offsets for
/// δ = 2√3λ), but their floating-point values scatter by a few ulps depending on position. To avoid
/// such coin flips the comparison uses a relative guard band of 1e-9·δ, far below the gap between
/// distinct lattice distances:
///  * inclusive (default): bond iff |ξ| ≤ δ(1 + 1e-9)  (the family of Miranda eq. 14, |ξ| ≤ δ)
///  * strict:              bond iff |ξ| < δ(1 − 1e-9)
enum class HorizonRule { inclusive, strict };

template <>
struct EnumName<HorizonRule> {
  static constexpr NameTable<HorizonRule, 2> table{{
      {"inclusive", HorizonRule::inclusive, "bonds of length exactly δ are kept"},
      {"strict", HorizonRule::strict, "bonds of length exactly δ are dropped"},
  }};
};

inline constexpr double horizon_guard_band = 1e-9;

/// The in-horizon rule, the one test behind every bond family, lattice-offset sum and resource
/// estimate: a bond of squared length r² exists iff r² ≤ reach² (inclusive) or r² < reach²
/// (strict), reach = δ(1 ± horizon_guard_band). Lengths and horizon may be in any one unit (the
/// lattice sums use units of λ, where δ = m).
struct InHorizon {
  InHorizon(double horizon, HorizonRule rule)
      : reach(rule == HorizonRule::inclusive ? horizon * (1.0 + horizon_guard_band)
                                             : horizon * (1.0 - horizon_guard_band)),
        reach_squared(reach * reach), inclusive(rule == HorizonRule::inclusive) {}

  bool operator()(double length_squared) const {
    return inclusive ? length_squared <= reach_squared : length_squared < reach_squared;
  }

  double reach;         ///< longest bond length that can exist (neighbour-search cell size)
  double reach_squared; ///< reach²
  bool inclusive;
};

struct BondFamily {
  std::vector<std::size_t> offsets;     ///< size N+1; row i is [offsets[i], offsets[i+1])
  std::vector<std::uint32_t> neighbour; ///< j of each directed bond
  std::vector<double> inverse_length;   ///< 1/|ξ| of each directed bond

  std::size_t particle_count() const { return offsets.empty() ? 0 : offsets.size() - 1; }
  std::size_t directed_bond_count() const { return neighbour.size(); }
  /// Number of bonds (unordered pairs), the count the papers report.
  std::size_t bond_count() const { return neighbour.size() / 2; }
  std::size_t family_size(std::size_t i) const { return offsets[i + 1] - offsets[i]; }
};

/// Build the families with a cell list of cell size δ: O(N) for a bounded density.
/// Rows are sorted by neighbour index.
BondFamily build_bond_family(const std::vector<Vec3>& position, int dim, double horizon,
                             HorizonRule rule = HorizonRule::inclusive);

/// For each directed bond k (i→j), the index of the reverse bond (j→i).
std::vector<std::size_t> reverse_bond_index(const BondFamily& family);

} // namespace pd
