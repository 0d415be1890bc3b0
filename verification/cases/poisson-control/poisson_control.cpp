// poisson-control (issue 17): the virtual-fibre model (Olsson, Ander & Williams 2021) sets ν
// freely. A free block of W × W × 3W (3D) or W × 3W (plane strain) is pulled by equal and opposite
// tractions σ on its end layers (scenes/poisson-control.yaml; no support, ADR). Away from the ends
// the stress is uniaxial, so
//   3D:            ε_xx = σ/E,          ε_yy = −νσ/E
//   plane strain:  ε_xx = (1 − ν²)σ/E,  ε_yy = −ν(1 + ν)σ/E      (ε_zz = 0)
// for ν = 0.1, 0.3, 0.45. The strains are read in the interior: ε_xx from the section-mean u_x of
// the layers at L/4 and 3L/4, ε_yy from the mean u_y of the particle rows a quarter of the width
// in from each lateral face, over the two layers at mid-length. Gates, at the default
// resolution and finer: the lateral contraction within 2 % of the reference (issue 17), and the
// axial strain, the same closed form's other half, within the same 2 %, and the ν the strains
// imply (r = −ε_yy/ε_xx in 3D, r/(1 + r) in plane strain) within 2 % of ν. A section coarser than
// the default is held to what a discretisation of the closed form owes: its lateral, axial and
// effective-ν errors are each larger than at every finer section of the same ν and dimension (the
// error falls with refinement).
//
// The scene takes the library's defaults and sets only the knob the case studies (bond_model):
// ghost layers outside the free faces complete every body particle's horizon (ghosts own no
// energy under the fibre model, discretisation/fibre_arms.hpp), and the default volume
// correction means, for the fibre model, lattice weights that make the bulk family's fourth
// moments isotropic; without them the cubic lattice alone moves the lateral contraction by 5 %
// (3D) and 29 % (plane strain) at ν = 0.1 (tests/unit/kernel/fibre_kernel_test.cpp shows the
// stress error with `none`).
//
// `poisson-control` runs every ν at the default resolution (3D: 10 particles across; plane
// strain: 20); `poisson-control-full` (label verification-full) adds a coarser section, held to
// the falling error in all three reported quantities (lateral, axial, effective ν), and a finer
// one. The axial strain's error does not fall in 3D at ν = 0.3 and 0.45: 0.00 → +0.16 → +0.07 %
// and +0.23 → +0.32 → +0.12 % at 6, 10, 16 across (small, but not falling): -full fails on it.
// Measured, lateral contraction error:
//   3D   6 across +11.4 / +4.5 / +3.0 %, 10 across −1.98 / −0.86 / −0.74 %, 16 across −0.41 /
//        −0.06 / +0.03 % (ν = 0.1 / 0.3 / 0.45)
//   plane strain 10 across −2.3 / −1.0 / −1.0 %, 20 across +0.07 / +0.08 / +0.06 %, 40 across
//        −0.01 / +0.02 / +0.03 %
// The error is the free faces' (every particle of a 6-across section is within δ of one): ghosts
// make each particle's energy exact for a linear field, but the uniform state is not quite the
// discrete equilibrium next to a face. ν = 0.1 at 10 across (3D) sits at −1.98 %, at the gate,
// and its effective ν (gated too) at −2.07 %: the case fails and runs in the report.
#include "libpd/app/run.hpp"
#include "libpd/io/scene.hpp"
#include "verification.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <fmt/format.h>
#include <map>
#include <string>
#include <vector>

namespace pd::verification {

namespace {

constexpr double lateral_gate = 0.02;
constexpr double axial_gate = 0.02;

struct Variant {
  int dim = 3;
  double nu = 0.3;
  int across = 10;   ///< particles across the width W
  bool gated = true; ///< false: coarser than the default, held to the falling errors only
};

Box box(const Vec3& lo, const Vec3& hi) {
  return Box{lo, hi};
}

ProbeSpec probe(const std::string& name, const Box& b, int component) {
  ProbeSpec p;
  p.name = name;
  p.kind = ProbeSpec::Kind::region;
  p.region.boxes = {b};
  p.component = component;
  return p;
}

/// The scene's block at `v.across` particles across (spacing fixed), its material's ν, and the
/// probes of the interior strains (cell-centred lattice: particle k at (k + ½)λ).
Scene variant(const Scene& base, const Variant& v) {
  Scene s = base;
  s.particles.reset();
  const double l = base.model.lattice.spacing;
  const double W = v.across * l, L = 3 * W;
  const double H = v.dim == 3 ? W : 0.0;
  s.model.dimension.dim = v.dim;
  s.model.dimension.plane = PlaneMode::plane_strain;
  s.model.materials.front().poisson_ratio = v.nu;
  s.model.bodies.front().region.boxes = {box({0, 0, 0}, {L, W, H})};
  const double area = v.dim == 3 ? W * H : W * s.model.dimension.thickness;
  s.model.loads.at(0).load.region.boxes = {box({L - l, 0, 0}, {L, W, H})};
  s.model.loads.at(1).load.region.boxes = {box({0, 0, 0}, {l, W, H})};
  for (LoadSpec& load : s.model.loads) {
    load.load.measure = area;
  }
  const int quarter = v.across / 4;
  const double y_lo = (quarter + 0.5) * l, y_hi = W - y_lo;
  const int layers = 3 * v.across;
  const double x_lo = (layers / 4 + 0.5) * l, x_hi = L - x_lo;
  const double x_mid = 0.5 * L;
  s.probes = {
      probe("axial_lo", box({x_lo - 0.5 * l, 0, 0}, {x_lo + 0.5 * l, W, H}), 0),
      probe("axial_hi", box({x_hi - 0.5 * l, 0, 0}, {x_hi + 0.5 * l, W, H}), 0),
      probe("lateral_lo", box({x_mid - l, y_lo - 0.5 * l, 0}, {x_mid + l, y_lo + 0.5 * l, H}), 1),
      probe("lateral_hi", box({x_mid - l, y_hi - 0.5 * l, 0}, {x_mid + l, y_hi + 0.5 * l, H}), 1),
  };
  s.title = fmt::format("{} (dim {}, nu = {}, {} across)", base.title, v.dim, v.nu, v.across);
  return s;
}

struct Measured {
  Json json;
  double lateral_error = 0; ///< signed, relative
  double axial_error = 0;   ///< signed, relative
  double nu_error = 0;      ///< the effective ν against the material's, signed, relative
  bool converged = false;
};

Measured run_variant(const Scene& base, const Variant& v, const Context& ctx,
                     const std::string& folder) {
  const Scene scene = variant(base, v);
  RunOptions opt = case_run_options(ctx, folder);
  opt.write_vtu = false;
  const RunOutcome run = run_scene(scene, opt);
  const double l = base.model.lattice.spacing;
  const double W = v.across * l;
  const int quarter = v.across / 4;
  const double y_lo = (quarter + 0.5) * l, y_hi = W - y_lo;
  const int layers = 3 * v.across;
  const double x_lo = (layers / 4 + 0.5) * l, x_hi = 3 * W - x_lo;
  const double E = scene.model.materials.front().youngs_modulus;
  const double sigma = scene.model.loads.front().load.value[0];
  const double nu = v.nu;
  const bool plane = v.dim == 2;
  const double axial_ref = (plane ? 1 - nu * nu : 1.0) * sigma / E;
  const double lateral_ref = -(plane ? nu * (1 + nu) : nu) * sigma / E;
  const double axial = (run.probes.at("axial_hi") - run.probes.at("axial_lo")) / (x_hi - x_lo);
  const double lateral =
      (run.probes.at("lateral_hi") - run.probes.at("lateral_lo")) / (y_hi - y_lo);
  Measured m;
  m.lateral_error = lateral / lateral_ref - 1.0;
  m.axial_error = axial / axial_ref - 1.0;
  m.converged = run.result.status == RunStatus::converged;
  Json& j = m.json;
  j["dimension"] = v.dim == 3 ? "3D" : "plane strain";
  j["poisson_ratio"] = nu;
  j["particles_across"] = v.across;
  j["pd"]["axial_strain"] = axial;
  j["pd"]["lateral_strain"] = lateral;
  j["reference"]["axial_strain"] = axial_ref;
  j["reference"]["lateral_strain"] = lateral_ref;
  j["signed_error"]["axial_strain"] = m.axial_error;
  j["signed_error"]["lateral_contraction"] = m.lateral_error;
  // ν as the block shows it: −ε_yy/ε_xx in 3D; ε_yy/ε_xx = −ν/(1 − ν) in plane strain.
  const double ratio = -lateral / axial;
  j["pd"]["effective_poisson_ratio"] = plane ? ratio / (1 + ratio) : ratio;
  m.nu_error = (plane ? ratio / (1 + ratio) : ratio) / nu - 1.0;
  j["signed_error"]["effective_poisson_ratio"] = m.nu_error;
  j["steady_state"]["status"] = to_string(run.result.status);
  j["steps"] = run.result.steps;
  j["particles"] = run.particles;
  j["bonds"] = run.bonds;
  j["solve_seconds"] = run.result.wall_seconds;
  fmt::print("   {:<12} ν = {:<4} {:>2} across: lateral contraction {:+6.2f} %, axial strain "
             "{:+6.2f} %, ν_eff = {:.4f} ({}, {} steps)\n",
             v.dim == 3 ? "3D" : "plane strain", nu, v.across, 100 * (lateral / lateral_ref - 1.0),
             100 * (axial / axial_ref - 1.0), plane ? ratio / (1 + ratio) : ratio,
             m.converged ? "converged" : "NOT converged", run.result.steps);
  return m;
}

/// One section's error magnitudes, for the falling-error gate of poisson-control-full.
struct SectionErrors {
  int across = 0;
  double lateral = 0;
  double axial = 0;
  double nu = 0;
};

/// The quantities whose errors must fall with the section, by the name of their gate.
constexpr std::array<std::pair<const char*, double SectionErrors::*>, 3> section_quantities{{
    {"lateral_error", &SectionErrors::lateral},
    {"axial_error", &SectionErrors::axial},
    {"poisson_ratio_error", &SectionErrors::nu},
}};

Json run_variants(const Context& ctx, const std::string& name, const std::vector<Variant>& vs) {
  const auto start = std::chrono::steady_clock::now();
  const Scene base = load_scene((ctx.folder / "poisson-control.yaml").string());
  Json out;
  out["case"] = name;
  out["quantity"] = "interior lateral contraction of a block in uniaxial tension, virtual fibres";
  bool converged = true;
  // The gated variants' largest errors, signed.
  double worst_lateral = 0, worst_axial = 0, worst_nu = 0;
  const auto worse = [](double& worst, double e) {
    worst = std::abs(e) > std::abs(worst) ? e : worst;
  };
  // Per (dimension, ν): each section's error magnitudes, sorted coarsest first below.
  std::map<std::pair<int, double>, std::vector<SectionErrors>> series;
  Json rows = Json::array();
  for (const Variant& v : vs) {
    const std::string folder =
        fmt::format("{}/{}d-nu{}-{}", name, v.dim, static_cast<int>(v.nu * 100 + 0.5), v.across);
    Measured m = run_variant(base, v, ctx, folder);
    m.json["gated"] = v.gated;
    converged = converged && m.converged;
    if (v.gated) {
      worse(worst_lateral, m.lateral_error);
      worse(worst_axial, m.axial_error);
      worse(worst_nu, m.nu_error);
    }
    series[{v.dim, v.nu}].push_back(
        {v.across, std::abs(m.lateral_error), std::abs(m.axial_error), std::abs(m.nu_error)});
    rows.push_back(std::move(m.json));
  }
  // Every section coarser than the default must have a larger error than each finer one, in each
  // quantity the case reports: the coarse sections' numbers are judged by this alone.
  std::size_t with_coarse = 0;
  std::array<std::size_t, section_quantities.size()> falling{};
  for (auto& [key, errors] : series) {
    std::sort(errors.begin(), errors.end(),
              [](const SectionErrors& a, const SectionErrors& b) { return a.across < b.across; });
    const bool coarse = std::any_of(vs.begin(), vs.end(), [&](const Variant& v) {
      return !v.gated && v.dim == key.first && v.nu == key.second;
    });
    if (!coarse) {
      continue;
    }
    ++with_coarse;
    for (std::size_t q = 0; q < section_quantities.size(); ++q) {
      const double SectionErrors::*error = section_quantities[q].second;
      bool falls = true;
      for (std::size_t k = 1; k < errors.size(); ++k) {
        falls = falls && errors[k].*error < errors[k - 1].*error;
      }
      falling[q] += falls ? 1 : 0;
    }
  }
  out["variants"] = std::move(rows);
  out["error"]["lateral_contraction"] = std::abs(worst_lateral);
  out["error"]["axial_strain"] = std::abs(worst_axial);
  out["signed_error"]["lateral_contraction"] = worst_lateral;
  out["signed_error"]["axial_strain"] = worst_axial;
  // The ν the block shows is what the case is for: held to the strains' tolerance.
  out["error"]["effective_poisson_ratio"] = std::abs(worst_nu);
  out["signed_error"]["effective_poisson_ratio"] = worst_nu;
  std::vector<Gate> gates = {{"lateral_contraction", lateral_gate},
                             {"axial_strain", axial_gate},
                             {"effective_poisson_ratio", lateral_gate}};
  if (with_coarse > 0) {
    for (std::size_t q = 0; q < section_quantities.size(); ++q) {
      const std::string key = std::string("series_with_falling_") + section_quantities[q].first;
      out["pd"][key] = falling[q];
      gates.push_back({"min_" + key, static_cast<double>(with_coarse)});
    }
  }
  finish_case(out, gates, converged, start);
  return out;
}

std::vector<Variant> every_ratio(int dim, int across) {
  return {{dim, 0.1, across}, {dim, 0.3, across}, {dim, 0.45, across}};
}

} // namespace

Json run_poisson_control(const Context& ctx) {
  std::vector<Variant> vs = every_ratio(3, 10);
  for (const Variant& v : every_ratio(2, 20)) {
    vs.push_back(v);
  }
  return run_variants(ctx, "poisson-control", vs);
}

Json run_poisson_control_full(const Context& ctx) {
  // Coarser sections than the default show the convergence and are not gated.
  std::vector<Variant> vs;
  for (int across : {6, 10, 16}) {
    for (Variant v : every_ratio(3, across)) {
      v.gated = across >= 10;
      vs.push_back(v);
    }
  }
  for (int across : {10, 20, 40}) {
    for (Variant v : every_ratio(2, across)) {
      v.gated = across >= 20;
      vs.push_back(v);
    }
  }
  return run_variants(ctx, "poisson-control-full", vs);
}

PD_VERIFICATION_RUN("poisson-control", run_poisson_control);
PD_VERIFICATION_RUN("poisson-control-full", run_poisson_control_full);

} // namespace pd::verification
