// patch-test: uniform strain imposed as a displacement field on a block; each particle's PD
// strain-energy density is compared with the classical one, for every surface correction × volume
// correction and two horizons (the scene's δ/λ and 2√3).
//
//   PD:        W_i = ½ Σ_j w_ij V_j, computed from the model's per-bond stiffness k_ij = c V_j f_ij
//              (all corrections folded in) as ½ Σ_j k_ij·(w/c)(r², 1/|ξ|), with w/c the stretch
//              measure's bond energy (stretch.hpp).
//   classical: W = ½ ε:C:ε with the bond-based ν = 1/4 (3D): λ_L = μ = 2E/5, so
//              uniaxial strain ε along an axis: W = ½(λ_L + 2μ)ε² = (3/5)Eε²,
//              simple shear γ_xy = γ:           W = ½ μ γ² = (1/5)Eγ²,
//              uniaxial stress along x:         W = ½ E ε².
// Particles are classed by their distances to the six faces of the block: interior (farther than
// δ from every face), face (outer layer of one face, farther than δ from the others), edge (outer
// layer of two faces) and corner (outer layer of three faces).
//
// Gate (quadrature consistency, issue 4), for every load and horizon, surface correction none:
//  * the volume corrections whose weights are built to reproduce the continuum's fourth moments
//    (`moment`, and `gradient`, the library default) give a mean interior ratio of 1;
//  * `exact` gives the ratio its definition implies: the bulk lattice sum of the exact cell
//    fractions over the family |ξ| ≤ δ, computed here independently of the model;
// both within 1e-5 (the O(ε) of the exact stretch's nonlinearity at ε = 1e-6; measured 3e-7).
// `exact` is not held to 1: it weights each neighbour in the family by the part of its cell inside
// the horizon, but the family stops at |ξ| ≤ δ (bond_family.hpp), so the parts of the cells whose
// centres lie beyond δ are missing (at δ = 3.015λ the family holds 0.898 of the ball and the
// uniaxial ratio is 0.839; at 2√3 λ 0.912 and 0.907), and even with every cut cell one-point
// quadrature of |ξ|n_x⁴ over the cells is +2.3 % (1.017 at 2√3). Both sums are in the case's JSON.
#include "libpd/discretisation/corrections.hpp"
#include "libpd/discretisation/model.hpp"
#include "libpd/io/scene.hpp"
#include "libpd/physics/stretch.hpp"
#include "verification.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <fmt/format.h>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

namespace pd::verification {

namespace {

constexpr double strain = 1e-6; // any small value: the ratios are those of the linearised energy

enum class LoadKind { uniaxial_strain, shear, uniaxial_stress };

struct Load {
  const char* name;
  std::array<std::array<double, 3>, 3> gradient; ///< u = ε·gradient·x
  double classical;                              ///< W / (E ε²) with ν = 1/4
  LoadKind kind;
  /// Part of the quadrature gate (stress-x also depends on the lattice's ν).
  bool gated() const { return kind != LoadKind::uniaxial_stress; }
};
// Uniaxial strain (W = ½(λ_L + 2μ)ε²), simple shear γ_xy (½μγ²) and uniaxial stress along x
// (u = ε(x, −νy, −νz), ½Eε²: the load a free surface parallel to x sees, what `tensor` restores).
constexpr std::array<Load, 5> loads{
    {{"tension-x", {{{1, 0, 0}, {0, 0, 0}, {0, 0, 0}}}, 0.6, LoadKind::uniaxial_strain},
     {"tension-y", {{{0, 0, 0}, {0, 1, 0}, {0, 0, 0}}}, 0.6, LoadKind::uniaxial_strain},
     {"tension-z", {{{0, 0, 0}, {0, 0, 0}, {0, 0, 1}}}, 0.6, LoadKind::uniaxial_strain},
     {"shear-xy", {{{0, 1, 0}, {0, 0, 0}, {0, 0, 0}}}, 0.2, LoadKind::shear},
     {"stress-x", {{{1, 0, 0}, {0, -0.25, 0}, {0, 0, -0.25}}}, 0.5, LoadKind::uniaxial_stress}}};

const auto surface_names = surface_correction_names();
const auto volume_names = volume_correction_names();
const std::array<const char*, 4> class_names{"interior", "face", "edge", "corner"};

template <class Stretch>
std::vector<double> energy_density(const Model& m, const std::vector<Vec3>& y) {
  std::vector<double> w(m.size(), 0.0);
  for (std::size_t i = 0; i < m.size(); ++i) {
    double sum = 0;
    for (std::size_t k = m.family.offsets[i]; k < m.family.offsets[i + 1]; ++k) {
      const std::size_t j = m.family.neighbour[k];
      const double d0 = y[j][0] - y[i][0], d1 = y[j][1] - y[i][1], d2 = y[j][2] - y[i][2];
      sum += bond_stiffness(m, k) *
             Stretch::bond_energy(d0 * d0 + d1 * d1 + d2 * d2, m.family.inverse_length[k]);
    }
    w[i] = 0.5 * sum;
  }
  return w;
}

std::vector<double> energy_density(const Model& m, const std::vector<Vec3>& y) {
  switch (m.effects.stretch) {
  case StretchKind::modified:
    return energy_density<ModifiedStretch>(m, y);
  case StretchKind::fast:
    return energy_density<FastStretch>(m, y);
  case StretchKind::exact:
    break;
  }
  return energy_density<ExactStretch>(m, y);
}

/// -1 unclassified, else an index into class_names.
std::vector<int> classify(const ParticleSet& p, const Box& box, double spacing, double horizon) {
  std::vector<int> out(p.size(), -1);
  for (std::size_t i = 0; i < p.size(); ++i) {
    int outer = 0, far = 0;
    for (std::size_t a = 0; a < 3; ++a) {
      const double d = std::min(p.position[i][a] - box.lo[a], box.hi[a] - p.position[i][a]);
      outer += d < spacing ? 1 : 0;
      far += d > horizon ? 1 : 0;
    }
    if (outer + far == 3) {
      out[i] = outer;
    }
  }
  return out;
}

struct Stats {
  double mean = 0, min = std::numeric_limits<double>::infinity(),
         max = -std::numeric_limits<double>::infinity();
  std::size_t count = 0;
};

Json to_json(const Stats& s) {
  Json j;
  j["mean"] = s.mean;
  j["min"] = s.min;
  j["max"] = s.max;
  j["particles"] = s.count;
  return j;
}

/// Bulk lattice sums of the exact fractions: family volume / ball volume and the energy ratios
/// Σ f w(n) |ξ| V / ∫ w(n) |ξ| dV of a uniaxial strain along x (w = n_x⁴, continuum πδ⁴/5) and a
/// simple shear in xy (w = n_x²n_y², continuum πδ⁴/15: the sphere's mean of n_x²n_y² is 1/15), for
/// the family |ξ| ≤ δ and for every cut cell; `none` is the family with f = 1.
struct BulkSums {
  double ball = 0, vol_all = 0, vol_family = 0;
  double uniaxial_none = 0, uniaxial_family = 0, uniaxial_all = 0;
  double shear_none = 0, shear_family = 0, shear_all = 0;

  Json to_json() const {
    Json out;
    out["ball_volume_over_cell"] = ball;
    out["all_cut_cells_volume_over_ball"] = vol_all / ball; // partition of unity: 1
    out["family_volume_over_ball"] = vol_family / ball;
    out["uniaxial_energy_ratio_none"] = uniaxial_none;
    out["uniaxial_energy_ratio_exact_family"] = uniaxial_family;
    out["uniaxial_energy_ratio_exact_all_cut_cells"] = uniaxial_all;
    out["shear_energy_ratio_none"] = shear_none;
    out["shear_energy_ratio_exact_family"] = shear_family;
    out["shear_energy_ratio_exact_all_cut_cells"] = shear_all;
    return out;
  }
};

BulkSums exact_truncation(double m) {
  const double delta = m; // λ = 1
  const auto reach = static_cast<long long>(std::ceil(m + 1.0));
  const InHorizon in_family(delta, HorizonRule::inclusive);
  BulkSums b;
  b.vol_all = exact_volume_fraction(3, {0, 0, 0}, delta, 1.0);
  b.vol_family = 1.0; // the particle's own cell
  for (long long k = -reach; k <= reach; ++k) {
    for (long long j = -reach; j <= reach; ++j) {
      for (long long i = -reach; i <= reach; ++i) {
        if (i == 0 && j == 0 && k == 0) {
          continue;
        }
        const Vec3 xi{static_cast<double>(i), static_cast<double>(j), static_cast<double>(k)};
        const double r = norm(xi);
        const double f = exact_volume_fraction(3, xi, delta, 1.0);
        const double nx = xi[0] / r, ny = xi[1] / r;
        const double uniaxial = nx * nx * nx * nx * r, shear = nx * nx * ny * ny * r;
        b.vol_all += f;
        b.uniaxial_all += f * uniaxial;
        b.shear_all += f * shear;
        if (in_family(dot(xi, xi))) {
          b.vol_family += f;
          b.uniaxial_family += f * uniaxial;
          b.uniaxial_none += uniaxial;
          b.shear_family += f * shear;
          b.shear_none += shear;
        }
      }
    }
  }
  b.ball = 4.0 * std::numbers::pi * delta * delta * delta / 3.0;
  const double uniaxial_moment = std::numbers::pi * std::pow(delta, 4) / 5.0;
  const double shear_moment = uniaxial_moment / 3.0;
  for (double* v : {&b.uniaxial_none, &b.uniaxial_family, &b.uniaxial_all}) {
    *v /= uniaxial_moment;
  }
  for (double* v : {&b.shear_none, &b.shear_family, &b.shear_all}) {
    *v /= shear_moment;
  }
  return b;
}

/// The bulk ratio `exact` must give for a load (uniaxial strain along any axis or shear; the
/// lattice and the ball share the cube's symmetries).
double exact_family_ratio(const BulkSums& b, const Load& load) {
  return load.kind == LoadKind::shear ? b.shear_family : b.uniaxial_family;
}

/// One model (a horizon, surface and volume correction) under every load: a row per load into
/// `table`, a printed line each; returns the mean interior ratio of each load.
std::array<double, loads.size()> evaluate(const ModelSpec& spec, const Box& box, double E,
                                          Json& table) {
  const Model model = build_model(spec);
  const auto cls = classify(model.particles, box, spec.lattice.spacing, spec.lattice.horizon());
  const char* surface = surface_names[static_cast<std::size_t>(spec.surface_correction)];
  const char* volume = volume_names[static_cast<std::size_t>(spec.volume_correction)];
  std::array<double, loads.size()> interior{};
  for (const Load& load : loads) {
    std::vector<Vec3> y = model.particles.position;
    for (std::size_t i = 0; i < y.size(); ++i) {
      for (std::size_t a = 0; a < 3; ++a) {
        for (std::size_t b = 0; b < 3; ++b) {
          y[i][a] += strain * load.gradient[a][b] * model.particles.position[i][b];
        }
      }
    }
    const double classical = load.classical * E * strain * strain;
    const auto w = energy_density(model, y);
    std::array<Stats, 4> stats{};
    // Whole body: Σ W_i V_i / (W V_body), independent of how a bond's energy is split
    // between its ends (the `tensor` correction makes it 1 for stress-x by construction).
    double body_pd = 0, body_volume = 0;
    for (std::size_t i = 0; i < w.size(); ++i) {
      body_pd += w[i] * model.particles.volume[i];
      body_volume += model.particles.volume[i];
    }
    for (std::size_t i = 0; i < w.size(); ++i) {
      if (cls[i] < 0) {
        continue;
      }
      Stats& st = stats[static_cast<std::size_t>(cls[i])];
      const double ratio = w[i] / classical;
      st.mean += ratio;
      st.min = std::min(st.min, ratio);
      st.max = std::max(st.max, ratio);
      ++st.count;
    }
    Json row;
    row["horizon_factor"] = spec.lattice.horizon_factor;
    row["surface_correction"] = surface;
    row["volume_correction"] = volume;
    row["load"] = load.name;
    std::string line = fmt::format("   {:<14} {:<8} {:<10}", surface, volume, load.name);
    row["body"] = body_pd / (classical * body_volume);
    line += fmt::format(" {:>7.4f}", body_pd / (classical * body_volume));
    for (std::size_t c = 0; c < stats.size(); ++c) {
      Stats& st = stats[c];
      st.mean = st.count ? st.mean / static_cast<double>(st.count) : 0.0;
      row[class_names[c]] = to_json(st);
      line += c == 0 ? fmt::format(" {:>9.4f}", st.mean)
                     : fmt::format(" {:>7.4f} [{:.4f}, {:.4f}]", st.mean, st.min, st.max);
    }
    fmt::print("{}\n", line);
    table.push_back(row);
    interior[static_cast<std::size_t>(&load - loads.data())] = stats[0].mean;
  }
  return interior;
}

/// Interior ratios without surface correction → the discrete lattice's elastic constants. Central
/// pair forces on a cubic lattice give C12 = C44 (Cauchy relation), so with C11 = (6/5)E·r_t and
/// C44 = (2/5)E·r_s the uniaxial-stress Poisson ratio is ν = C12/(C11 + C12) = r_s/(3r_t + r_s)
/// and Young's modulus E' = C11 − 2C12²/(C11 + C12).
Json lattice_constants(double m, const char* volume, const std::array<double, loads.size()>& r) {
  const double c11 = 1.2 * r[0], c12 = 0.4 * r[3];
  Json lc;
  lc["horizon_factor"] = m;
  lc["volume_correction"] = volume;
  lc["poisson_ratio"] = c12 / (c11 + c12);
  lc["youngs_modulus_over_E"] = c11 - 2.0 * c12 * c12 / (c11 + c12);
  fmt::print("   bulk lattice, volume {:<8}: ν = {:.4f} (continuum 0.25), E'/E = {:.4f}\n", volume,
             c12 / (c11 + c12), c11 - 2.0 * c12 * c12 / (c11 + c12));
  return lc;
}

/// Weights built to reproduce the continuum's fourth moments in the bulk (corrections.hpp), so the
/// interior energy of every uniform strain is the classical one.
bool moment_matched(VolumeCorrection v) {
  return v == VolumeCorrection::moment || v == VolumeCorrection::gradient;
}

} // namespace

Json run_patch_test(const Context& ctx) {
  const auto start = std::chrono::steady_clock::now();
  const Scene scene = load_scene((ctx.folder / "patch-test.yaml").string());
  const ModelSpec& base = scene.model;
  const Box box = base.bodies.front().region.boxes.front();
  const double E = base.materials.front().youngs_modulus;
  const std::array<double, 2> ms{base.lattice.horizon_factor, 2.0 * std::numbers::sqrt3};
  // Both checks are exact identities of the linearised energy; the exact stretch's energy differs
  // from it by O(ε) = 1e-6 relative (measured: 3e-7), so 1e-5 leaves room for that alone.
  const double gate = 1e-5;

  Json out;
  out["case"] = "patch-test";
  out["quantity"] = "strain-energy density PD / classical under uniform strain (ε = 1e-6), by "
                    "particle class, for every surface × volume correction";
  out["strain"] = strain;
  Json table = Json::array();
  bool passed = true;
  Json gate_values = Json::array();
  Json constants = Json::array();
  Json trunc;
  double worst_matched = 0, worst_exact = 0;

  for (const double m : ms) {
    const BulkSums sums = exact_truncation(m);
    trunc[fmt::format("{:.4f}", m)] = sums.to_json();
    fmt::print("   δ/λ = {:.4f}: W_PD / W_classical (mean [min, max])\n", m);
    fmt::print("   {:<14} {:<8} {:<10} {:>7} {:>9} {:>27} {:>27} {:>27}\n", "surface", "volume",
               "load", "body", "interior", "face", "edge", "corner");
    for (std::size_t s = 0; s < surface_names.size(); ++s) {
      for (std::size_t v = 0; v < volume_names.size(); ++v) {
        ModelSpec spec = base;
        spec.lattice.horizon_factor = m;
        spec.surface_correction = static_cast<SurfaceCorrection>(s);
        spec.volume_correction = static_cast<VolumeCorrection>(v);
        const auto interior = evaluate(spec, box, E, table);
        if (spec.surface_correction != SurfaceCorrection::none) {
          continue;
        }
        constants.push_back(lattice_constants(m, volume_names[v], interior));
        const bool matched = moment_matched(spec.volume_correction);
        if (!matched && spec.volume_correction != VolumeCorrection::exact) {
          continue;
        }
        for (std::size_t l = 0; l < loads.size(); ++l) {
          if (!loads[l].gated()) {
            continue;
          }
          const double expected = matched ? 1.0 : exact_family_ratio(sums, loads[l]);
          const double err = std::abs(interior[l] / expected - 1.0);
          const bool ok = err <= gate;
          (matched ? worst_matched : worst_exact) =
              std::max(matched ? worst_matched : worst_exact, err);
          Json g;
          g["horizon_factor"] = m;
          g["volume_correction"] = volume_names[v];
          g["load"] = loads[l].name;
          g["interior_ratio"] = interior[l];
          g["expected"] = expected;
          g["expected_from"] = matched ? "classical energy" : "bulk lattice sum of exact fractions";
          g["passed"] = ok;
          gate_values.push_back(g);
          passed = passed && ok;
        }
      }
    }
  }
  out["table"] = table;
  out["bulk_lattice_elastic_constants"] = constants;
  out["exact_volume_truncation"] = trunc;
  out["error"]["interior_moment_gradient_vs_classical"] = worst_matched;
  out["error"]["interior_exact_vs_lattice_sum"] = worst_exact;
  out["gate"] = "surface_correction none, every load and horizon: interior mean ratio within 1e-5 "
                "of 1 for the moment-matched weights (moment, gradient), and of exact's bulk "
                "lattice sum over the family |ξ| ≤ δ for exact (0.84 at δ = 3.015λ: the family "
                "misses the parts of the cut cells whose centres lie beyond δ)";
  out["gate_values"] = gate_values;
  out["passed"] = passed;
  out["wall_seconds"] =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  for (const double m : ms) {
    const Json& t = *trunc.find(fmt::format("{:.4f}", m));
    fmt::print("   exact volume, bulk lattice sums at δ/λ = {:.4f}: family volume / ball = {:.4f} "
               "(all cut cells {:.6f}); uniaxial energy ratio none {:.4f}, exact (family |ξ| ≤ "
               "δ) {:.4f}, exact (all cut cells) {:.4f}; shear {:.4f}, {:.4f}, {:.4f}\n",
               m, *t.find("family_volume_over_ball")->number(),
               *t.find("all_cut_cells_volume_over_ball")->number(),
               *t.find("uniaxial_energy_ratio_none")->number(),
               *t.find("uniaxial_energy_ratio_exact_family")->number(),
               *t.find("uniaxial_energy_ratio_exact_all_cut_cells")->number(),
               *t.find("shear_energy_ratio_none")->number(),
               *t.find("shear_energy_ratio_exact_family")->number(),
               *t.find("shear_energy_ratio_exact_all_cut_cells")->number());
  }
  fmt::print("   gate: moment/gradient interior worst |ratio − 1| = {:.2e}, exact vs its lattice "
             "sum worst {:.2e} (both ≤ {:g})\n",
             worst_matched, worst_exact, gate);
  return out;
}

PD_VERIFICATION_RUN("patch-test", run_patch_test);

} // namespace pd::verification
