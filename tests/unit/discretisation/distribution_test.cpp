// Splitting a model over ranks (discretisation/distribution.hpp) without MPI: localise is pure,
// so each rank's part can be built and checked in one process. Every particle has one owner, the
// halo plans of two ranks mirror each other, and each rank's forces on its own particles are
// bitwise those of the whole model — with ghost layers, quadratic clamps and mirror images whose
// forces fold onto sources that other ranks own.
#include "libpd/discretisation/distribution.hpp"
#include "libpd/io/scene.hpp"
#include "libpd/kernel/linear_operator.hpp"
#include "libpd/time/integrator.hpp"

#include <cmath>
#include <gtest/gtest.h>
#include <random>
#include <string>
#include <vector>

namespace {

constexpr int ranks = 3;

/// The clamped beam of the MPI tests: ghosts, gradient weights, quadratic clamps (the defaults).
pd::Model clamped_beam() {
  return pd::build_model(
      pd::load_scene(std::string(PD_SCENES_DIR) + "/../../tests/mpi/clamped-beam-dynamic.yaml"));
}

/// Owners in slabs along the beam, cut where no lattice plane is (a stand-in for Zoltan).
std::vector<std::int32_t> slab_owners(const pd::Model& m) {
  std::vector<std::int32_t> owner(m.size());
  for (std::size_t i = 0; i < m.size(); ++i) {
    const double x = m.particles.position[i][0];
    owner[i] = x < 1.01 ? 0 : (x < 2.33 ? 1 : 2);
  }
  return owner;
}

/// Positions of the whole model: a random displacement, then supports and extrapolation applied.
std::vector<double> displaced(const pd::Model& m) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1e-4, 1e-4);
  std::vector<double> y(3 * m.size());
  for (std::size_t i = 0; i < m.size(); ++i) {
    for (std::size_t c = 0; c < 3; ++c) {
      y[3 * i + c] = m.particles.position[i][c] + u(rng);
    }
  }
  pd::apply_constraints(m, pd::LoadRamp{}, 1.0, y.data(), nullptr);
  return y;
}

TEST(Distribution, EveryParticleHasOneOwnerAndHaloPlansMirrorEachOther) {
  const pd::Model global = clamped_beam();
  ASSERT_FALSE(global.extrapolated.empty()); // the case under test: dependants cross ranks
  const auto owner = slab_owners(global);
  std::vector<pd::Model> part;
  for (int r = 0; r < ranks; ++r) {
    part.push_back(pd::localise(global, owner, r, ranks, pd::serial_communicator()));
  }
  std::vector<int> owned_by(global.size(), 0);
  for (const pd::Model& l : part) {
    for (std::size_t i = 0; i < l.size(); ++i) {
      owned_by[l.ownership.global(i)] += l.ownership.owns(i) ? 1 : 0;
    }
  }
  for (std::size_t g = 0; g < global.size(); ++g) {
    ASSERT_EQ(owned_by[g], 1) << "particle " << g;
  }
  for (int r = 0; r < ranks; ++r) {
    for (const auto& peer : part[static_cast<std::size_t>(r)].ownership.halo.peers) {
      const auto& theirs = part[static_cast<std::size_t>(peer.rank)].ownership;
      const auto back = std::find_if(theirs.halo.peers.begin(), theirs.halo.peers.end(),
                                     [&](const pd::HaloPlan::Peer& p) { return p.rank == r; });
      ASSERT_NE(back, theirs.halo.peers.end());
      ASSERT_EQ(peer.receive.size(), back->send.size());
      for (std::size_t k = 0; k < peer.receive.size(); ++k) {
        EXPECT_EQ(part[static_cast<std::size_t>(r)].ownership.global(peer.receive[k]),
                  theirs.global(back->send[k]));
      }
    }
  }
  const pd::PartitionQuality q = pd::partition_quality(global, owner, ranks);
  EXPECT_GT(q.cut_bonds, 0U);
  EXPECT_EQ(q.owned[0] + q.owned[1] + q.owned[2], global.size());
}

TEST(Distribution, OwnedForcesAndEnergyAreBitwiseThoseOfTheWholeModel) {
  pd::Model global = clamped_beam();
  const auto owner = slab_owners(global);
  const std::vector<double> y = displaced(global);
  std::vector<double> b(y.size());
  pd::make_constrained_force_evaluator(global)->compute(y.data(), b.data());
  const double energy = pd::make_constrained_force_evaluator(global)->strain_energy(y.data());

  pd::ExactSum parts;
  std::size_t checked = 0;
  for (int r = 0; r < ranks; ++r) {
    pd::Model local = pd::localise(global, owner, r, ranks, pd::serial_communicator());
    std::vector<double> yl(3 * local.size()), bl(3 * local.size());
    for (std::size_t i = 0; i < local.size(); ++i) {
      for (std::size_t c = 0; c < 3; ++c) {
        yl[3 * i + c] = y[3 * local.ownership.global(i) + c];
      }
    }
    auto forces = pd::make_constrained_force_evaluator(local);
    forces->compute(yl.data(), bl.data());
    for (std::size_t i = 0; i < local.size(); ++i) {
      if (!local.ownership.owns(i)) {
        continue;
      }
      for (std::size_t c = 0; c < 3; ++c) {
        ASSERT_EQ(bl[3 * i + c], b[3 * local.ownership.global(i) + c])
            << "rank " << r << ", particle " << local.ownership.global(i) << ", component " << c;
      }
      ++checked;
    }
    parts.add(forces->strain_energy(yl.data())); // each rank's share (serial communicator)
  }
  EXPECT_EQ(checked, global.size());
  EXPECT_NEAR(parts.value(), energy, 1e-14 * energy);
}

} // namespace
