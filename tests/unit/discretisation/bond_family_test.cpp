// Neighbour search: the cell-list families against an O(N²) search, CSR invariants, reverse
// bonds and the treatment of bonds exactly on the horizon.
#include "libpd/discretisation/bond_family.hpp"
#include "libpd/discretisation/lattice.hpp"

#include <algorithm>
#include <cmath>
#include <gtest/gtest.h>
#include <random>
#include <string>

namespace {

using pd::BondFamily;
using pd::HorizonRule;
using pd::Vec3;

/// The O(N²) definition of a family, with the documented guard band.
std::vector<std::vector<std::uint32_t>> brute_force(const std::vector<Vec3>& x, double horizon,
                                                    HorizonRule rule) {
  std::vector<std::vector<std::uint32_t>> rows(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) {
    for (std::size_t j = 0; j < x.size(); ++j) {
      if (i == j) {
        continue;
      }
      const double r = std::sqrt((x[j][0] - x[i][0]) * (x[j][0] - x[i][0]) +
                                 (x[j][1] - x[i][1]) * (x[j][1] - x[i][1]) +
                                 (x[j][2] - x[i][2]) * (x[j][2] - x[i][2]));
      const bool in =
          rule == HorizonRule::inclusive ? r <= horizon * (1 + 1e-9) : r < horizon * (1 - 1e-9);
      if (in) {
        rows[i].push_back(static_cast<std::uint32_t>(j));
      }
    }
  }
  return rows;
}

std::vector<std::uint32_t> row(const BondFamily& f, std::size_t i) {
  return {f.neighbour.begin() + static_cast<std::ptrdiff_t>(f.offsets[i]),
          f.neighbour.begin() + static_cast<std::ptrdiff_t>(f.offsets[i + 1])};
}

/// Checks every invariant of a family built from `x`, including agreement with brute force.
void check_family(const std::vector<Vec3>& x, int dim, double horizon, HorizonRule rule,
                  const std::string& what) {
  SCOPED_TRACE(what);
  const BondFamily f = pd::build_bond_family(x, dim, horizon, rule);
  const auto expected = brute_force(x, horizon, rule);
  ASSERT_EQ(f.particle_count(), x.size());
  ASSERT_EQ(f.offsets.front(), 0u);
  ASSERT_EQ(f.offsets.back(), f.neighbour.size());
  ASSERT_EQ(f.inverse_length.size(), f.neighbour.size());
  std::size_t total = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const auto r = row(f, i);
    ASSERT_EQ(r, expected[i]) << "row " << i; // same members, sorted (brute force is sorted)
    EXPECT_EQ(f.family_size(i), r.size());
    EXPECT_TRUE(std::is_sorted(r.begin(), r.end()));
    total += r.size();
    for (std::size_t k = f.offsets[i]; k < f.offsets[i + 1]; ++k) {
      const std::size_t j = f.neighbour[k];
      const double len = std::hypot(x[j][0] - x[i][0], x[j][1] - x[i][1], x[j][2] - x[i][2]);
      EXPECT_NEAR(f.inverse_length[k] * len, 1.0, 1e-14);
      // Symmetry: i is in j's row.
      const auto rj = row(f, j);
      EXPECT_TRUE(std::binary_search(rj.begin(), rj.end(), static_cast<std::uint32_t>(i)));
    }
  }
  EXPECT_EQ(f.directed_bond_count(), total);
  EXPECT_EQ(total % 2, 0u);
  EXPECT_EQ(f.bond_count(), total / 2);

  const std::vector<std::size_t> rev = pd::reverse_bond_index(f);
  ASSERT_EQ(rev.size(), f.neighbour.size());
  for (std::size_t i = 0; i < x.size(); ++i) {
    for (std::size_t k = f.offsets[i]; k < f.offsets[i + 1]; ++k) {
      const std::size_t j = f.neighbour[k];
      const std::size_t kr = rev[k];
      ASSERT_GE(kr, f.offsets[j]);
      ASSERT_LT(kr, f.offsets[j + 1]);
      EXPECT_EQ(f.neighbour[kr], i);
      EXPECT_EQ(rev[kr], k);
      // The two directions of a bond see bitwise the same length.
      EXPECT_EQ(f.inverse_length[kr], f.inverse_length[k]);
    }
  }
}

std::vector<Vec3> random_points(std::size_t n, int dim, double size, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, size);
  std::vector<Vec3> x(n, Vec3{0, 0, 0});
  for (Vec3& p : x) {
    for (int a = 0; a < dim; ++a) {
      p[a] = u(rng);
    }
  }
  return x;
}

std::vector<Vec3> jittered_lattice(int dim, double lambda, double jitter, std::uint64_t seed) {
  pd::ModelDimension d;
  d.dim = dim;
  pd::LatticeSpec l;
  l.spacing = lambda;
  l.position_jitter = jitter;
  l.seed = seed;
  l.origin = {-0.013, 0.027, 0.1};
  pd::BodySpec b;
  b.region.boxes = {pd::Box{{0, 0, 0}, {dim == 1 ? 3.0 : 1.0, 0.7, 0.5}}};
  return pd::generate_lattice(d, l, {b}).position;
}

TEST(BondFamily, MatchesBruteForceOnRandomPoints) {
  for (int dim : {1, 2, 3}) {
    for (std::uint64_t seed : {1u, 2u, 3u}) {
      const std::size_t n = dim == 1 ? 60 : (dim == 2 ? 250 : 400);
      const auto x = random_points(n, dim, 1.0, seed);
      // Horizons from a fraction of a typical spacing up to a large part of the box.
      for (double horizon : {0.03, 0.11, 0.37}) {
        for (HorizonRule rule : {HorizonRule::inclusive, HorizonRule::strict}) {
          check_family(x, dim, horizon, rule,
                       "random dim " + std::to_string(dim) + " seed " + std::to_string(seed) +
                           " horizon " + std::to_string(horizon));
        }
      }
    }
  }
}

TEST(BondFamily, MatchesBruteForceOnJitteredLattices) {
  for (int dim : {1, 2, 3}) {
    for (std::uint64_t seed : {5u, 6u}) {
      const double lambda = dim == 3 ? 0.1 : 0.05;
      const auto x = jittered_lattice(dim, lambda, 0.25, seed);
      ASSERT_GT(x.size(), 20u);
      for (double m : {1.5, 3.015}) {
        for (HorizonRule rule : {HorizonRule::inclusive, HorizonRule::strict}) {
          check_family(x, dim, m * lambda, rule,
                       "jittered dim " + std::to_string(dim) + " m " + std::to_string(m));
        }
      }
    }
  }
}

TEST(BondFamily, RegularLatticeFamilySizes) {
  // Bulk family of δ = 3.015λ in 3D: all integer offsets with |n|² ≤ 9, minus the centre.
  int bulk = 0;
  for (int i = -3; i <= 3; ++i) {
    for (int j = -3; j <= 3; ++j) {
      for (int k = -3; k <= 3; ++k) {
        bulk += (i * i + j * j + k * k <= 9 && (i || j || k)) ? 1 : 0;
      }
    }
  }
  pd::LatticeSpec l;
  l.spacing = 0.1;
  pd::BodySpec b;
  b.region.boxes = {pd::Box{{0, 0, 0}, {0.8, 0.8, 0.8}}}; // 8³: the middle particles are bulk
  const auto x = pd::generate_lattice(pd::ModelDimension{}, l, {b}).position;
  const BondFamily f = pd::build_bond_family(x, 3, 0.3015);
  std::size_t largest = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    largest = std::max(largest, f.family_size(i));
  }
  EXPECT_EQ(largest, static_cast<std::size_t>(bulk));
  EXPECT_EQ(bulk, 122);
}

TEST(BondFamily, ExactlyOnHorizonIsDecidedTheSameEverywhere) {
  // δ = 2√3λ: the (±2,±2,±2) offsets lie exactly on the horizon. With origin 0.1 and λ = 0.05 the
  // computed distances scatter by a few ulps from particle to particle; the guard band must make
  // the decision uniform.
  const double lambda = 0.05;
  pd::LatticeSpec l;
  l.spacing = lambda;
  l.convention = pd::LatticeConvention::node_based;
  l.origin = {0.1, 0.1, 0.1};
  pd::BodySpec b;
  b.region.boxes = {
      pd::Box{{0.1, 0.1, 0.1}, {0.1 + 9 * lambda, 0.1 + 7 * lambda, 0.1 + 6 * lambda}}};
  const auto x = pd::generate_lattice(pd::ModelDimension{}, l, {b}).position;
  ASSERT_EQ(x.size(), 10u * 8u * 7u);
  const double horizon = 2.0 * std::sqrt(3.0) * lambda;
  const BondFamily inc = pd::build_bond_family(x, 3, horizon, HorizonRule::inclusive);
  const BondFamily str = pd::build_bond_family(x, 3, horizon, HorizonRule::strict);

  // The raw distances really are ambiguous: some (2,2,2) pairs are computed above δ, some below
  // (otherwise this test would not exercise the guard band).
  bool above = false, below = false;
  std::size_t corner_pairs = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    long long ni[3];
    for (int a = 0; a < 3; ++a) {
      ni[a] = std::llround((x[i][a] - 0.1) / lambda);
    }
    const auto ri = row(inc, i);
    const auto rs = row(str, i);
    for (std::size_t j = 0; j < x.size(); ++j) {
      long long d2 = 0;
      bool corner = true;
      for (int a = 0; a < 3; ++a) {
        const long long dn = std::llround((x[j][a] - 0.1) / lambda) - ni[a];
        d2 += dn * dn;
        corner = corner && (dn == 2 || dn == -2);
      }
      const bool in_inc = std::binary_search(ri.begin(), ri.end(), static_cast<std::uint32_t>(j));
      const bool in_str = std::binary_search(rs.begin(), rs.end(), static_cast<std::uint32_t>(j));
      if (corner) {
        ++corner_pairs;
        EXPECT_TRUE(in_inc) << i << "->" << j;
        EXPECT_FALSE(in_str) << i << "->" << j;
        const double r = std::hypot(x[j][0] - x[i][0], x[j][1] - x[i][1], x[j][2] - x[i][2]);
        above = above || r > horizon;
        below = below || r < horizon;
      } else if (j != i) {
        // Every other offset is unambiguous: |n|² < 12 inside both, > 12 outside both.
        EXPECT_EQ(in_inc, d2 < 12) << i << "->" << j;
        EXPECT_EQ(in_str, d2 < 12) << i << "->" << j;
      }
    }
  }
  EXPECT_GT(corner_pairs, 0u);
  EXPECT_TRUE(above);
  EXPECT_TRUE(below);
  // Each particle's rows differ by exactly its (2,2,2) corner partners.
  EXPECT_EQ(inc.directed_bond_count() - str.directed_bond_count(), corner_pairs);
}

TEST(BondFamily, InvalidHorizonThrows) {
  const std::vector<Vec3> x{{0, 0, 0}, {1, 0, 0}};
  EXPECT_THROW(pd::build_bond_family(x, 3, 0.0), std::invalid_argument);
  EXPECT_THROW(pd::build_bond_family(x, 3, -1.0), std::invalid_argument);
}

TEST(BondFamily, IsolatedParticlesHaveEmptyRows) {
  const std::vector<Vec3> x{{0, 0, 0}, {10, 0, 0}, {10.5, 0, 0}};
  const BondFamily f = pd::build_bond_family(x, 1, 1.0);
  EXPECT_EQ(f.family_size(0), 0u);
  EXPECT_EQ(f.family_size(1), 1u);
  EXPECT_EQ(f.family_size(2), 1u);
  EXPECT_EQ(f.bond_count(), 1u);
}

} // namespace
