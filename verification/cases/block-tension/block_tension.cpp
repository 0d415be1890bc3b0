// block-tension (Pasupathy, Table 1): 1 × 0.1 × 0.1 m block, left end clamped, 200 MPa on the right
// end. Uniaxial stress gives u_x(x) = σx/E along the centre line and a lateral strain −νσ/E with
// the bond-based ν = 1/4. Without surface correction the outer particles are too soft, so the
// block stretches more than σL/E (+19 %) and contracts more than νσ/E (+42 %).
//
// `block-tension` (10 particles across, the paper's λ) and `block-tension-thin` (5 across) run the
// scene with the library's defaults and gate the two errors. `block-tension-corrections` (slow,
// label verification-full) runs every surface × volume correction and a δ/λ sweep at fixed λ and
// at fixed δ, and reports the same errors; it gates nothing.
//
// Where the errors come from (measured):
//  * the bulk lattice: with uniform, `linear` or `exact` weights the cubic lattice at δ = 3.015λ
//    has ν = 0.268–0.278 instead of 1/4 (patch-test, bulk_lattice_elastic_constants: central pair
//    forces give C12 = C44 and the lattice sums make C44/C11 too large). A scalar factor per bond
//    scales C11 and C12 alike and cannot change that ratio. `moment` and `gradient` weights give
//    the bulk exactly E and ν = 1/4.
//  * the surface: 84 of the 100 particles of a cross-section are within δ of a face. Ghost layers
//    make every linear field cost each particle exactly the bulk energy, but the uniform state is
//    not quite the discrete equilibrium: a perturbation of one surface row is not a quadratic
//    field, so the outer rows relax (the second row's lateral strain is 6 % above the bulk's at
//    10 across) and the outer-row lateral strain reads +0.85 %.
//  * the clamp: a mirror clamp holds the face itself; fixed particle layers would clamp ~0.4 λ
//    behind it (+0.4 λ / L elongation, see the scene).
#include "libpd/app/run.hpp"
#include "libpd/discretisation/corrections.hpp"
#include "libpd/io/scene.hpp"
#include "verification.hpp"

#include <array>
#include <chrono>
#include <cmath>
#include <fmt/format.h>
#include <numbers>
#include <string>

namespace pd::verification {

namespace {

// Issue 14's gates. Measured with the defaults: 10 across −0.17 % / +0.85 %, 5 across +0.23 % /
// +0.24 % (signed: + is too soft).
constexpr double elongation_gate = 0.005;
constexpr double lateral_gate = 0.02;

const auto surface_names = surface_correction_names();
const auto volume_names = volume_correction_names();

Box box(const Vec3& lo, const Vec3& hi) {
  return Box{lo, hi};
}

/// The block-tension scene at another spacing λ and δ/λ: the grip gets ⌊δ/λ⌋ fixed layers (all
/// that reach the first block layer, 3 as in the scene for δ = 3.015λ), the
/// load the last particle layer, and the probes the centre line and the outer rows at mid-length
/// of the new lattice (cell-centred: particles at (k + ½)λ).
Scene variant(const Scene& base, double spacing, double m) {
  Scene s = base;
  const Box block = base.model.bodies.front().region.boxes.front();
  const double L = block.hi[0], W = block.hi[1], H = block.hi[2];
  const double l = spacing;
  s.model.lattice.spacing = l;
  s.model.lattice.horizon_factor = m;
  const double grip = std::floor(m + 1e-9) * l;
  s.model.bodies.at(1).region.boxes = {box({-grip, 0, 0}, {0, W, H})};
  s.model.supports.at(0).region.boxes = {box({-grip, 0, 0}, {0, W, H})};
  s.model.loads.at(0).load.region.boxes = {box({L - l, 0, 0}, {L, W, H})};
  // Centre line: the particles within ¾λ of (y, z) = (W/2, H/2): one row (odd count) or the four
  // around it (even count), symmetric either way.
  const double c = 0.75 * l;
  for (ProbeSpec& p : s.probes) {
    p.kind = ProbeSpec::Kind::region;
    if (p.name == "end_displacement") {
      p.region.boxes = {box({L - l, W / 2 - c, H / 2 - c}, {L, W / 2 + c, H / 2 + c})};
    } else if (p.name == "mid_displacement") {
      p.region.boxes = {box({L / 2 - l, W / 2 - c, H / 2 - c}, {L / 2, W / 2 + c, H / 2 + c})};
    } else if (p.name == "mid_top_y") {
      p.region.boxes = {box({L / 2 - l, W - l, H / 2 - c}, {L / 2, W, H / 2 + c})};
    } else if (p.name == "mid_bottom_y") {
      p.region.boxes = {box({L / 2 - l, 0, H / 2 - c}, {L / 2, l, H / 2 + c})};
    }
  }
  return s;
}

struct BlockResult {
  Json json;
  double elongation_error = 0;
  double lateral_error = 0;
  bool converged = false;
};

/// A run of the block; `folder` empty: write nothing.
BlockResult run_block(const Scene& scene, const Context& ctx, const std::string& folder) {
  RunOptions opt;
  if (!folder.empty()) {
    opt = case_run_options(ctx, folder);
  }
  opt.progress = ctx.progress;
  opt.write_vtu = !folder.empty();
  const RunOutcome run = run_scene(scene, opt);

  const Box block = scene.model.bodies.front().region.boxes.front();
  const double l = scene.model.lattice.spacing;
  const double E = scene.model.materials.front().youngs_modulus;
  const double sigma = scene.model.loads.front().load.value[0];
  const double nu = 0.25; // bond-based PD in 3D
  // Probe particles sit half a spacing inside the faces (cell-centred lattice).
  const double x_end = block.hi[0] - 0.5 * l, x_mid = 0.5 * block.hi[0] - 0.5 * l;
  const double width = block.hi[1] - l;
  const double elongation_ref = sigma * x_end / E;
  const double mid_ref = sigma * x_mid / E;
  const double lateral_ref = -nu * sigma / E;
  const double elongation = run.probes.at("end_displacement");
  const double mid = run.probes.at("mid_displacement");
  const double lateral = (run.probes.at("mid_top_y") - run.probes.at("mid_bottom_y")) / width;

  BlockResult r;
  r.elongation_error = relative_error(elongation, elongation_ref);
  r.lateral_error = relative_error(lateral, lateral_ref);
  r.converged = run.result.status == RunStatus::converged;
  Json& out = r.json;
  out["surface_correction"] =
      surface_names[static_cast<std::size_t>(scene.model.surface_correction)];
  out["volume_correction"] = volume_names[static_cast<std::size_t>(scene.model.volume_correction)];
  out["spacing"] = l;
  out["horizon_factor"] = scene.model.lattice.horizon_factor;
  out["horizon"] = scene.model.lattice.horizon();
  out["pd"]["end_displacement"] = elongation;
  out["pd"]["mid_displacement"] = mid;
  out["pd"]["lateral_strain"] = lateral;
  out["reference"]["end_displacement"] = elongation_ref;
  out["reference"]["mid_displacement"] = mid_ref;
  out["reference"]["lateral_strain"] = lateral_ref;
  // Signed errors too: + means too soft (too long, too much contraction).
  out["error"]["elongation"] = r.elongation_error;
  out["error"]["mid_displacement"] = relative_error(mid, mid_ref);
  out["error"]["lateral_contraction"] = r.lateral_error;
  out["signed_error"]["elongation"] = elongation / elongation_ref - 1.0;
  out["signed_error"]["lateral_contraction"] = lateral / lateral_ref - 1.0;
  out["steady_state"]["status"] = to_string(run.result.status);
  out["steady_state"]["residual"] = run.result.residual;
  out["steps"] = run.result.steps;
  out["setup_seconds"] = run.setup_seconds;
  out["particles"] = run.particles;
  out["bonds"] = run.bonds;
  out["run"] = run.summary;
  return r;
}

std::string describe(const BlockResult& r, const Scene& s) {
  return fmt::format(
      "{:<14} {:<7} λ = {:.5f} m, δ/λ = {:.4f}: elongation {:+7.2f} %, lateral contraction "
      "{:+7.2f} % ({}, {} steps)",
      surface_names[static_cast<std::size_t>(s.model.surface_correction)],
      volume_names[static_cast<std::size_t>(s.model.volume_correction)], s.model.lattice.spacing,
      s.model.lattice.horizon_factor,
      100 * *r.json.find("signed_error")->find("elongation")->number(),
      100 * *r.json.find("signed_error")->find("lateral_contraction")->number(),
      r.converged ? "converged" : "NOT converged", *r.json.find("steps")->number());
}

} // namespace

namespace {

/// The block at `particles_across` particles across its square section (the scene's δ/λ), gated.
Json gated_block(const Context& ctx, const std::string& name, int particles_across) {
  const Scene base = load_scene((ctx.folder / "block-tension.yaml").string());
  const double width = base.model.bodies.front().region.boxes.front().hi[1];
  const Scene scene = variant(base, width / particles_across, base.model.lattice.horizon_factor);
  BlockResult r = run_block(scene, ctx, name);
  Json out;
  out["case"] = name;
  out["quantity"] = "centre-line u_x at the loaded end and lateral strain at mid-length";
  out["particles_across"] = particles_across;
  for (const char* key :
       {"surface_correction", "volume_correction", "spacing", "pd", "reference", "error",
        "signed_error", "steady_state", "steps", "setup_seconds", "run"}) {
    out[key] = *r.json.find(key);
  }
  out["gate"] = fmt::format("elongation error <= {:g} %, lateral contraction error <= {:g} %, "
                            "steady state reached",
                            100 * elongation_gate, 100 * lateral_gate);
  out["passed"] =
      r.converged && r.elongation_error <= elongation_gate && r.lateral_error <= lateral_gate;
  fmt::print("   {}\n", describe(r, scene));
  return out;
}

} // namespace

Json run_block_tension(const Context& ctx) {
  return gated_block(ctx, "block-tension", 10);
}

Json run_block_tension_thin(const Context& ctx) {
  return gated_block(ctx, "block-tension-thin", 5);
}

Json run_block_tension_corrections(const Context& ctx) {
  const auto start = std::chrono::steady_clock::now();
  const Scene base = load_scene((ctx.folder / "block-tension.yaml").string());
  const double spacing = base.model.lattice.spacing, m0 = base.model.lattice.horizon_factor;
  Json out;
  out["case"] = "block-tension-corrections";
  out["quantity"] = "block-tension elongation and lateral-contraction errors for every surface x "
                    "volume correction, and their dependence on delta/lambda";
  Json combos = Json::array();
  for (std::size_t s = 0; s < surface_names.size(); ++s) {
    for (std::size_t v = 0; v < volume_names.size(); ++v) {
      if (static_cast<VolumeCorrection>(v) == VolumeCorrection::fitted) {
        continue; // weights for sets that are not a lattice
      }
      Scene scene = variant(base, spacing, m0);
      scene.model.surface_correction = static_cast<SurfaceCorrection>(s);
      scene.model.volume_correction = static_cast<VolumeCorrection>(v);
      const BlockResult r = run_block(scene, ctx, {});
      fmt::print("   {}\n", describe(r, scene));
      std::fflush(stdout);
      combos.push_back(r.json);
    }
  }
  out["combinations"] = combos;

  // δ/λ sweep for no correction and for the scene's (default) corrections: at fixed λ, and at
  // fixed δ = 0.05 m with λ = 0.1/n m (the cross-section must hold whole cells), n = 4, 6, 7, 8
  // for δ/λ = 2, 3, 3.5 (the nearest to 2√3 that fits), 4.
  const std::array<double, 4> ms{2.0, 3.0, 2.0 * std::numbers::sqrt3, 4.0};
  const std::array<int, 4> cells{4, 6, 7, 8};
  const double fixed_delta = 0.05;
  Json sweep = Json::array();
  for (const bool corrected : {false, true}) {
    for (std::size_t k = 0; k < ms.size(); ++k) {
      for (const bool fixed_lambda : {true, false}) {
        const double l = fixed_lambda ? spacing : 0.1 / cells[k];
        const double m = fixed_lambda ? ms[k] : fixed_delta / l;
        Scene scene = variant(base, l, m);
        if (!corrected) {
          scene.model.surface_correction = SurfaceCorrection::none;
          scene.model.volume_correction = VolumeCorrection::none;
        }
        BlockResult r = run_block(scene, ctx, {});
        r.json["sweep"] = fixed_lambda ? "fixed spacing" : "fixed horizon";
        r.json["nominal_horizon_factor"] = ms[k];
        fmt::print("   [{}] {}\n", fixed_lambda ? "fixed λ" : "fixed δ", describe(r, scene));
        std::fflush(stdout);
        sweep.push_back(r.json);
      }
    }
  }
  out["m_convergence"] = sweep;
  finish_case(out, "none: reported only (block-tension gates the default corrections)", true,
              start);
  return out;
}

PD_VERIFICATION_RUN("block-tension", run_block_tension);
PD_VERIFICATION_RUN("block-tension-thin", run_block_tension_thin);
PD_VERIFICATION_RUN("block-tension-corrections", run_block_tension_corrections);

} // namespace pd::verification
