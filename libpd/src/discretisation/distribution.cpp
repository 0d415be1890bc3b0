// Localising a model to one rank (distribution.hpp, ownership.hpp).
#include "libpd/discretisation/distribution.hpp"

#include <algorithm>
#include <fmt/format.h>
#include <stdexcept>

namespace pd {

namespace {

/// Who depends on whom outside the bond families: each ghost or clamp particle on the sources of
/// its extrapolation, each mirror dependant on its image. A dependant's position is set from its
/// sources, and its force is folded back onto them.
struct Dependencies {
  std::vector<std::vector<std::uint32_t>> sources;    ///< per particle, as a dependant
  std::vector<std::vector<std::uint32_t>> dependants; ///< per particle, as a source
  std::vector<std::uint8_t> extrapolated;             ///< per particle

  explicit Dependencies(const Model& m)
      : sources(m.size()), dependants(m.size()), extrapolated(m.size(), 0) {
    const ExtrapolatedParticles& e = m.extrapolated;
    for (std::size_t d = 0; d < e.size(); ++d) {
      extrapolated[e.particle[d]] = 1;
      for (std::size_t t = e.offsets[d]; t < e.offsets[d + 1]; ++t) {
        tie(e.particle[d], e.source[t]);
      }
    }
    for (const Constraint& c : m.constraints) {
      if (c.mirror_of != Constraint::no_mirror) {
        tie(c.particle, c.mirror_of);
      }
    }
  }

private:
  void tie(std::uint32_t dependant, std::uint32_t source) {
    sources[dependant].push_back(source);
    dependants[source].push_back(dependant);
  }
};

/// The particles a rank computes forces for (`compute`: its own, and the dependants whose forces
/// fold onto them), those whose bond rows it keeps (`rows`: these and, under virtual fibres, their
/// bond neighbours, whose mean strains the forces read) and those it holds (`held`: the rows'
/// particles, their bond neighbours, and the sources of every dependant among those).
struct LocalSet {
  std::vector<std::uint8_t> compute;
  std::vector<std::uint8_t> rows;
  std::vector<std::uint8_t> held;
};

/// Marks the bond neighbours of every particle marked in `from` in `to` (which may be `from`'s
/// copy, so a pass reads the set it started with).
void mark_neighbours(const Model& m, const std::vector<std::uint8_t>& from,
                     std::vector<std::uint8_t>& to) {
  for (std::size_t i = 0; i < from.size(); ++i) {
    if (from[i] != 0) {
      for (std::size_t k = m.family.offsets[i]; k < m.family.offsets[i + 1]; ++k) {
        to[m.family.neighbour[k]] = 1;
      }
    }
  }
}

LocalSet local_set(const Model& m, const Dependencies& deps, const std::vector<std::int32_t>& owner,
                   int rank) {
  const std::size_t n = m.size();
  LocalSet s{std::vector<std::uint8_t>(n, 0), {}, {}};
  for (std::size_t i = 0; i < n; ++i) {
    if (owner[i] == rank) {
      s.compute[i] = 1;
      for (const std::uint32_t d : deps.dependants[i]) {
        s.compute[d] = 1;
      }
    }
  }
  s.rows = s.compute;
  if (!m.fibre_arms.empty()) {
    // Eq. 70: an arm's tension reads the mean strain (eq. 73) of both its ends. The rank computes
    // its neighbours' means from their own rows rather than receiving them between the two passes:
    // a halo twice as deep and the rows' work done twice at the cut, but one exchange per
    // evaluation as for bond-based models, and each mean summed in the serial order.
    mark_neighbours(m, s.compute, s.rows);
  }
  s.held = s.rows;
  mark_neighbours(m, s.rows, s.held);
  for (std::size_t i = 0; i < n; ++i) { // sources are never dependants: one pass closes the set
    if (s.held[i] != 0) {
      for (const std::uint32_t src : deps.sources[i]) {
        s.held[src] = 1;
      }
    }
  }
  return s;
}

/// Particles held by `rank` that another rank owns and that are exchanged (not extrapolated:
/// those are set from their sources on every rank), ascending.
std::vector<std::uint32_t> halo_of(const LocalSet& s, const Dependencies& deps,
                                   const std::vector<std::int32_t>& owner, int rank, int from) {
  std::vector<std::uint32_t> out;
  for (std::size_t i = 0; i < s.held.size(); ++i) {
    if (s.held[i] != 0 && owner[i] == from && from != rank && deps.extrapolated[i] == 0) {
      out.push_back(static_cast<std::uint32_t>(i));
    }
  }
  return out;
}

template <class T>
std::vector<T> subset(const std::vector<T>& v, const std::vector<std::uint32_t>& keep,
                      std::size_t width = 1) {
  if (v.empty()) {
    return {};
  }
  std::vector<T> out;
  out.reserve(keep.size() * width);
  for (const std::uint32_t i : keep) {
    for (std::size_t c = 0; c < width; ++c) {
      out.push_back(v[width * i + c]);
    }
  }
  return out;
}

void copy_rows(const Model& g, Model& l, const LocalSet& s, const std::vector<std::uint32_t>& kept,
               const std::vector<std::int64_t>& local_of) {
  std::vector<std::uint32_t> bonds; // global directed-bond indices kept, in local row order
  l.family.offsets.assign(1, 0);
  for (const std::uint32_t gi : kept) {
    if (s.rows[gi] != 0) {
      for (std::size_t k = g.family.offsets[gi]; k < g.family.offsets[gi + 1]; ++k) {
        bonds.push_back(static_cast<std::uint32_t>(k));
        l.family.neighbour.push_back(static_cast<std::uint32_t>(local_of[g.family.neighbour[k]]));
        l.family.inverse_length.push_back(g.family.inverse_length[k]);
      }
    }
    l.family.offsets.push_back(l.family.neighbour.size());
  }
  l.field.stiffness = g.field.stiffness;
  l.field.critical_stretch = g.field.critical_stretch;
  l.field.yield_stretch = g.field.yield_stretch;
  l.field.bond_stiffness = subset(g.field.bond_stiffness, bonds);
  l.field.bond_critical_stretch = subset(g.field.bond_critical_stretch, bonds);
  l.field.bond_yield_stretch = subset(g.field.bond_yield_stretch, bonds);
  l.state.broken = subset(g.state.broken, bonds);
  l.state.plastic_stretch = subset(g.state.plastic_stretch, bonds);
  l.state.damage = subset(g.state.damage, kept);
  if (!g.fibre_arms.empty()) {
    FibreArms& a = l.fibre_arms;
    a = g.fibre_arms; // the scalars and the balance's record, then the arrays restricted
    a.own = subset(g.fibre_arms.own, bonds);
    a.other = subset(g.fibre_arms.other, bonds);
    a.shear = subset(g.fibre_arms.shear, kept);
    a.volumetric = subset(g.fibre_arms.volumetric, kept);
  }
}

void copy_ties(const Model& g, Model& l, const std::vector<std::int64_t>& local_of) {
  for (const Constraint& c : g.constraints) {
    if (local_of[c.particle] < 0) {
      continue;
    }
    Constraint lc = c;
    lc.particle = static_cast<std::uint32_t>(local_of[c.particle]);
    if (c.mirror_of != Constraint::no_mirror) {
      lc.mirror_of = static_cast<std::uint32_t>(local_of[c.mirror_of]);
    }
    l.constraints.push_back(lc);
  }
  const ExtrapolatedParticles& e = g.extrapolated;
  ExtrapolatedParticles& le = l.extrapolated;
  for (std::size_t d = 0; d < e.size(); ++d) {
    if (local_of[e.particle[d]] < 0) {
      continue;
    }
    le.particle.push_back(static_cast<std::uint32_t>(local_of[e.particle[d]]));
    for (std::size_t t = e.offsets[d]; t < e.offsets[d + 1]; ++t) {
      le.source.push_back(static_cast<std::uint32_t>(local_of[e.source[t]]));
      le.coefficient.push_back(e.coefficient[t]);
      if (!e.negated.empty()) {
        le.negated.push_back(e.negated[t]);
      }
    }
    le.offsets.push_back(le.source.size());
  }
}

} // namespace

Model localise(const Model& global, const std::vector<std::int32_t>& owner, int rank, int ranks,
               const Communicator& comm) {
  if (owner.size() != global.size()) {
    throw std::logic_error("localise: one owner per particle expected");
  }
  const Dependencies deps(global);
  const LocalSet mine = local_set(global, deps, owner, rank);
  std::vector<std::uint32_t> kept;
  std::vector<std::int64_t> local_of(global.size(), -1);
  for (std::size_t i = 0; i < global.size(); ++i) {
    if (mine.held[i] != 0) {
      local_of[i] = static_cast<std::int64_t>(kept.size());
      kept.push_back(static_cast<std::uint32_t>(i));
    }
  }

  Model l;
  l.spec = global.spec;
  l.effects = global.effects;
  l.bonds_cut_by_crack = global.bonds_cut_by_crack;
  l.particle_weights = global.particle_weights;
  l.particles.position = subset(global.particles.position, kept);
  l.particles.volume = subset(global.particles.volume, kept);
  l.particles.material = subset(global.particles.material, kept);
  l.particles.body = subset(global.particles.body, kept);
  l.particles.particle_size = subset(global.particles.particle_size, kept);
  l.density = subset(global.density, kept);
  l.external_force_density = subset(global.external_force_density, kept, 3);
  const std::size_t first_ghost = global.size() - global.ghost_count;
  l.ghost_count = static_cast<std::size_t>(
      std::count_if(kept.begin(), kept.end(), [&](std::uint32_t i) { return i >= first_ghost; }));
  copy_rows(global, l, mine, kept, local_of);
  copy_ties(global, l, local_of);

  Ownership& o = l.ownership;
  o.comm = &comm;
  o.global_index = kept;
  o.owned.resize(kept.size());
  for (std::size_t i = 0; i < kept.size(); ++i) {
    o.owned[i] = owner[kept[i]] == rank ? 1 : 0;
  }
  if (mine.rows != mine.compute) {
    o.row_for_mean_only.resize(kept.size());
    for (std::size_t i = 0; i < kept.size(); ++i) {
      o.row_for_mean_only[i] = mine.rows[kept[i]] != 0 && mine.compute[kept[i]] == 0 ? 1 : 0;
    }
  }
  o.global_particles = global.size();
  o.global_body_particles = global.body_particle_count();
  for (int peer = 0; peer < ranks; ++peer) {
    if (peer == rank) {
      continue;
    }
    HaloPlan::Peer p{peer, {}, {}};
    for (const std::uint32_t gi : halo_of(mine, deps, owner, rank, peer)) {
      p.receive.push_back(static_cast<std::uint32_t>(local_of[gi]));
    }
    const LocalSet theirs = local_set(global, deps, owner, peer);
    for (const std::uint32_t gi : halo_of(theirs, deps, owner, peer, rank)) {
      p.send.push_back(static_cast<std::uint32_t>(local_of[gi]));
    }
    if (!p.receive.empty() || !p.send.empty()) {
      o.halo.peers.push_back(std::move(p));
    }
  }
  return l;
}

PartitionQuality partition_quality(const Model& global, const std::vector<std::int32_t>& owner,
                                   int ranks) {
  PartitionQuality q;
  q.owned.assign(static_cast<std::size_t>(ranks), 0);
  for (std::size_t i = 0; i < global.size(); ++i) {
    ++q.owned[static_cast<std::size_t>(owner[i])];
    for (std::size_t k = global.family.offsets[i]; k < global.family.offsets[i + 1]; ++k) {
      const std::size_t j = global.family.neighbour[k];
      if (j > i && owner[j] != owner[i]) {
        ++q.cut_bonds;
      }
    }
  }
  return q;
}

} // namespace pd
