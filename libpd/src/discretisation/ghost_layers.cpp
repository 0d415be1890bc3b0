#include "libpd/discretisation/ghost_layers.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <tuple>
#include <unordered_set>

namespace pd {

namespace {

using Site = std::array<long long, 3>;

struct SiteHash {
  std::size_t operator()(const Site& s) const {
    std::uint64_t h = 1469598103934665603ULL;
    for (long long v : s) {
      h = (h ^ static_cast<std::uint64_t>(v)) * 1099511628211ULL;
    }
    return static_cast<std::size_t>(h);
  }
};

double lattice_shift(const LatticeSpec& l) {
  return l.convention == LatticeConvention::cell_centered ? 0.5 : 0.0;
}

/// The lattice site a particle belongs to (its position rounded to the lattice).
Site site_of(const Vec3& x, int dim, const LatticeSpec& l) {
  Site s{0, 0, 0};
  for (std::size_t a = 0; a < static_cast<std::size_t>(dim); ++a) {
    s[a] = std::llround((x[a] - l.origin[a]) / l.spacing - lattice_shift(l));
  }
  return s;
}

/// Every lattice site whose centre lies in one of `mesh`'s simplices (on a face counts as in),
/// added to `sites`.
void sites_inside_simplices(int dim, const LatticeSpec& l, const PointCloud& mesh,
                            std::unordered_set<Site, SiteHash>& sites) {
  const auto d = static_cast<std::size_t>(dim);
  // Barycentric coordinates within round-off of the lattice count as inside, so that a site on a
  // face shared by two simplices is not lost to both.
  const double tolerance = 1e-9;
  for (std::size_t s = 0; s + d < mesh.simplex.size(); s += d + 1) {
    std::array<Vec3, 4> c{};
    std::array<long long, 3> first{0, 0, 0}, last{0, 0, 0};
    for (std::size_t k = 0; k <= d; ++k) {
      c[k] = mesh.corner[mesh.simplex[s + k]];
    }
    for (std::size_t a = 0; a < d; ++a) {
      double lo = c[0][a], hi = c[0][a];
      for (std::size_t k = 1; k <= d; ++k) {
        lo = std::min(lo, c[k][a]);
        hi = std::max(hi, c[k][a]);
      }
      std::tie(first[a], last[a]) = index_range(l, static_cast<int>(a), lo, hi);
    }
    // x = c0 + E b, b the barycentric coordinates of corners 1..d.
    Eigen::Matrix3d e = Eigen::Matrix3d::Identity();
    for (std::size_t k = 1; k <= d; ++k) {
      for (std::size_t a = 0; a < d; ++a) {
        e(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(k - 1)) = c[k][a] - c[0][a];
      }
    }
    const Eigen::Matrix3d inverse = e.inverse();
    Site site{0, 0, 0};
    for (site[2] = first[2]; site[2] <= last[2]; ++site[2]) {
      for (site[1] = first[1]; site[1] <= last[1]; ++site[1]) {
        for (site[0] = first[0]; site[0] <= last[0]; ++site[0]) {
          Eigen::Vector3d x = Eigen::Vector3d::Zero();
          for (std::size_t a = 0; a < d; ++a) {
            x(static_cast<Eigen::Index>(a)) =
                lattice_coordinate(l, static_cast<int>(a), site[a]) - c[0][a];
          }
          const Eigen::Vector3d b = inverse * x;
          double rest = 1;
          bool inside = true;
          for (std::size_t k = 0; k < d; ++k) {
            inside = inside && b(static_cast<Eigen::Index>(k)) >= -tolerance;
            rest -= b(static_cast<Eigen::Index>(k));
          }
          if (inside && rest >= -tolerance) {
            sites.insert(site);
          }
        }
      }
    }
  }
}

/// Quadratic basis around a dependant at p, restricted by the clamp planes it lies behind.
class Basis {
public:
  Basis(int dim, double spacing, const Vec3& p, std::vector<ClampPlane> behind,
        const std::vector<Vec3>& position, const std::vector<std::uint32_t>& sources)
      : dim_(static_cast<std::size_t>(dim)), spacing_(spacing), p_(p), behind_(std::move(behind)) {
    // Along which axes the sources vary enough for a linear (2 positions) or quadratic (3) term.
    std::array<std::size_t, 3> distinct{0, 0, 0};
    for (std::size_t a = 0; a < dim_; ++a) {
      std::vector<long long> values;
      for (std::uint32_t j : sources) {
        values.push_back(std::llround(4.0 * (position[j][a] - p_[a]) / spacing_));
      }
      std::sort(values.begin(), values.end());
      distinct[a] =
          static_cast<std::size_t>(std::unique(values.begin(), values.end()) - values.begin());
    }
    const int degree = 2 - static_cast<int>(behind_.size());
    terms_.push_back({-1, -1}); // the constant
    if (degree >= 1) {
      for (int a = 0; a < dim; ++a) {
        if (distinct[static_cast<std::size_t>(a)] >= 2) {
          terms_.push_back({a, -1});
        }
      }
    }
    if (degree >= 2) {
      for (int a = 0; a < dim; ++a) {
        for (int b = a; b < dim; ++b) {
          const std::size_t need_a = a == b ? 3 : 2;
          if (distinct[static_cast<std::size_t>(a)] >= need_a &&
              distinct[static_cast<std::size_t>(b)] >= 2) {
            terms_.push_back({a, b});
          }
        }
      }
    }
  }

  std::size_t size() const { return terms_.size(); }

  /// Every basis function at x.
  void evaluate(const Vec3& x, double* out) const {
    double factor = 1;
    for (const ClampPlane& c : behind_) {
      factor *= (x[static_cast<std::size_t>(c.axis)] - c.at) / spacing_;
    }
    for (std::size_t t = 0; t < terms_.size(); ++t) {
      double v = factor;
      for (int a : {terms_[t][0], terms_[t][1]}) {
        if (a >= 0) {
          v *= (x[static_cast<std::size_t>(a)] - p_[static_cast<std::size_t>(a)]) / spacing_;
        }
      }
      out[t] = v;
    }
  }

private:
  std::size_t dim_;
  double spacing_;
  Vec3 p_;
  std::vector<ClampPlane> behind_;
  std::vector<std::array<int, 2>> terms_; ///< axes of the monomial's factors, −1 for none
};

/// The minimum-norm weights a with Σ_j a_j f(x_j) = f(p) for every basis function f: the value
/// at p of the least-squares fit through the sources.
std::vector<double> fit_weights(const Basis& basis, const Vec3& p,
                                const std::vector<Vec3>& position,
                                const std::vector<std::uint32_t>& sources) {
  const auto k = static_cast<Eigen::Index>(basis.size());
  const auto m = static_cast<Eigen::Index>(sources.size());
  Eigen::MatrixXd P(m, k);
  std::vector<double> row(basis.size());
  for (Eigen::Index s = 0; s < m; ++s) {
    basis.evaluate(position[sources[static_cast<std::size_t>(s)]], row.data());
    for (Eigen::Index t = 0; t < k; ++t) {
      P(s, t) = row[static_cast<std::size_t>(t)];
    }
  }
  Eigen::VectorXd phi(k);
  basis.evaluate(p, row.data());
  for (Eigen::Index t = 0; t < k; ++t) {
    phi(t) = row[static_cast<std::size_t>(t)];
  }
  // Pᵀ a = φ, underdetermined (m ≥ k): the complete orthogonal decomposition gives the
  // minimum-norm solution, i.e. a = P (PᵀP)⁻¹ φ without forming PᵀP.
  const Eigen::MatrixXd Pt = P.transpose();
  const Eigen::VectorXd a = Pt.completeOrthogonalDecomposition().solve(phi);
  return {a.data(), a.data() + a.size()};
}

} // namespace

std::vector<Vec3> ghost_sites(int dim, const LatticeSpec& lattice, HorizonRule rule,
                              const std::vector<Vec3>& body,
                              const std::vector<const PointCloud*>& mesh_of_body,
                              const std::vector<std::uint16_t>& body_of) {
  std::unordered_set<Site, SiteHash> occupied;
  occupied.reserve(body.size());
  for (std::size_t i = 0; i < body.size(); ++i) {
    if (body_of.empty() || mesh_of_body.empty() || mesh_of_body[body_of[i]] == nullptr) {
      occupied.insert(site_of(body[i], dim, lattice));
    }
  }
  for (const PointCloud* mesh : mesh_of_body) {
    if (mesh != nullptr) {
      sites_inside_simplices(dim, lattice, *mesh, occupied);
    }
  }
  std::unordered_set<Site, SiteHash> ghosts;
  for (const Vec3& x : body) {
    const Site base = site_of(x, dim, lattice);
    for_each_offset_within(lattice.horizon_factor, dim, rule, [&](const Site& o) {
      const Site s{base[0] + o[0], base[1] + o[1], base[2] + o[2]};
      if (!occupied.contains(s)) {
        ghosts.insert(s);
      }
    });
  }
  std::vector<Site> sorted(ghosts.begin(), ghosts.end());
  std::sort(sorted.begin(), sorted.end(), [](const Site& a, const Site& b) {
    return std::tie(a[2], a[1], a[0]) < std::tie(b[2], b[1], b[0]);
  });
  std::vector<Vec3> out;
  out.reserve(sorted.size());
  const Vec3 unused_axes = body.empty() ? Vec3{0, 0, 0} : body.front();
  for (const Site& s : sorted) {
    Vec3 p = unused_axes;
    for (std::size_t a = 0; a < static_cast<std::size_t>(dim); ++a) {
      p[a] = lattice_coordinate(lattice, static_cast<int>(a), s[a]);
    }
    out.push_back(p);
  }
  return out;
}

ExtrapolatedParticles extrapolation_ties(int dim, double spacing, const std::vector<Vec3>& position,
                                         const BondFamily& family,
                                         const std::vector<std::uint8_t>& dependent,
                                         const std::vector<std::uint32_t>& fitted,
                                         const std::vector<ClampPlane>& planes,
                                         const std::vector<SymmetryPlane>& symmetry) {
  ExtrapolatedParticles ties;
  const double tolerance = 1e-6 * spacing;
  const double fit_radius = ghost_fit_radius * spacing;
  const auto free_family = [&](std::size_t i, std::vector<std::uint32_t>& out) {
    for (std::size_t k = family.offsets[i]; k < family.offsets[i + 1]; ++k) {
      if (!dependent[family.neighbour[k]]) {
        out.push_back(family.neighbour[k]);
      }
    }
  };
  std::vector<std::uint32_t> near;
  std::vector<std::uint32_t> sources;
  for (const std::uint32_t i : fitted) {
    ties.particle.push_back(i);
    const Vec3& p = position[i];
    std::vector<ClampPlane> behind;
    for (const ClampPlane& c : planes) {
      if (c.behind(p, tolerance)) {
        behind.push_back(c);
      }
    }
    near.clear();
    free_family(i, near);
    if (near.empty() || behind.size() >= 3) {
      ties.offsets.push_back(ties.source.size()); // out of reach, or held on three planes: zero
      continue;
    }
    // The nearest source (lowest index among equals, so the choice is reproducible).
    std::uint32_t nearest = near.front();
    double best = std::numeric_limits<double>::infinity();
    for (std::uint32_t j : near) {
      double d2 = 0;
      for (std::size_t a = 0; a < 3; ++a) {
        d2 += (position[j][a] - p[a]) * (position[j][a] - p[a]);
      }
      if (d2 < best - tolerance * tolerance ||
          (std::abs(d2 - best) <= tolerance * tolerance && j < nearest)) {
        best = std::min(best, d2);
        nearest = j;
      }
    }
    // The fit is local: the free particles within the fit radius of the nearest (all of its
    // family for a horizon shorter than that). The smaller the cloud, the fewer sources each
    // dependant couples and the less the static solver's factor fills in (√6 λ: about 3× fewer
    // than with δ at m = 2√3).
    sources.assign(1, nearest);
    for (std::size_t k = family.offsets[nearest]; k < family.offsets[nearest + 1]; ++k) {
      if (!dependent[family.neighbour[k]] &&
          family.inverse_length[k] * fit_radius * (1 + 1e-9) >= 1.0) {
        sources.push_back(family.neighbour[k]);
      }
    }
    std::sort(sources.begin(), sources.end());
    if (symmetry.empty()) {
      const Basis basis(dim, spacing, p, behind, position, sources);
      const std::vector<double> a = fit_weights(basis, p, position, sources);
      for (std::size_t s = 0; s < sources.size(); ++s) {
        if (a[s] != 0.0) {
          ties.source.push_back(sources[s]);
          ties.coefficient.push_back(a[s]);
          ties.negated.push_back(0);
        }
      }
      ties.offsets.push_back(ties.source.size());
      continue;
    }
    // The data: the sources, and their images across the symmetry planes (and across two of them,
    // a corner) that lie within the fit radius of the nearest source.
    std::vector<Vec3> data_position;
    std::vector<std::uint32_t> data_source;
    std::vector<std::uint8_t> data_negated;
    for (const std::uint32_t s : sources) {
      for (unsigned mask = 0; mask < (1U << symmetry.size()); ++mask) {
        Vec3 x = position[s];
        std::uint8_t negated = 0;
        bool distinct = true;
        for (std::size_t k = 0; k < symmetry.size(); ++k) {
          if (((mask >> k) & 1U) != 0) {
            const auto axis = static_cast<std::size_t>(symmetry[k].axis);
            distinct = distinct && std::abs(x[axis] - symmetry[k].at) > tolerance;
            x[axis] = 2 * symmetry[k].at - x[axis];
            negated = static_cast<std::uint8_t>(negated ^ (1U << axis));
          }
        }
        double d2 = 0;
        for (std::size_t a = 0; a < 3; ++a) {
          d2 += (x[a] - position[nearest][a]) * (x[a] - position[nearest][a]);
        }
        if (mask == 0 || (distinct && d2 <= fit_radius * fit_radius * (1 + 1e-9))) {
          data_position.push_back(x);
          data_source.push_back(s);
          data_negated.push_back(negated);
        }
      }
    }
    std::vector<std::uint32_t> data(data_position.size());
    for (std::size_t k = 0; k < data.size(); ++k) {
      data[k] = static_cast<std::uint32_t>(k);
    }
    const Basis basis(dim, spacing, p, behind, data_position, data);
    const std::vector<double> a = fit_weights(basis, p, data_position, data);
    for (std::size_t k = 0; k < data.size(); ++k) {
      if (a[k] != 0.0) {
        ties.source.push_back(data_source[k]);
        ties.coefficient.push_back(a[k]);
        ties.negated.push_back(data_negated[k]);
      }
    }
    ties.offsets.push_back(ties.source.size());
  }
  if (std::all_of(ties.negated.begin(), ties.negated.end(),
                  [](std::uint8_t n) { return n == 0; })) {
    ties.negated.clear();
  }
  return ties;
}

ExtrapolatedParticles refit_within(int dim, double spacing, const std::vector<Vec3>& position,
                                   const ExtrapolatedParticles& ties,
                                   const std::vector<ClampPlane>& planes,
                                   const std::vector<SymmetryPlane>& symmetry, double fit_radius) {
  const double tolerance = 1e-6 * spacing;
  const double reach2 = fit_radius * fit_radius * spacing * spacing * (1 + 1e-9);
  const auto distance2 = [](const Vec3& a, const Vec3& b) {
    double d2 = 0;
    for (std::size_t c = 0; c < 3; ++c) {
      d2 += (a[c] - b[c]) * (a[c] - b[c]);
    }
    return d2;
  };
  ExtrapolatedParticles out;
  std::vector<Vec3> datum;       // where each term's source is seen from (its symmetry image)
  std::vector<Vec3> kept;        // the data within the radius
  std::vector<std::size_t> term; // and their terms
  for (std::size_t d = 0; d < ties.size(); ++d) {
    const Vec3& p = position[ties.particle[d]];
    out.particle.push_back(ties.particle[d]);
    datum.clear();
    std::size_t nearest = ties.offsets[d];
    for (std::size_t t = ties.offsets[d]; t < ties.offsets[d + 1]; ++t) {
      Vec3 x = position[ties.source[t]];
      for (const SymmetryPlane& s : symmetry) {
        const auto axis = static_cast<std::size_t>(s.axis);
        if (ties.sign(t, axis) < 0) {
          x[axis] = 2 * s.at - x[axis];
        }
      }
      datum.push_back(x);
      if (distance2(x, p) <
          distance2(datum[nearest - ties.offsets[d]], p) - tolerance * tolerance) {
        nearest = t;
      }
    }
    kept.clear();
    term.clear();
    for (std::size_t t = ties.offsets[d]; t < ties.offsets[d + 1]; ++t) {
      const Vec3& x = datum[t - ties.offsets[d]];
      if (distance2(x, datum[nearest - ties.offsets[d]]) <= reach2) {
        kept.push_back(x);
        term.push_back(t);
      }
    }
    std::vector<ClampPlane> behind;
    for (const ClampPlane& c : planes) {
      if (c.behind(p, tolerance)) {
        behind.push_back(c);
      }
    }
    std::vector<std::uint32_t> data(kept.size());
    for (std::size_t k = 0; k < data.size(); ++k) {
      data[k] = static_cast<std::uint32_t>(k);
    }
    if (!data.empty()) {
      const Basis basis(dim, spacing, p, behind, kept, data);
      const std::vector<double> a = fit_weights(basis, p, kept, data);
      for (std::size_t k = 0; k < data.size(); ++k) {
        if (a[k] != 0.0) {
          out.source.push_back(ties.source[term[k]]);
          out.coefficient.push_back(a[k]);
          out.negated.push_back(ties.negated.empty() ? 0 : ties.negated[term[k]]);
        }
      }
    }
    out.offsets.push_back(out.source.size());
  }
  if (ties.negated.empty()) {
    out.negated.clear();
  }
  return out;
}

} // namespace pd
