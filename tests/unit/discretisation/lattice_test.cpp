// Lattice generation: point counts and positions for both conventions, unions of boxes, volumes,
// ordering and jitter.
#include "libpd/discretisation/lattice.hpp"

#include <algorithm>
#include <cmath>
#include <gtest/gtest.h>
#include <set>
#include <tuple>

namespace {

using pd::BodySpec;
using pd::Box;
using pd::LatticeConvention;
using pd::LatticeSpec;
using pd::ModelDimension;
using pd::ParticleSet;
using pd::Region;
using pd::Vec3;

ModelDimension dim3() {
  return ModelDimension{};
}

BodySpec body(const std::vector<Box>& boxes, int material = 0) {
  BodySpec b;
  b.name = "b";
  b.region.boxes = boxes;
  b.material = material;
  return b;
}

/// Integer lattice index of a coordinate, for comparing positions without round-off.
long long index_of(double x, double origin, double spacing, double shift) {
  return std::llround((x - origin) / spacing - shift);
}

TEST(Lattice, CellCenteredBoxHasOnePointPerCellAtItsCentre) {
  const double lambda = 0.01;
  LatticeSpec l;
  l.spacing = lambda;
  const ParticleSet ps = pd::generate_lattice(dim3(), l, {body({Box{{0, 0, 0}, {1.0, 0.1, 0.1}}})});
  ASSERT_EQ(ps.size(), 100u * 10u * 10u);
  // Every point is a cell centre (i + ½)λ strictly inside the box, and each cell is hit once.
  std::set<std::tuple<long long, long long, long long>> cells;
  for (const Vec3& p : ps.position) {
    long long idx[3];
    for (int a = 0; a < 3; ++a) {
      idx[a] = index_of(p[a], 0.0, lambda, 0.5);
      EXPECT_NEAR(p[a], (static_cast<double>(idx[a]) + 0.5) * lambda, 1e-12);
      EXPECT_GT(p[a], 0.0);
    }
    EXPECT_LT(p[0], 1.0);
    EXPECT_LT(p[1], 0.1);
    EXPECT_LT(p[2], 0.1);
    EXPECT_GE(idx[0], 0);
    EXPECT_LT(idx[0], 100);
    EXPECT_GE(idx[1], 0);
    EXPECT_LT(idx[1], 10);
    EXPECT_GE(idx[2], 0);
    EXPECT_LT(idx[2], 10);
    cells.insert({idx[0], idx[1], idx[2]});
  }
  EXPECT_EQ(cells.size(), ps.size());
  // The volumes tile the box exactly.
  double total = 0;
  for (double v : ps.volume) {
    EXPECT_DOUBLE_EQ(v, lambda * lambda * lambda);
    total += v;
  }
  EXPECT_NEAR(total, 1.0 * 0.1 * 0.1, 1e-12);
}

TEST(Lattice, NodeBasedMirandaModelA) {
  LatticeSpec l;
  l.spacing = 0.05;
  l.convention = LatticeConvention::node_based;
  const ParticleSet ps = pd::generate_lattice(dim3(), l, {body({Box{{0, 0, 0}, {4.1, 0.4, 0.3}}})});
  ASSERT_EQ(ps.size(), 83u * 9u * 7u);
  ASSERT_EQ(ps.size(), 5229u);
  // Nodes include the corners and faces of the box.
  double lo[3] = {1e9, 1e9, 1e9}, hi[3] = {-1e9, -1e9, -1e9};
  for (const Vec3& p : ps.position) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], p[a]);
      hi[a] = std::max(hi[a], p[a]);
      const long long n = index_of(p[a], 0.0, 0.05, 0.0);
      EXPECT_NEAR(p[a], static_cast<double>(n) * 0.05, 1e-12);
    }
  }
  EXPECT_NEAR(lo[0], 0.0, 1e-12);
  EXPECT_NEAR(lo[1], 0.0, 1e-12);
  EXPECT_NEAR(lo[2], 0.0, 1e-12);
  EXPECT_NEAR(hi[0], 4.1, 1e-12);
  EXPECT_NEAR(hi[1], 0.4, 1e-12);
  EXPECT_NEAR(hi[2], 0.3, 1e-12);
  EXPECT_EQ(pd::count_lattice_points(dim3(), l, Region{{Box{{0, 0, 0}, {4.1, 0.4, 0.3}}}}), 5229u);
}

TEST(Lattice, NodeBasedWithNonZeroOrigin) {
  // The lattice is anchored at the origin, not at the box: a box that starts half a spacing off
  // the lattice loses its face layer.
  LatticeSpec l;
  l.spacing = 0.1;
  l.convention = LatticeConvention::node_based;
  l.origin = {0.05, 0, 0};
  const ParticleSet ps = pd::generate_lattice(dim3(), l, {body({Box{{0, 0, 0}, {1.0, 0.2, 0.2}}})});
  // x nodes at 0.05, 0.15, ..., 0.95 (10), y and z at 0, 0.1, 0.2 (3 each).
  ASSERT_EQ(ps.size(), 10u * 3u * 3u);
  EXPECT_NEAR(ps.position.front()[0], 0.05, 1e-12);
  EXPECT_NEAR(ps.position.back()[0], 0.95, 1e-12);
}

TEST(Lattice, UnionOfTouchingAndOverlappingBoxesHasNoDuplicates) {
  for (LatticeConvention conv : {LatticeConvention::cell_centered, LatticeConvention::node_based}) {
    LatticeSpec l;
    l.spacing = 0.1;
    l.convention = conv;
    // Touching at x = 1 and overlapping on [0.5, 1] × [0, 0.3]; the second body repeats a box.
    const Box a{{0, 0, 0}, {1.0, 0.3, 0.2}};
    const Box b{{1.0, 0, 0}, {2.0, 0.3, 0.2}};
    const Box c{{0.5, 0, 0}, {1.5, 0.5, 0.2}};
    const std::vector<BodySpec> bodies{body({a, b}, 0), body({c, a}, 1)};
    const ParticleSet ps = pd::generate_lattice(dim3(), l, bodies);

    std::set<std::tuple<long long, long long, long long>> seen;
    const double shift = conv == LatticeConvention::cell_centered ? 0.5 : 0.0;
    for (std::size_t i = 0; i < ps.size(); ++i) {
      const Vec3& p = ps.position[i];
      const auto key = std::make_tuple(index_of(p[0], 0, 0.1, shift), index_of(p[1], 0, 0.1, shift),
                                       index_of(p[2], 0, 0.1, shift));
      EXPECT_TRUE(seen.insert(key).second) << "duplicate point " << p[0] << " " << p[1];
      // Shared points belong to the first body listed.
      const bool in_first = a.contains(p, 3, 1e-9) || b.contains(p, 3, 1e-9);
      EXPECT_EQ(ps.body[i], in_first ? 0 : 1);
      EXPECT_EQ(ps.material[i], in_first ? 0 : 1);
    }
    // Independent count: lattice points of the bounding box that lie in any of the boxes.
    std::size_t expected = 0;
    const double off = shift * 0.1;
    for (long long k = -2; k < 30; ++k) {
      for (long long j = -2; j < 30; ++j) {
        for (long long i = -2; i < 30; ++i) {
          const Vec3 p{static_cast<double>(i) * 0.1 + off, static_cast<double>(j) * 0.1 + off,
                       static_cast<double>(k) * 0.1 + off};
          if (a.contains(p, 3, 1e-9) || b.contains(p, 3, 1e-9) || c.contains(p, 3, 1e-9)) {
            ++expected;
          }
        }
      }
    }
    EXPECT_EQ(ps.size(), expected);
    Region all;
    all.boxes = {a, b, c, a};
    EXPECT_EQ(pd::count_lattice_points(dim3(), l, all), expected);
    if (conv == LatticeConvention::cell_centered) {
      // The cells tile the union: a ∪ b = [0,2]×[0,0.3]×[0,0.2] is 20·3·2 cells and c adds
      // [0.5,1.5]×[0.3,0.5]×[0,0.2], 10·2·2 cells.
      EXPECT_EQ(expected, 20u * 3u * 2u + 10u * 2u * 2u);
    } else {
      // Nodes of [0,2]×[0,0.3]×[0,0.2]: 21·4·3, plus c's nodes with y in {0.4, 0.5}: 11·2·3.
      EXPECT_EQ(expected, 21u * 4u * 3u + 11u * 2u * 3u);
    }
  }
}

TEST(Lattice, OneAndTwoDimensionalVolumes) {
  const double lambda = 0.02;
  {
    ModelDimension d;
    d.dim = 1;
    d.cross_section = 3e-4;
    LatticeSpec l;
    l.spacing = lambda;
    const ParticleSet ps = pd::generate_lattice(d, l, {body({Box{{0, 5, 5}, {1.0, -5, -5}}})});
    // Unused coordinates are ignored (even an "inverted" y/z range) and set to zero.
    ASSERT_EQ(ps.size(), 50u);
    for (std::size_t i = 0; i < ps.size(); ++i) {
      EXPECT_DOUBLE_EQ(ps.volume[i], lambda * 3e-4);
      EXPECT_EQ(ps.position[i][1], 0.0);
      EXPECT_EQ(ps.position[i][2], 0.0);
      EXPECT_NEAR(ps.position[i][0], (static_cast<double>(i) + 0.5) * lambda, 1e-12);
    }
    EXPECT_DOUBLE_EQ(pd::cell_volume(d, lambda), lambda * 3e-4);
  }
  {
    ModelDimension d;
    d.dim = 2;
    d.thickness = 0.005;
    LatticeSpec l;
    l.spacing = lambda;
    const ParticleSet ps = pd::generate_lattice(d, l, {body({Box{{0, 0, 0}, {0.2, 0.1, 0}}})});
    ASSERT_EQ(ps.size(), 10u * 5u);
    for (std::size_t i = 0; i < ps.size(); ++i) {
      EXPECT_DOUBLE_EQ(ps.volume[i], lambda * lambda * 0.005);
      EXPECT_EQ(ps.position[i][2], 0.0);
    }
    EXPECT_DOUBLE_EQ(pd::cell_volume(d, lambda), lambda * lambda * 0.005);
  }
  EXPECT_DOUBLE_EQ(pd::cell_volume(dim3(), lambda), lambda * lambda * lambda);
}

TEST(Lattice, OrderIsXFastestThenYThenZ) {
  LatticeSpec l;
  l.spacing = 0.1;
  // Boxes listed in an order that is not the storage order.
  const std::vector<BodySpec> bodies{body({Box{{0, 0.2, 0.2}, {0.4, 0.4, 0.4}}}),
                                     body({Box{{0, 0, 0}, {0.4, 0.2, 0.2}}})};
  const ParticleSet ps = pd::generate_lattice(dim3(), l, bodies);
  ASSERT_EQ(ps.size(), 4u * 2u * 2u * 2u);
  for (std::size_t i = 1; i < ps.size(); ++i) {
    const Vec3& p = ps.position[i - 1];
    const Vec3& q = ps.position[i];
    EXPECT_TRUE(std::tie(p[2], p[1], p[0]) < std::tie(q[2], q[1], q[0])) << i;
  }
  // x fastest: the first 4 points form a row along x.
  for (std::size_t i = 1; i < 4; ++i) {
    EXPECT_NEAR(ps.position[i][0] - ps.position[i - 1][0], 0.1, 1e-12);
    EXPECT_EQ(ps.position[i][1], ps.position[0][1]);
    EXPECT_EQ(ps.position[i][2], ps.position[0][2]);
  }
  // Calling twice gives the same result.
  const ParticleSet again = pd::generate_lattice(dim3(), l, bodies);
  EXPECT_EQ(again.position, ps.position);
}

TEST(Lattice, JitterIsBoundedAndReproducible) {
  const double lambda = 0.05;
  for (int dim : {1, 2, 3}) {
    ModelDimension d;
    d.dim = dim;
    LatticeSpec plain;
    plain.spacing = lambda;
    LatticeSpec jittered = plain;
    jittered.position_jitter = 0.2;
    jittered.volume_variation = 0.1;
    jittered.seed = 42;
    const std::vector<BodySpec> bodies{body({Box{{0, 0, 0}, {0.5, 0.3, 0.2}}})};
    const ParticleSet a = pd::generate_lattice(d, plain, bodies);
    const ParticleSet b = pd::generate_lattice(d, jittered, bodies);
    const ParticleSet c = pd::generate_lattice(d, jittered, bodies);
    ASSERT_EQ(a.size(), b.size());
    double largest = 0;
    bool moved = false;
    for (std::size_t i = 0; i < a.size(); ++i) {
      for (int k = 0; k < 3; ++k) {
        const double delta = std::abs(b.position[i][k] - a.position[i][k]);
        if (k >= dim) {
          EXPECT_EQ(delta, 0.0);
        }
        EXPECT_LE(delta, 0.2 * lambda * (1 + 1e-12));
        largest = std::max(largest, delta);
        moved = moved || delta > 0;
      }
      const double ratio = b.volume[i] / a.volume[i];
      EXPECT_GE(ratio, 0.9 - 1e-12);
      EXPECT_LE(ratio, 1.1 + 1e-12);
    }
    EXPECT_TRUE(moved);
    // With hundreds of draws the largest should come close to the bound.
    if (dim > 1) {
      EXPECT_GT(largest, 0.15 * lambda);
    }
    EXPECT_EQ(b.position, c.position);
    EXPECT_EQ(b.volume, c.volume);
    jittered.seed = 43;
    const ParticleSet e = pd::generate_lattice(d, jittered, bodies);
    EXPECT_NE(e.position, b.position);
  }
}

TEST(Lattice, CountAgreesWithGenerate) {
  const std::vector<std::vector<Box>> regions{
      {Box{{0, 0, 0}, {1, 0.5, 0.3}}},
      {Box{{0, 0, 0}, {1, 0.5, 0.3}}, Box{{0.5, 0.25, 0}, {1.5, 1.0, 0.3}}},
      {Box{{0.03, 0.01, 0.02}, {0.71, 0.33, 0.19}}, Box{{0.71, 0.01, 0.02}, {0.9, 0.2, 0.4}}},
      {Box{{0, 0, 0}, {0.5, 0.5, 0.5}}, Box{{0.1, 0.1, 0.1}, {0.2, 0.2, 0.2}}}};
  for (LatticeConvention conv : {LatticeConvention::cell_centered, LatticeConvention::node_based}) {
    for (int dim : {1, 2, 3}) {
      for (const auto& boxes : regions) {
        ModelDimension d;
        d.dim = dim;
        LatticeSpec l;
        l.spacing = 0.05;
        l.convention = conv;
        l.origin = {0.01, -0.02, 0.0};
        const std::size_t generated = pd::generate_lattice(d, l, {body(boxes)}).size();
        EXPECT_EQ(pd::count_lattice_points(d, l, Region{boxes}), generated)
            << "dim " << dim << " boxes " << boxes.size();
        EXPECT_GT(generated, 0u);
      }
    }
  }
}

TEST(Lattice, EmptyAndInvalid) {
  LatticeSpec l;
  l.spacing = 0.1;
  // A box thinner than a cell holds no cell centre.
  EXPECT_EQ(pd::generate_lattice(dim3(), l, {body({Box{{0.01, 0, 0}, {0.04, 1, 1}}})}).size(), 0u);
  EXPECT_EQ(pd::count_lattice_points(dim3(), l, Region{{Box{{0.01, 0, 0}, {0.04, 1, 1}}}}), 0u);
  l.spacing = 0;
  EXPECT_THROW(pd::generate_lattice(dim3(), l, {body({Box{{0, 0, 0}, {1, 1, 1}}})}),
               std::invalid_argument);
}

} // namespace
