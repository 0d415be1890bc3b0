// The reduced stiffness of the static solve, assembled in 3×3 blocks per pair of particles.
//
// With u = A u_f + u_p (A maps the unknowns to every dof: free dofs themselves, dependants through
// their terms; u_p holds the prescribed values and what dependants take from prescribed sources)
// and B the map of equations (a free row times its particle's volume; a dependant whose forces
// fold sends its row, times its own volume, to its sources with its coefficients, as
// fold_mirror_forces does), the system is Bᵀ K A u_f = Bᵀ (b_ext − K u_p): Aᵀ (V K) A, symmetric,
// when every dependant folds; V (K_ff + K_fd A) under `copy` mirrors.
//
// A dependant's terms never mix components (ExtrapolatedParticles, Constraint), so A and B are
// diagonal 3×3 blocks per pair of particles and K is k n⊗n per bond: the product is formed per
// particle pair, row by row (Gustavson: a dense block accumulator over the particles, reset by a
// marker), nine times fewer index operations than the same product per dof. Row p gathers
// Σ_i B_ipᵀ (K A)_i· over the particles i that use p: p itself and every dependant p is a source
// of. A ghost has about 50 sources, so its K_ii A_i· couples all of them: this is what makes a
// row about ten times denser than the bonds, and what the assembly spends its time on.
#include "static_assembly.hpp"

#include "libpd/kernel/linear_operator.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace pd {

bool DofMap::every_dependant_folds() const {
  for (std::size_t g = 0; g < kind.size(); ++g) {
    if (kind[g] == 2 && folds_row[g] == 0) {
      return false;
    }
  }
  return true;
}

DofMap map_dofs(const Model& m, const ExtrapolatedParticles& e) {
  const std::size_t ndof = 3 * m.size();
  DofMap d;
  d.free_index.assign(ndof, DofMap::none);
  d.terms.assign(ndof, {});
  d.prescribed.assign(ndof, 0.0);
  d.kind.assign(ndof, 0);
  d.folds_row.assign(ndof, 0);
  const int dim = m.spec.dimension.dim;
  for (std::size_t g = 0; g < ndof; ++g) {
    if (static_cast<int>(g % 3) >= dim) {
      d.kind[g] = 1; // out-of-plane components stay zero
    }
  }
  const bool consistent = consistent_mirror_coupling(m);
  for (const Constraint& c : m.constraints) {
    const std::size_t g = 3 * c.particle + c.component;
    if (c.mirror_of != Constraint::no_mirror) {
      d.kind[g] = 2;
      d.terms[g] = {{3 * c.mirror_of + c.component, c.mirror_sign}};
      d.folds_row[g] = consistent ? 1 : 0;
    } else {
      d.kind[g] = 1;
      d.prescribed[g] = c.value;
    }
  }
  for (std::size_t k = 0; k < e.size(); ++k) {
    for (std::size_t a = 0; a < static_cast<std::size_t>(dim); ++a) {
      const std::size_t g = 3 * e.particle[k] + a;
      d.kind[g] = 2;
      d.folds_row[g] = 1;
      for (std::size_t t = e.offsets[k]; t < e.offsets[k + 1]; ++t) {
        d.terms[g].push_back({3 * e.source[t] + a, e.sign(t, a) * e.coefficient[t]});
      }
    }
  }
  for (std::size_t g = 0; g < ndof; ++g) {
    if (d.kind[g] == 0) {
      d.free_index[g] = static_cast<std::ptrdiff_t>(d.free_dofs.size());
      d.free_dofs.push_back(g);
    }
  }
  return d;
}

namespace {

Vec3 minus(const Vec3& p, const Vec3& q) {
  return {p[0] - q[0], p[1] - q[1], p[2] - q[2]};
}

Vec3 cross(const Vec3& p, const Vec3& q) {
  return {p[1] * q[2] - p[2] * q[1], p[2] * q[0] - p[0] * q[2], p[0] * q[1] - p[1] * q[0]};
}

} // namespace

std::vector<std::size_t> rigid_motion_pins(const Model& m) {
  // A support may hold the body without constraints (a quadratic clamp extrapolates its
  // particles): the scene's supports decide.
  if (!m.spec.supports.empty() || !m.constraints.empty() || m.body_particle_count() < 3) {
    return {};
  }
  const int dim = m.spec.dimension.dim;
  // Body particles only: ghosts (extrapolated, after them) follow their sources.
  const std::vector<Vec3> x(m.particles.position.begin(),
                            m.particles.position.begin() +
                                static_cast<std::ptrdiff_t>(m.body_particle_count()));
  const auto dominant = [dim](const Vec3& v) {
    int k = 0;
    for (int a = 1; a < dim; ++a) {
      k = std::abs(v[a]) > std::abs(v[k]) ? a : k;
    }
    return static_cast<std::size_t>(k);
  };
  const auto farthest = [&](const auto& distance) {
    std::size_t best = 0;
    for (std::size_t i = 1; i < x.size(); ++i) {
      best = distance(x[i]) > distance(x[best]) ? i : best;
    }
    return best;
  };
  // A: the lexicographically smallest position, a corner of a box-shaped body.
  const std::size_t a =
      static_cast<std::size_t>(std::min_element(x.begin(), x.end(),
                                                [](const Vec3& p, const Vec3& q) {
                                                  return std::lexicographical_compare(
                                                      p.begin(), p.end(), q.begin(), q.end());
                                                }) -
                               x.begin());
  const std::size_t b =
      farthest([&](const Vec3& p) { return dot(minus(p, x[a]), minus(p, x[a])); });
  const Vec3 ab = minus(x[b], x[a]);
  std::vector<std::size_t> pins;
  for (std::size_t c = 0; c < static_cast<std::size_t>(dim); ++c) {
    pins.push_back(3 * a + c);
    if (c != dominant(ab)) {
      pins.push_back(3 * b + c);
    }
  }
  if (dim == 3) {
    const std::size_t c = farthest([&](const Vec3& p) {
      const Vec3 n = cross(ab, minus(p, x[a]));
      return dot(n, n);
    });
    pins.push_back(3 * c + dominant(cross(ab, minus(x[c], x[a]))));
  }
  return pins;
}

void pin_dofs(DofMap& d, const std::vector<std::size_t>& dofs) {
  for (const std::size_t g : dofs) {
    d.kind[g] = 1;
    d.prescribed[g] = 0.0;
  }
  d.free_dofs.clear();
  std::fill(d.free_index.begin(), d.free_index.end(), DofMap::none);
  for (std::size_t g = 0; g < d.kind.size(); ++g) {
    if (d.kind[g] == 0) {
      d.free_index[g] = static_cast<std::ptrdiff_t>(d.free_dofs.size());
      d.free_dofs.push_back(g);
    }
  }
}

namespace {

using Block = std::array<double, 9>; // row-major 3×3

/// One block of A or B between a particle and an unknown particle: a weight per component.
struct Coupling {
  std::uint32_t particle;
  std::array<double, 3> weight;
};

/// Per particle, its couplings (CSR).
struct Couplings {
  std::vector<std::size_t> offsets;
  std::vector<Coupling> entries;

  const Coupling* begin(std::size_t i) const { return entries.data() + offsets[i]; }
  const Coupling* end(std::size_t i) const { return entries.data() + offsets[i + 1]; }
};

/// Add weight w on component c of unknown particle q to a particle's list (terms that reach the
/// same particle twice are summed).
void add_weight(std::vector<Coupling>& list, std::size_t first, std::size_t q, std::size_t c,
                double w) {
  for (std::size_t k = first; k < list.size(); ++k) {
    if (list[k].particle == q) {
      list[k].weight[c] += w;
      return;
    }
  }
  Coupling x{static_cast<std::uint32_t>(q), {0, 0, 0}};
  x.weight[c] = w;
  list.push_back(x);
}

/// A (columns: how each particle moves with the unknowns) or, with `equations`, B (rows: where
/// each particle's equation goes, in force units) by particle.
Couplings couplings(const Model& m, const DofMap& d, bool equations) {
  Couplings out;
  out.offsets.reserve(m.size() + 1);
  out.offsets.push_back(0);
  for (std::size_t i = 0; i < m.size(); ++i) {
    const double scale = equations ? m.particles.volume[i] : 1.0;
    const std::size_t first = out.entries.size();
    for (std::size_t c = 0; c < 3; ++c) {
      const std::size_t g = 3 * i + c;
      if (d.kind[g] == 0) {
        add_weight(out.entries, first, i, c, scale);
      } else if (d.kind[g] == 2 && (!equations || d.folds_row[g])) {
        for (const DofMap::Term& t : d.terms[g]) {
          if (d.kind[t.dof] == 0) {
            add_weight(out.entries, first, t.dof / 3, c, scale * t.coefficient);
          }
        }
      }
    }
    out.offsets.push_back(out.entries.size());
  }
  return out;
}

/// For each unknown particle p, the particles whose equations B sends to p, with the weights.
Couplings transpose(const Couplings& b, std::size_t particles) {
  Couplings t;
  t.offsets.assign(particles + 1, 0);
  for (const Coupling& x : b.entries) {
    ++t.offsets[x.particle + 1];
  }
  for (std::size_t p = 0; p < particles; ++p) {
    t.offsets[p + 1] += t.offsets[p];
  }
  t.entries.resize(b.entries.size());
  std::vector<std::size_t> next(t.offsets.begin(), t.offsets.end() - 1);
  for (std::size_t i = 0; i < particles; ++i) {
    for (const Coupling* x = b.begin(i); x != b.end(i); ++x) {
      t.entries[next[x->particle]++] = {static_cast<std::uint32_t>(i), x->weight};
    }
  }
  return t;
}

/// The bonds that carry stiffness, per particle (CSR order), as their off-diagonal blocks
/// K_ij = −k_ij n⊗n, and each particle's diagonal block K_ii = Σ_j k_ij n⊗n.
struct Bonds {
  struct Bond {
    std::uint32_t neighbour;
    Block block;
  };
  std::vector<std::size_t> offsets;
  std::vector<Bond> bonds;
  std::vector<Block> diagonal;
};

Bonds stiff_bonds(const Model& m) {
  Bonds out;
  out.offsets.reserve(m.size() + 1);
  out.offsets.push_back(0);
  out.diagonal.assign(m.size(), Block{});
  for (std::size_t i = 0; i < m.size(); ++i) {
    Block& diag = out.diagonal[i];
    for_each_linearised_bond(m, i, BrokenBonds::left_out, [&](const LinearisedBond& b) {
      if (b.stiffness == 0.0) {
        return; // bonds between two dependants carry no energy (ghost_layers.hpp)
      }
      Bonds::Bond bond{static_cast<std::uint32_t>(b.neighbour), {}};
      for (std::size_t a = 0; a < 3; ++a) {
        for (std::size_t c = 0; c < 3; ++c) {
          const double knn = b.stiffness * b.direction[a] * b.direction[c];
          diag[3 * a + c] += knn;
          bond.block[3 * a + c] = -knn;
        }
      }
      out.bonds.push_back(bond);
    });
    out.offsets.push_back(out.bonds.size());
  }
  return out;
}

/// The rows of Bᵀ K A, one particle's block row at a time.
class RowAssembler {
public:
  RowAssembler(const Bonds& k, const Couplings& a, std::size_t particles)
      : k_(k), a_(a), block_(particles), mark_(particles, unmarked) {}

  /// Accumulate row p: Σ over (i, β) of users of p of diag(β) (K A)_i·; with `upper`, only the
  /// blocks of particles q ≥ p. The touched particles come back sorted.
  const std::vector<std::uint32_t>& row(std::size_t p, const Coupling* first, const Coupling* last,
                                        bool upper) {
    touched_.clear();
    for (const Coupling* user = first; user != last; ++user) {
      const std::size_t i = user->particle;
      add(k_.diagonal[i], a_.begin(i), a_.end(i), user->weight, p, upper);
      for (std::size_t q = k_.offsets[i]; q < k_.offsets[i + 1]; ++q) {
        const Bonds::Bond& b = k_.bonds[q];
        add(b.block, a_.begin(b.neighbour), a_.end(b.neighbour), user->weight, p, upper);
      }
    }
    std::sort(touched_.begin(), touched_.end());
    return touched_;
  }

  const Block& block(std::size_t q) const { return block_[q]; }

private:
  static constexpr std::uint32_t unmarked = std::numeric_limits<std::uint32_t>::max();

  /// block_q += diag(β) M diag(α_q) for every coupling (q, α) of the columns given.
  void add(const Block& m, const Coupling* first, const Coupling* last,
           const std::array<double, 3>& beta, std::size_t p, bool upper) {
    Block bm; // diag(β) M, the same for every column (a ghost's ~50)
    for (std::size_t r = 0; r < 3; ++r) {
      for (std::size_t c = 0; c < 3; ++c) {
        bm[3 * r + c] = beta[r] * m[3 * r + c];
      }
    }
    for (const Coupling* col = first; col != last; ++col) {
      const std::uint32_t q = col->particle;
      if (upper && q < p) {
        continue;
      }
      Block& out = block_[q];
      if (mark_[q] != p) {
        mark_[q] = static_cast<std::uint32_t>(p);
        out.fill(0.0);
        touched_.push_back(q);
      }
      for (std::size_t r = 0; r < 3; ++r) {
        for (std::size_t c = 0; c < 3; ++c) {
          out[3 * r + c] += bm[3 * r + c] * col->weight[c];
        }
      }
    }
  }

  const Bonds& k_;
  const Couplings& a_;
  std::vector<Block> block_;
  std::vector<std::uint32_t> mark_;
  std::vector<std::uint32_t> touched_;
};

/// u_p: the prescribed values, and what dependants take from prescribed sources.
std::vector<double> known_displacements(const DofMap& d) {
  std::vector<double> known(d.kind.size(), 0.0);
  for (std::size_t g = 0; g < d.kind.size(); ++g) {
    if (d.kind[g] == 1) {
      known[g] = d.prescribed[g];
    } else if (d.kind[g] == 2) {
      for (const DofMap::Term& t : d.terms[g]) {
        if (d.kind[t.dof] != 0) {
          known[g] += t.coefficient * d.prescribed[t.dof];
        }
      }
    }
  }
  return known;
}

/// b_ext − K u_p per particle and component (per unit volume).
std::vector<double> unbalanced_load(const Model& m, const Bonds& k, const DofMap& d) {
  const std::vector<double> known = known_displacements(d);
  std::vector<double> w(3 * m.size(), 0.0);
  const std::vector<double>& ext = m.external_force_density;
  for (std::size_t i = 0; i < m.size(); ++i) {
    for (std::size_t a = 0; a < 3; ++a) {
      double ku = 0;
      for (std::size_t c = 0; c < 3; ++c) {
        ku += k.diagonal[i][3 * a + c] * known[3 * i + c];
      }
      w[3 * i + a] = (ext.empty() ? 0.0 : ext[3 * i + a]) - ku;
    }
    for (std::size_t q = k.offsets[i]; q < k.offsets[i + 1]; ++q) {
      const Bonds::Bond& b = k.bonds[q];
      for (std::size_t a = 0; a < 3; ++a) {
        for (std::size_t c = 0; c < 3; ++c) {
          w[3 * i + a] -= b.block[3 * a + c] * known[3 * b.neighbour + c];
        }
      }
    }
  }
  return w;
}

} // namespace

StaticSystem assemble_reduced(const Model& m, const DofMap& d, RowPart part) {
  const Bonds k = stiff_bonds(m);
  const Couplings a = couplings(m, d, false);
  const Couplings users = transpose(couplings(m, d, true), m.size());
  const std::vector<double> w = unbalanced_load(m, k, d);
  const bool upper = part == RowPart::upper_half;

  StaticSystem s;
  s.unknowns = d.free_dofs;
  s.row_offsets.reserve(d.free_dofs.size() + 1);
  s.row_offsets.push_back(0);
  s.rhs.reserve(d.free_dofs.size());
  RowAssembler rows(k, a, m.size());
  for (std::size_t p = 0; p < m.size(); ++p) {
    if (users.begin(p) == users.end(p)) {
      continue; // no free component: no equation
    }
    const std::vector<std::uint32_t>& touched = rows.row(p, users.begin(p), users.end(p), upper);
    for (std::size_t r = 0; r < 3; ++r) {
      const std::ptrdiff_t row = d.free_index[3 * p + r];
      if (row == DofMap::none) {
        continue;
      }
      for (const std::uint32_t q : touched) {
        const Block& block = rows.block(q);
        for (std::size_t c = 0; c < 3; ++c) {
          const std::ptrdiff_t col = d.free_index[3 * q + c];
          const double v = block[3 * r + c];
          if (col == DofMap::none || (upper && col < row) || v == 0.0) {
            continue;
          }
          s.columns.push_back(static_cast<int>(col));
          s.values.push_back(v);
        }
      }
      s.row_offsets.push_back(static_cast<int>(s.columns.size()));
      double f = 0;
      for (const Coupling* user = users.begin(p); user != users.end(p); ++user) {
        f += user->weight[r] * w[3 * user->particle + r];
      }
      s.rhs.push_back(f);
    }
  }
  return s;
}

double bond_asymmetry(const Model& m) {
  // Each pair of bonds once (from its lower end), the reverse found by binary search in the
  // neighbour's sorted row; a bond without its reverse counts in full.
  const auto& volume = m.particles.volume;
  const BondFamily& f = m.family;
  auto stiffness = [&](std::size_t from, std::size_t k) {
    const bool broken = !m.state.broken.empty() && m.state.broken[k];
    return broken ? 0.0 : volume[from] * bond_stiffness(m, k) * f.inverse_length[k];
  };
  double diff = 0, norm = 0;
  for (std::size_t i = 0; i < m.size(); ++i) {
    for (std::size_t k = f.offsets[i]; k < f.offsets[i + 1]; ++k) {
      const std::size_t j = f.neighbour[k];
      const double vk = stiffness(i, k);
      norm += vk * vk;
      const auto row_begin = f.neighbour.begin() + static_cast<std::ptrdiff_t>(f.offsets[j]);
      const auto row_end = f.neighbour.begin() + static_cast<std::ptrdiff_t>(f.offsets[j + 1]);
      const auto back = std::lower_bound(row_begin, row_end, i);
      if (back == row_end || *back != i) {
        diff += 2 * vk * vk; // entries (i, j) and (j, i) of V K − (V K)ᵀ
      } else if (i < j) {
        const double vk_back = stiffness(j, static_cast<std::size_t>(back - f.neighbour.begin()));
        diff += 2 * (vk - vk_back) * (vk - vk_back);
      }
    }
  }
  return norm > 0 ? std::sqrt(diff / norm) : 0.0;
}

} // namespace pd
