// Splitting a model over ranks (discretisation/distribution.hpp) without MPI: localise is pure,
// so each rank's part can be built and checked in one process. Every particle has one owner, the
// halo plans of two ranks mirror each other, and each rank's forces on its own particles are
// bitwise those of the whole model — with ghost layers, quadratic clamps and mirror images whose
// forces fold onto sources that other ranks own, and under virtual fibres, whose forces read the
// neighbours' mean strains.
#include "libpd/discretisation/distribution.hpp"
#include "libpd/io/scene.hpp"
#include "libpd/kernel/linear_operator.hpp"
#include "libpd/time/integrator.hpp"

#include <algorithm>
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

/// Positions of the whole model: a random displacement of up to `jitter` per component, then
/// supports and extrapolation applied.
std::vector<double> displaced(const pd::Model& m, double jitter) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-jitter, jitter);
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

/// Each rank's forces on its own particles, computed on its part alone, against the whole model's
/// (bitwise), and the ranks' energies against the whole model's.
void expect_owned_forces_of_whole_model(pd::Model global, const std::vector<std::int32_t>& owner,
                                        double jitter = 1e-4) {
  const std::vector<double> y = displaced(global, jitter);
  // Energies first: the fibre kernel's forces change the arms' state (they yield and fail), and
  // the ranks' parts are cut from the model as it was.
  const double energy = pd::make_constrained_force_evaluator(global)->strain_energy(y.data());
  std::vector<double> b(y.size());
  pd::Model whole = global;
  pd::make_constrained_force_evaluator(whole)->compute(y.data(), b.data());

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
    const auto forces = pd::make_constrained_force_evaluator(local);
    parts.add(forces->strain_energy(yl.data())); // each rank's share (serial communicator)
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
  }
  EXPECT_EQ(checked, global.size());
  EXPECT_NEAR(parts.value(), energy, 1e-14 * std::abs(energy));
}

TEST(Distribution, OwnedForcesAndEnergyAreBitwiseThoseOfTheWholeModel) {
  const pd::Model global = clamped_beam();
  expect_owned_forces_of_whole_model(global, slab_owners(global));
}

/// Virtual fibres: a force reads both ends' mean strains, so a rank keeps its neighbours' rows
/// (distribution.cpp); the notched plates of the MPI tests, elastic (vectorised passes) and with
/// arms that yield and fail (scalar passes), cut into three slabs across the notch.
TEST(Distribution, FibreForcesAndEnergyAreBitwiseThoseOfTheWholeModel) {
  for (const char* scene : {"fibre-elastic-verlet.yaml", "fibre-plastic-adr.yaml"}) {
    SCOPED_TRACE(scene);
    const pd::Model global =
        pd::build_model(pd::load_scene(std::string(PD_SCENES_DIR) + "/../../tests/mpi/" + scene));
    ASSERT_FALSE(global.fibre_arms.empty());
    std::vector<std::int32_t> owner(global.size());
    for (std::size_t i = 0; i < global.size(); ++i) {
      const double x = global.particles.position[i][0];
      owner[i] = x < 0.0211 ? 0 : (x < 0.0437 ? 1 : 2);
    }
    // Displacements of 2 µm on arms of 2 to 7 mm: strains up to about 2e-3 against the plastic
    // scene's yield strain of 1e-3, so arms yield and some pass the elongation limit and fail.
    expect_owned_forces_of_whole_model(global, owner, 2e-6);
    if (global.effects.plasticity) {
      pd::Model probe = global;
      const std::vector<double> y = displaced(probe, 2e-6);
      std::vector<double> b(y.size());
      pd::make_constrained_force_evaluator(probe)->compute(y.data(), b.data());
      const auto& plastic = probe.state.plastic_stretch;
      const auto& broken = probe.state.broken;
      EXPECT_GT(std::count_if(plastic.begin(), plastic.end(), [](double e) { return e != 0; }), 0);
      EXPECT_GT(std::count(broken.begin(), broken.end(), std::uint8_t{1}), 0);
    }
    bool mean_only_rows = false;
    for (int r = 0; r < ranks; ++r) {
      const pd::Model local = pd::localise(global, owner, r, ranks, pd::serial_communicator());
      mean_only_rows = mean_only_rows || !local.ownership.row_for_mean_only.empty();
    }
    EXPECT_TRUE(mean_only_rows);
  }
}

} // namespace
