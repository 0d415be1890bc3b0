// lattice_toughness_ratio (declared in model.hpp; a file of its own for the layout's size limit).
// The toughness of the discrete model: the stress intensity at which a straight crack runs through
// the lattice, over the K_Ic = √(E' G0) that the energy-derived critical stretch aims at.
//
// Why s0 from G0 alone is not enough: eq. 11 (and its 2D forms) makes the energy stored at s0 in
// the bonds crossing a unit area equal G0. A crack in a lattice of brittle bonds does not grow at
// that energy release rate: when the tip bond snaps, the bonds it leaves behind are loaded beyond
// what a smooth crack front would give them, and the next bond (often a diagonal reaching back
// over the broken column) needs a larger K than the first one did. This is lattice trapping
// (Thomson, Hsieh & Rana 1971): the crack runs only once K passes the largest value over one
// lattice period, so the discrete model is tougher than G0 says, by a factor that depends on the
// bond weights and the horizon in spacings m, not on λ. At the default m = 2√3 it is 1.141
// over the energy-derived s0 with the `gradient` weights (stiffness on the bonds up to two
// spacings), 1.141 without volume weights and 1.157 with `moment` (a crack held to one row would
// need 1.162, 1.275 and 1.257); it does not fall under δ-refinement at fixed m, so a failure load
// converged in δ stayed 27–58 % above Griffith's (issue 36).
//
// The factor is measured, for the model's own lattice and corrections, on the boundary-layer
// problem of fracture mechanics: a square of half-width R = 10δ around a crack tip that lies on a
// cell face between two rows, the outer band (δ + λ wide) held at the mode-I displacement field of
// LEFM for K = K_Ic, re-centred on the current tip after every break. Bonds break one at a time,
// the most over-stretched first, any bond within a horizon of the crack line, not only those that
// cross it: the lattice's crack then zig-zags between neighbouring rows where that is easier, as it
// does in a specimen, and runs at about 2 % less K than one held to a straight line (sequentially
// linear: each break is followed by a new equilibrium;
// breaks are rank-one changes of the stiffness, solved with the Woodbury identity on one
// factorisation), and the factor is the largest load multiplier a break needs once the tip has
// moved past the first lattice periods (the crack's steady state). Dividing the energy-derived s0
// by it makes the model's crack run at K_Ic under a pure K field. Specimens add their own T-stress
// and, at a/δ of a few, more: a centre-cracked plate pulled one way fails within 5 % of LEFM, the
// same plate pulled both ways (T = 0) 7–8 % low, a double cantilever beam 10–16 % low (verify
// cases fracture-stop*, dcb*; open, issue 36).
// The energy stored in the crossing bonds at this s0 is then G0 / factor²: the rest of G0 is what
// each snapping bond releases into its neighbours (dissipated dynamically or by the static
// solver's break events), which a global energy balance counts and a sum over bonds does not.
//
// Every particle of the square holds the bonds of a bulk particle of the user's model (its
// stencil, read off the centre of a small model built with the user's weights and corrections):
// the square stands for an unbounded body, so no surface treatment acts in it.
//
// Scope: two and three dimensions. In 3D the tip is a straight front along z in plane strain,
// the 2D square's particles are columns of the cubic lattice, and each bond of the 3D stencil
// joins two columns, stretched by the in-plane part of its direction; the front breaks uniformly
// along z (a bond breaks in every layer at once). Plane stress and plane strain give the same 2D
// factor; the computation is scale-free, so it depends only on the dimension, m, the horizon rule
// and the corrections. It is cached per configuration; a computation takes about a second in 2D
// and a few in 3D. In 1D there is no crack tip (lattice_toughness_ratio returns nullopt).
#include "libpd/discretisation/model.hpp"

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <numbers>
#include <stdexcept>
#include <tuple>
#include <utility>
#include <vector>

namespace pd {

namespace {

/// Half-width of the square around the tip, in horizons; the factor moves by 0.4 % between 8 and
/// 14 horizons with the default weights.
constexpr double half_width_in_horizons = 10;
/// The factor is the largest multiplier over the tip's third to sixth lattice periods: from the
/// second on the breaks repeat with a period of one or two cells (a zig-zag between two rows),
/// which four periods cover. The first period needs 0.4–3 % less with the weightings here: the
/// pre-crack keeps the bonds that reach past its front (bond_cuts.cpp), as the grown crack does;
/// cutting them too made it 4–13 % less.
constexpr int periods = 6;
constexpr int steady_from = 2;
/// A stiffness added to K's diagonal, relative to its mean diagonal, so that a particle cut free
/// from both faces by the breaks keeps K (and the Woodbury system) regular; it moves no stretch
/// of a connected bond by more than round-off.
constexpr double regularisation = 1e-12;
/// Breaks carried by the Woodbury identity before K is assembled and factorised again.
constexpr std::size_t refactor_every = 256;

struct Pair {
  std::uint32_t i = 0, j = 0;
  double stiffness = 0; ///< ½(V_i C_ij + V_j C_ji) / |ξ|: the pair's K entry per unit n nᵀ
  Vec3 n{0, 0, 0};      ///< unit bond vector i → j
  double length = 0;
};

/// Mode-I displacement of LEFM at (x, y) from the tip, for K, shear modulus μ and Kolosov κ.
std::array<double, 2> mode_one(double x, double y, double k, double mu, double kappa) {
  const double r = std::hypot(x, y);
  const double theta = std::atan2(y, x);
  const double f = k / (2 * mu) * std::sqrt(r / (2 * std::numbers::pi));
  const double s = std::sin(theta / 2), c = std::cos(theta / 2);
  return {f * c * (kappa - 1 + 2 * s * s), f * s * (kappa + 1 - 2 * c * c)};
}

/// A square (2D) or cube (3D) of half-width `half` centred on the origin in the user's lattice
/// (m, rule) and corrections, at λ = 1 and E = 1 (the ratio is scale-free).
ModelSpec calibration_spec(const ModelSpec& user, double half) {
  ModelSpec spec;
  spec.dimension.dim = user.dimension.dim;
  spec.dimension.plane = user.dimension.plane;
  spec.dimension.thickness = 1;
  spec.lattice.spacing = 1;
  spec.lattice.horizon_factor = user.lattice.horizon_factor;
  spec.horizon_rule = user.horizon_rule;
  spec.surface_correction = user.surface_correction;
  spec.volume_correction = user.volume_correction;
  spec.mirror_coupling = user.mirror_coupling;
  Material m;
  m.name = "calibration";
  m.youngs_modulus = 1;
  m.density = 1;
  spec.materials = {m};
  BodySpec body;
  body.name = "calibration";
  const double z = spec.dimension.dim == 3 ? half : 0;
  body.region = Region{{Box{{-half, -half, -z}, {half, half, z}}}};
  spec.bodies = {body};
  return spec;
}

/// One bond of a bulk particle: its lattice offset and its pair stiffness per unit stretch,
/// ½(V_i C_ij + V_j C_ji) (the kernel's force on i per unit stretch is V_i C_ij; the mean of the
/// two directions keeps K symmetric where a correction is not).
struct StencilBond {
  Vec3 offset;
  double stiffness = 0;
};

/// The bonds of the particle at the centre of a cube (square in 2D) large enough that its family
/// and its neighbours' families lie inside: what every particle away from surfaces and cracks
/// holds, with the user's weights and corrections as build_model makes them. (A surface treatment
/// that scales a bond by both ends' factors must not see the cube's surface from the centre's
/// neighbours, hence two horizons.)
std::vector<StencilBond> bulk_stencil(const ModelSpec& user) {
  const double half = 2 * std::ceil(user.lattice.horizon_factor) + 1.5; // particles at integers
  const Model model = build_model(calibration_spec(user, half));
  const auto& x = model.particles.position;
  const auto& fam = model.family;
  std::size_t centre = 0;
  for (std::size_t p = 1; p < model.body_particle_count(); ++p) {
    if (norm(x[p]) < norm(x[centre])) {
      centre = p;
    }
  }
  const std::vector<std::size_t> reverse = reverse_bond_index(fam);
  const auto stiffness = [&](std::size_t k) { return bond_stiffness(model, k); };
  std::vector<StencilBond> stencil;
  for (std::size_t k = fam.offsets[centre]; k < fam.offsets[centre + 1]; ++k) {
    const std::uint32_t j = fam.neighbour[k];
    if (stiffness(k) == 0) {
      continue;
    }
    const Vec3 o{std::round(x[j][0] - x[centre][0]), std::round(x[j][1] - x[centre][1]),
                 std::round(x[j][2] - x[centre][2])};
    stencil.push_back({o, 0.5 * (model.particles.volume[centre] * stiffness(k) +
                                 model.particles.volume[j] * stiffness(reverse[k]))});
  }
  return stencil;
}

/// The boundary-layer problem's particles (λ = 1) and pairs, each pair once.
struct Layer {
  std::vector<Vec3> position;
  std::vector<Pair> pairs;
};

/// The square of half-width r_box (an integer) around a tip at the origin, the crack along y = 0
/// behind it, one particle per cell, every particle holding the bulk stencil. In 3D each particle
/// stands for a column along z of a front that is straight and plane-strained (u_z = 0): a bond
/// to another layer joins the two columns, stretched by the in-plane part of its direction. A
/// bond is cut if it crosses y = 0 and both ends lie over the crack (x < 0), the pre-crack rule
/// of bond_cuts.cpp. Stencil bonds that stay in their column never stretch and are left out.
Layer stencil_layer(const std::vector<StencilBond>& stencil, double r_box) {
  const auto n = static_cast<long long>(r_box);
  const long long side = 2 * n;
  Layer layer;
  for (long long b = 0; b < side; ++b) {
    for (long long a = 0; a < side; ++a) {
      layer.position.push_back(
          {static_cast<double>(a - n) + 0.5, static_cast<double>(b - n) + 0.5, 0});
    }
  }
  for (long long b = 0; b < side; ++b) {
    for (long long a = 0; a < side; ++a) {
      const auto i = static_cast<std::uint32_t>(b * side + a);
      for (const StencilBond& s : stencil) {
        const auto ox = static_cast<long long>(s.offset[0]);
        const auto oy = static_cast<long long>(s.offset[1]);
        if (ox < 0 || (ox == 0 && oy <= 0)) {
          continue; // the other end holds it, or it stays in its column
        }
        if (a + ox >= side || b + oy < 0 || b + oy >= side) {
          continue;
        }
        const auto j = static_cast<std::uint32_t>((b + oy) * side + a + ox);
        const Vec3& xi = layer.position[i];
        const Vec3& xj = layer.position[j];
        if (xi[1] * xj[1] < 0 && xi[0] < 0 && xj[0] < 0) {
          continue;
        }
        const double length = norm(s.offset);
        layer.pairs.push_back({i,
                               j,
                               s.stiffness / length,
                               {s.offset[0] / length, s.offset[1] / length, s.offset[2] / length},
                               length});
      }
    }
  }
  return layer;
}

/// The boundary-layer problem: unknowns inside the band, the band held at the K field of a tip at
/// `tip` (re-centred by the caller), pairs broken one at a time. A break is a rank-one change of
/// K: K_n = K0 − V D Vᵀ is solved with the Woodbury identity on K0's factor, and K is assembled
/// and factorised again every `refactor_every` breaks.
class BoundaryLayer {
public:
  BoundaryLayer(Layer layer, double inner_half_width, double horizon)
      : position_(std::move(layer.position)), crack_zone_half_width_(horizon) {
    unknown_.assign(position_.size(), -1);
    for (std::size_t p = 0; p < position_.size(); ++p) {
      if (std::max(std::abs(position_[p][0]), std::abs(position_[p][1])) < inner_half_width) {
        unknown_[p] = n_free_++;
      }
    }
    for (const Pair& b : layer.pairs) {
      if (unknown_[b.i] >= 0 || unknown_[b.j] >= 0) {
        pairs_.push_back(b); // only pairs that touch an unknown enter K
      }
    }
    broken_.assign(pairs_.size(), 0);
    for (std::size_t q = 0; q < pairs_.size(); ++q) {
      const Pair& b = pairs_[q];
      if (unknown_[b.i] >= 0 && unknown_[b.j] >= 0 &&
          std::abs(position_[b.i][1] + position_[b.j][1]) < 2 * crack_zone_half_width_) {
        breakable_.push_back(q);
      }
    }
    refactor();
  }

  /// The tip: the cell face behind the farthest particle that a break has reached (0 before any).
  double tip() const {
    const auto& x = position_;
    double farthest = 0;
    for (const std::size_t q : breakable_) {
      if (broken_[q]) {
        farthest = std::max({farthest, x[pairs_[q].i][0], x[pairs_[q].j][0]});
      }
    }
    return std::floor(farthest);
  }

  /// Equilibrium with the band at the K field (K, μ, κ) of a tip at `tip`.
  Eigen::VectorXd solve(double tip, double k, double mu, double kappa) {
    if (tip != solved_tip_ || solved_generation_ != generation_) {
      const auto& x = position_;
      Eigen::VectorXd f = Eigen::VectorXd::Zero(size());
      for (const auto& [row, p, comp, value] : kfp_) {
        const auto u = mode_one(x[p][0] - tip, x[p][1], k, mu, kappa);
        f[row] -= value * u[static_cast<std::size_t>(comp)];
      }
      unbroken_ = factor_.solve(f);
      solved_tip_ = tip;
      solved_generation_ = generation_;
    }
    Eigen::VectorXd u = unbroken_;
    const auto n = static_cast<Eigen::Index>(v_.size());
    if (n > 0) {
      Eigen::MatrixXd s(n, n);
      Eigen::VectorXd w(n);
      for (Eigen::Index a = 0; a < n; ++a) {
        w[a] = v_[static_cast<std::size_t>(a)].dot(u);
        for (Eigen::Index c = 0; c < n; ++c) {
          s(a, c) = (a == c ? 1 / d_[static_cast<std::size_t>(a)] : 0.0) -
                    v_[static_cast<std::size_t>(a)].dot(z_[static_cast<std::size_t>(c)]);
        }
      }
      const Eigen::VectorXd y = s.partialPivLu().solve(w);
      for (Eigen::Index c = 0; c < n; ++c) {
        u += y[c] * z_[static_cast<std::size_t>(c)];
      }
    }
    return u;
  }

  /// The unbroken breakable pair with the largest stretch in `u`, and that stretch.
  std::pair<std::size_t, double> most_stretched(const Eigen::VectorXd& u) const {
    double largest = 0;
    std::size_t which = 0;
    for (const std::size_t q : breakable_) {
      if (broken_[q]) {
        continue;
      }
      const Pair& b = pairs_[q];
      const auto ui = 2 * static_cast<Eigen::Index>(unknown_[b.i]);
      const auto uj = 2 * static_cast<Eigen::Index>(unknown_[b.j]);
      const double stretch =
          (b.n[0] * (u[uj] - u[ui]) + b.n[1] * (u[uj + 1] - u[ui + 1])) / b.length;
      if (stretch > largest) {
        largest = stretch;
        which = q;
      }
    }
    return {which, largest};
  }

  void break_pair(std::size_t q) {
    broken_[q] = 1;
    if (v_.size() + 1 >= refactor_every) {
      refactor();
      return;
    }
    const Pair& b = pairs_[q];
    const Eigen::Index i = 2 * unknown_[b.i], j = 2 * unknown_[b.j];
    v_.push_back({{i, i + 1, j, j + 1}, {-b.n[0], -b.n[1], b.n[0], b.n[1]}});
    Eigen::VectorXd dense = Eigen::VectorXd::Zero(size());
    for (std::size_t e = 0; e < 4; ++e) {
      dense[v_.back().index[e]] = v_.back().value[e];
    }
    z_.push_back(factor_.solve(dense));
    d_.push_back(b.stiffness);
  }

private:
  /// A broken pair's column of V: −n at i, +n at j (four entries).
  struct PairVector {
    std::array<Eigen::Index, 4> index;
    std::array<double, 4> value;
    double dot(const Eigen::VectorXd& a) const {
      return value[0] * a[index[0]] + value[1] * a[index[1]] + value[2] * a[index[2]] +
             value[3] * a[index[3]];
    }
  };

  Eigen::Index size() const { return 2 * static_cast<Eigen::Index>(n_free_); }

  /// K on the unknowns without the broken pairs, and its coupling to the band (V-scaled rows).
  void refactor() {
    std::vector<Eigen::Triplet<double>> kff;
    kfp_.clear();
    for (std::size_t q = 0; q < pairs_.size(); ++q) {
      if (broken_[q]) {
        continue;
      }
      const Pair& b = pairs_[q];
      const std::array<double, 4> v{-b.n[0], -b.n[1], b.n[0], b.n[1]};
      const std::array<std::uint32_t, 4> particle{b.i, b.i, b.j, b.j};
      for (std::size_t r = 0; r < 4; ++r) {
        const int ur = unknown_[particle[r]];
        for (std::size_t c = 0; ur >= 0 && c < 4; ++c) {
          const double value = b.stiffness * v[r] * v[c];
          const int row = 2 * ur + static_cast<int>(r % 2);
          if (const int uc = unknown_[particle[c]]; uc >= 0) {
            kff.emplace_back(row, 2 * uc + static_cast<int>(c % 2), value);
          } else {
            kfp_.emplace_back(row, particle[c], static_cast<int>(c % 2), value);
          }
        }
      }
    }
    Eigen::SparseMatrix<double> k(size(), size());
    k.setFromTriplets(kff.begin(), kff.end());
    const double shift = regularisation * k.diagonal().mean();
    for (Eigen::Index r = 0; r < size(); ++r) {
      k.coeffRef(r, r) += shift;
    }
    factor_.compute(k);
    if (factor_.info() != Eigen::Success) {
      throw std::runtime_error("lattice toughness: the boundary-layer stiffness is singular");
    }
    v_.clear();
    z_.clear();
    d_.clear();
    ++generation_;
  }

  std::vector<Vec3> position_;
  double crack_zone_half_width_; ///< δ: pairs whose midpoint is nearer y = 0 may break
  std::vector<int> unknown_;
  int n_free_ = 0;
  std::vector<Pair> pairs_;
  std::vector<std::size_t> breakable_; // pairs whose midpoint lies within a horizon of y = 0
  std::vector<std::uint8_t> broken_;
  std::vector<std::tuple<int, std::uint32_t, int, double>> kfp_; // row, band particle, comp, K
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> factor_;
  std::vector<PairVector> v_;
  std::vector<Eigen::VectorXd> z_; // K0⁻¹ V
  std::vector<double> d_;
  Eigen::VectorXd unbroken_;
  double solved_tip_ = std::numeric_limits<double>::quiet_NaN();
  int generation_ = 0, solved_generation_ = -1;
};

/// The ratio for a lattice whose bulk particles hold `stencil`, in `user_dimension` (its plane
/// mode in 2D; a 3D front is plane-strained), at m = `delta` spacings.
double ratio_of_stencil(const std::vector<StencilBond>& stencil,
                        const ModelDimension& user_dimension, double delta) {
  const double r_box = std::ceil(half_width_in_horizons * delta);
  BoundaryLayer layer(stencil_layer(stencil, r_box), r_box - (std::ceil(delta) + 1), delta);
  ModelDimension dimension = user_dimension;
  if (dimension.dim == 3) {
    dimension.plane = PlaneMode::plane_strain; // the front's columns do not move along z
  }
  const double nu = *bond_based_poisson_ratio(user_dimension);
  const bool plane_strain = dimension.plane == PlaneMode::plane_strain;
  const double g0 = 1;
  const double k_ic = std::sqrt((plane_strain ? 1 / (1 - nu * nu) : 1.0) * g0);
  const double mu = 1 / (2 * (1 + nu));
  const double kappa = plane_strain ? 3 - 4 * nu : (3 - nu) / (1 + nu);
  const double s0 = critical_stretch_from_fracture_energy(user_dimension, 1, delta, g0);

  std::vector<double> largest(periods, 0.0);
  for (;;) {
    const double tip = layer.tip();
    const auto period = static_cast<std::size_t>(std::max(0.0, tip));
    if (period >= largest.size()) {
      break;
    }
    const auto [pair, stretch] = layer.most_stretched(layer.solve(tip, k_ic, mu, kappa));
    if (stretch <= 0) {
      throw std::logic_error("lattice toughness: no crossing bond is stretched");
    }
    largest[period] = std::max(largest[period], s0 / stretch);
    layer.break_pair(pair);
  }
  return *std::max_element(largest.begin() + steady_from, largest.end());
}

} // namespace

double lattice_toughness_ratio_in(const ModelSpec& user) {
  if (user.dimension.dim != 2 && user.dimension.dim != 3) {
    throw std::logic_error("lattice_toughness_ratio_in: 2D and 3D only");
  }
  return ratio_of_stencil(bulk_stencil(user), user.dimension, user.lattice.horizon_factor);
}

std::optional<double> lattice_toughness_ratio(const ModelSpec& spec) {
  if (spec.dimension.dim == 1) {
    return std::nullopt; // no crack tip
  }
  // In 2D plane stress whatever the scene's plane: the factor is the same in plane strain (a unit
  // test holds them to 1e-3), and one computation per lattice keeps the cache independent of
  // order. In 3D the front is plane-strained whatever the plane says.
  ModelSpec plane_stress = spec;
  plane_stress.dimension.plane = PlaneMode::plane_stress;
  // What calibration_spec takes from the scene: a model built again with the same settings finds
  // its ratio without building the stencil's cube again.
  using Settings = std::tuple<int, double, int, int, int, int>;
  const Settings settings{spec.dimension.dim,
                          spec.lattice.horizon_factor,
                          static_cast<int>(spec.horizon_rule),
                          static_cast<int>(spec.surface_correction),
                          static_cast<int>(spec.volume_correction),
                          static_cast<int>(spec.mirror_coupling)};
  static std::mutex mutex;
  static std::map<Settings, double> by_settings;
  static std::map<std::vector<double>, double> by_stencil;
  {
    const std::lock_guard lock(mutex);
    if (const auto found = by_settings.find(settings); found != by_settings.end()) {
      return found->second;
    }
  }
  // The ratio is a function of the bulk stencil alone, so configurations that differ only where
  // the square has no particles (the surface treatments) share one computation; stiffnesses
  // enter the key to 12 digits, as some treatments reach the bulk value only to round-off.
  const std::vector<StencilBond> stencil = bulk_stencil(plane_stress);
  double stiffest = 0;
  for (const StencilBond& b : stencil) {
    stiffest = std::max(stiffest, b.stiffness);
  }
  std::vector<double> key{static_cast<double>(spec.dimension.dim), spec.lattice.horizon_factor};
  for (const StencilBond& b : stencil) {
    key.insert(key.end(),
               {b.offset[0], b.offset[1], b.offset[2], std::round(1e12 * b.stiffness / stiffest)});
  }
  {
    const std::lock_guard lock(mutex);
    if (const auto found = by_stencil.find(key); found != by_stencil.end()) {
      by_settings.emplace(settings, found->second);
      return found->second;
    }
  }
  const double ratio =
      ratio_of_stencil(stencil, plane_stress.dimension, spec.lattice.horizon_factor);
  const std::lock_guard lock(mutex);
  by_stencil.emplace(std::move(key), ratio);
  by_settings.emplace(settings, ratio);
  return ratio;
}

} // namespace pd
