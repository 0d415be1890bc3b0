// compression-cube (Miranda et al. 2019 §5.2.2): 150 mm C60/75 cube compressed between two stiff
// machine layers held horizontally, brittle micro-elastic bonds (eqs. 9–13). Outputs the
// stress–strain curve (curve.csv, one row per relaxed increment), the damage evolution (broken
// bonds and mean damage of the free faces, of the faces against the plates and of the core, per
// increment) and VTU damage fields at the peak (the last increment before the failure), at the
// first increment after it, and at 50 % and 100 % of the imposed closure.
//
// Compared with the paper's peak (72.9 MPa at ε = 0.26 %) and Eurocode 2's C60/75 values
// (f_cm = 68 MPa at ε_c1 = 0.25 %, EN 1992-1-1 Table 3.1). Stress = force on the top plate from the
// specimen's bonds / 0.15², nominal strain = plate closure / 150 mm.
//
// The critical stretch. The paper gives no G0 nor f_ct for this example; the case runs the rule of
// rc-beam, s0 = f_ctm/E (f_ctm = 4.4 MPa for C60/75), and, as a sweep that stops after the peak,
// 0.8 and 1.2 times it and the s0 that eq. 11 gives for the fib Model Code 2010 fracture energy
// G_F = 73 f_cm^0.18. Bond-based PD with ν = 1/4 makes the compressive strength of a brittle
// specimen a few times f_ct (lateral stretch ν ε), far below concrete's f_c/f_ct ≈ 15: see
// docs/theory/quasi-brittle.md. The gate is the concrete's all the same (the peak stress within
// EC2's 8 MPa of f_cm), so the case fails for as long as the model's strength in compression
// falls short of concrete's.
#include "curve_recorder.hpp"
#include "libpd/io/scene.hpp"
#include "libpd/physics/material.hpp"
#include "libpd/time/quasi_static.hpp"
#include "verification.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fmt/format.h>
#include <numbers>

namespace pd::verification {

namespace {

constexpr double paper_peak_stress = 72.9e6, paper_peak_strain = 0.0026;
constexpr double ec2_peak_stress = 68.0e6, ec2_peak_strain = 0.0025; // f_cm, ε_c1 (C60/75)
constexpr double ec2_tensile_strength = 4.4e6;                       // f_ctm (C60/75)
// EN 1992-1-1 3.1.2: f_cm = f_ck + 8 MPa, f_ck the 5 % fractile of the cube's class; the gate holds
// the peak to that band about f_cm, the scatter of the concrete EC2's values describe.
constexpr double ec2_mean_over_characteristic = 8.0e6;
constexpr double side = 0.15;

double model_code_fracture_energy() {
  return 73.0 * std::pow(ec2_peak_stress / 1e6, 0.18); // fib MC2010 eq. 5.1-9 [N/m]
}

const SupportSpec& support(const Scene& s, const std::string& name) {
  for (const SupportSpec& sup : s.model.supports) {
    if (sup.name == name) {
      return sup;
    }
  }
  throw std::runtime_error("compression-cube: the scene has no support '" + name + "'");
}

Material& concrete(Scene& s) {
  for (Material& m : s.model.materials) {
    if (m.name == "concrete") {
      return m;
    }
  }
  throw std::runtime_error("compression-cube: the scene has no material 'concrete'");
}

struct CubeRun {
  Json json;
  std::vector<double> stresses, strains; ///< per increment
  double peak_stress = 0, peak_strain = 0, last_stress = 0;
  double max_stress = 0, max_strain = 0; ///< global maximum, after-failure branch included
  bool failed = false;                   ///< the first peak has been passed
  bool completed = false;
};

/// The failure drop that marks the first peak: the stress falls ≥ 5 % below its maximum so far.
constexpr double failure_drop = 0.05;

/// Mean damage of the specimen's particles on the four free faces, on the two faces against the
/// plates (excluding the free-face edges) and of the rest.
Json damage_by_zone(const Model& m, double spacing) {
  double sum[3] = {0, 0, 0};
  std::size_t count[3] = {0, 0, 0};
  const double edge = spacing; // the outer particle layer lies λ/2 inside each face
  for (std::size_t i = 0; i < m.size(); ++i) {
    const Vec3& x = m.particles.position[i];
    if (x[2] < 0 || x[2] > side) {
      continue; // machine
    }
    const bool free_face = x[0] < edge || x[0] > side - edge || x[1] < edge || x[1] > side - edge;
    const bool plate_face = !free_face && (x[2] < edge || x[2] > side - edge);
    const int zone = free_face ? 0 : plate_face ? 1 : 2;
    sum[zone] += m.state.damage[i];
    ++count[zone];
  }
  Json j;
  j["free_faces"] = count[0] ? sum[0] / static_cast<double>(count[0]) : 0.0;
  j["plate_faces"] = count[1] ? sum[1] / static_cast<double>(count[1]) : 0.0;
  j["core"] = count[2] ? sum[2] / static_cast<double>(count[2]) : 0.0;
  return j;
}

CubeRun run_cube(const Scene& scene, const std::filesystem::path& dir, bool full, bool progress,
                 quasi_static::Method method = quasi_static::Method::adr) {
  Model model = build_model(scene.model);
  const double spacing = scene.model.lattice.spacing;
  const auto top = quasi_static::particles_in(model, support(scene, "top").region);
  const auto bottom = quasi_static::particles_in(model, support(scene, "bottom").region);
  const double closure =
      support(scene, "bottom").displacement[2] - support(scene, "top").displacement[2];
  CubeRun r;
  quasi_static::Settings st;
  // Fine steps (0.0027 % strain) over the first half, where the specimen fails for every s0
  // swept here, then 0.013 % steps to the end.
  for (int k = 1; k <= 50; ++k) {
    st.levels.push_back(0.01 * k);
  }
  for (int k = 11; k <= 20; ++k) {
    st.levels.push_back(0.05 * k);
  }
  st.method = method;
  st.max_iterations = 400;
  st.first_ramp_iterations = 100;
  st.residual_tolerance = scene.solver.steady.force_tolerance;
  st.progress = progress;
  std::vector<int> vtu_increments;
  if (full) {
    vtu_increments = {50, 60}; // 50 % and 100 % of the closure
  } else {
    st.done = [&](const Simulation&) { return r.failed; };
  }
  Json evolution = Json::array();
  const std::string header = "increment,strain_percent,stress_MPa,stress_bottom_MPa,"
                             "measured_strain_percent,broken_bonds,damage_free_faces,"
                             "damage_plate_faces,damage_core,iterations,residual,converged";
  CurveRecorder record(
      dir, header, vtu_increments, "compression-cube",
      [&](const Simulation& sim, const quasi_static::IncrementInfo& inc) {
        const double area = side * side;
        // The specimen pushes the top plate up (b_z > 0) and the bottom plate down.
        const double stress = quasi_static::bond_force(sim, top, 2) / area;
        const double stress_bottom = -quasi_static::bond_force(sim, bottom, 2) / area;
        const double strain = inc.fraction * closure / side;
        // Strain between the specimen's outer particle layers (λ/2 inside its faces).
        double u_top = 0, u_bot = 0;
        std::size_t n_top = 0, n_bot = 0;
        for (std::size_t i = 0; i < sim.model().size(); ++i) {
          const double z = sim.model().particles.position[i][2];
          if (std::abs(z - 0.5 * spacing) < 1e-6) {
            u_bot += sim.displacement(i, 2);
            ++n_bot;
          } else if (std::abs(z - (side - 0.5 * spacing)) < 1e-6) {
            u_top += sim.displacement(i, 2);
            ++n_top;
          }
        }
        const double measured =
            (u_bot / static_cast<double>(n_bot) - u_top / static_cast<double>(n_top)) /
            (side - spacing);
        // The peak is the first maximum, the brittle failure of the specimen. After it the split
        // columns keep carrying load through bonds that are compressed (bond-based bonds break
        // only in tension) while the closure concentrates at the plate–specimen interface, so
        // the stress climbs again: that branch is reported apart (max_stress), not as strength.
        r.last_stress = stress;
        r.stresses.push_back(stress);
        r.strains.push_back(strain);
        if (!r.failed && stress > r.peak_stress) {
          r.peak_stress = stress;
          r.peak_strain = strain;
        }
        const bool was_failed = r.failed;
        r.failed = r.failed || stress < (1.0 - failure_drop) * r.peak_stress;
        // The damage just before and just after the failure (the paper's Figure 23).
        if (!dir.empty() && !r.failed && stress >= r.peak_stress) {
          write_vtu(dir / "compression-cube-peak.vtu", sim);
        }
        if (!dir.empty() && r.failed && !was_failed) {
          write_vtu(dir / "compression-cube-failure.vtu", sim);
        }
        if (stress > r.max_stress) {
          r.max_stress = stress;
          r.max_strain = strain;
        }
        const Json zones = damage_by_zone(sim.model(), spacing);
        const std::size_t broken = quasi_static::broken_bonds(sim.model());
        Json row;
        row["strain"] = strain;
        row["stress"] = stress;
        row["broken_bonds"] = broken;
        row["damage"] = zones;
        evolution.push_back(row);
        return fmt::format("{},{:.5f},{:.4f},{:.4f},{:.5f},{},{:.4f},{:.4f},{:.4f},{},{:.3e},{}",
                           inc.index, 100 * strain, 1e-6 * stress, 1e-6 * stress_bottom,
                           100 * measured, broken, *zones.find("free_faces")->number(),
                           *zones.find("plate_faces")->number(), *zones.find("core")->number(),
                           inc.iterations, inc.residual, inc.converged ? 1 : 0);
      });
  const auto outcome = quasi_static::run(model, scene.solver, scene.initial, st, std::ref(record));
  r.completed = outcome.completed;
  r.json["peak_stress_MPa"] = 1e-6 * r.peak_stress;
  r.json["peak_strain_percent"] = 100 * r.peak_strain;
  r.json["final_stress_MPa"] = 1e-6 * r.last_stress;
  r.json["failed"] = r.failed;
  r.json["max_stress_after_failure_branch_MPa"] = 1e-6 * r.max_stress;
  r.json["max_stress_strain_percent"] = 100 * r.max_strain;
  record_outcome(r.json, outcome, false);
  if (full) {
    r.json["evolution"] = evolution;
  }
  return r;
}

} // namespace

/// compression-cube-static: the main run's curve by the static solver with break events beside
/// the same curve by ADR, in one run (docs/theory/quasi-brittle.md, "Static against ADR").
Json run_compression_cube_static(const Context& ctx) {
  const auto start = std::chrono::steady_clock::now();
  const Scene scene = load_scene((ctx.folder / "compression-cube.yaml").string());
  Json out;
  out["case"] = "compression-cube-static";
  out["quantity"] = "stress-strain curve by the static solver with break events vs ADR";
  const std::filesystem::path dir = ctx.output_dir / "compression-cube-static";
  std::filesystem::create_directories(dir / "adr");
  std::filesystem::create_directories(dir / "static");
  CubeRun stat = run_cube(scene, dir / "static", true, ctx.progress, quasi_static::Method::static_);
  CubeRun adr = run_cube(scene, dir / "adr", true, ctx.progress, quasi_static::Method::adr);
  out["static"] = stat.json;
  out["adr"] = adr.json;
  Json c = compare_with_adr(adr.stresses, stat.stresses, adr.strains, failure_drop);
  c["static_wall_seconds"] = *stat.json.find("wall_seconds")->number();
  c["adr_wall_seconds"] = *adr.json.find("wall_seconds")->number();
  fmt::print("   static vs ADR: peak {:.2f} vs {:.2f} MPa ({:+.1f} %) at {:.4f} vs {:.4f} %, "
             "curve difference to the peak {:.1f} % of the ADR peak; {:.0f} s vs {:.0f} s\n",
             1e-6 * *c.find("static_peak")->number(), 1e-6 * *c.find("adr_peak")->number(),
             100 * *c.find("peak_difference")->number(), 100 * *c.find("static_peak_at")->number(),
             100 * *c.find("adr_peak_at")->number(),
             100 * *c.find("largest_curve_difference_to_peak")->number(),
             *c.find("static_wall_seconds")->number(), *c.find("adr_wall_seconds")->number());
  out["comparison"] = c;
  finish_case(out, {gate_static_against_adr(out, c)}, stat.completed && adr.completed, start);
  return out;
}

Json run_compression_cube(const Context& ctx) {
  const auto start = std::chrono::steady_clock::now();
  Scene scene = load_scene((ctx.folder / "compression-cube.yaml").string());
  const double E = concrete(scene).youngs_modulus;
  const double delta = scene.model.lattice.horizon();
  const double s0 = concrete(scene).critical_stretch.value_or(0.0);
  const double s0_rule = ec2_tensile_strength / E;
  const double gf = model_code_fracture_energy();
  const double s0_gf = critical_stretch_from_fracture_energy(scene.model.dimension, E, delta, gf);
  Json out;
  out["case"] = "compression-cube";
  out["quantity"] = "stress-strain curve, peak stress and strain vs the paper and Eurocode 2";
  Json& deriv = out["critical_stretch_derivation"];
  deriv["rule"] = "s0 = f_ctm / E (as rc-beam); alternative: eq. 11 with G_F of fib MC2010";
  deriv["f_ctm"] = ec2_tensile_strength;
  deriv["E"] = E;
  deriv["horizon"] = delta;
  deriv["s0_from_f_ctm"] = s0_rule;
  deriv["s0_scene"] = s0;
  deriv["G_F_model_code"] = gf;
  deriv["s0_from_G_F_eq11"] = s0_gf;
  const bool s0_consistent = std::abs(s0 / s0_rule - 1.0) < 1e-3;

  const std::filesystem::path dir = ctx.output_dir / "compression-cube";
  std::filesystem::create_directories(dir);
  CubeRun main = run_cube(scene, dir, true, ctx.progress);
  fmt::print("   s0 = {:.4e}: peak {:.2f} MPa at {:.3f} % ({:.0f} s)\n", s0,
             1e-6 * main.peak_stress, 100 * main.peak_strain,
             *main.json.find("wall_seconds")->number());
  std::fflush(stdout);
  out["run"] = main.json;
  out["pd"]["peak_stress_MPa"] = 1e-6 * main.peak_stress;
  out["pd"]["peak_strain_percent"] = 100 * main.peak_strain;
  out["reference"]["paper_peak_stress_MPa"] = 1e-6 * paper_peak_stress;
  out["reference"]["paper_peak_strain_percent"] = 100 * paper_peak_strain;
  out["reference"]["ec2_peak_stress_MPa"] = 1e-6 * ec2_peak_stress;
  out["reference"]["ec2_peak_strain_percent"] = 100 * ec2_peak_strain;
  out["error"]["peak_stress_vs_paper"] = main.peak_stress / paper_peak_stress - 1.0;
  out["error"]["peak_strain_vs_paper"] = main.peak_strain / paper_peak_strain - 1.0;
  out["error"]["peak_stress_vs_ec2"] = main.peak_stress / ec2_peak_stress - 1.0;
  out["error"]["peak_strain_vs_ec2"] = main.peak_strain / ec2_peak_strain - 1.0;

  // The brittle peak grows in proportion to s0 (the sweep shows it), so the s0 the paper's peak
  // implies is s0 × 72.9 MPa / peak. Its run checks what was not fitted: the strain at the peak.
  const double s0_paper = main.peak_stress > 0 ? s0 * paper_peak_stress / main.peak_stress : s0;
  deriv["s0_scaled_to_paper_peak"] = s0_paper;
  deriv["G0_eq11_for_s0_scaled_to_paper_peak"] = std::numbers::pi *
                                                 micromodulus(scene.model.dimension, E, delta) *
                                                 std::pow(delta, 5) * s0_paper * s0_paper / 10.0;
  Json sweep = Json::array();
  for (const auto& [label, value] :
       std::vector<std::pair<std::string, double>>{{"0.8 f_ctm/E", 0.8 * s0_rule},
                                                   {"1.2 f_ctm/E", 1.2 * s0_rule},
                                                   {"eq. 11, G_F", s0_gf},
                                                   {"scaled to the paper's peak", s0_paper}}) {
    Scene s = scene;
    concrete(s).critical_stretch = value;
    CubeRun r = run_cube(s, {}, false, ctx.progress);
    r.json["s0"] = value;
    r.json["label"] = label;
    r.json["peak_change"] = peak_change(r.peak_stress, main.peak_stress);
    fmt::print("   s0 = {:.4e} ({}): peak {:.2f} MPa at {:.3f} % ({:.0f} s)\n", value, label,
               1e-6 * r.peak_stress, 100 * r.peak_strain, *r.json.find("wall_seconds")->number());
    std::fflush(stdout);
    sweep.push_back(r.json);
  }
  out["s0_sensitivity"] = sweep;

  // Resolution: λ = 15 mm and 7.5 mm beside the 10 mm of the main run (7.5 mm gives 8,800
  // particles, the paper's 8,425). Plates stay one particle layer thick.
  Json resolution = Json::array();
  for (double spacing : {0.015, 0.0075}) {
    Scene s = scene;
    s.model.lattice.spacing = spacing;
    s.model.bodies.at(1).region.boxes = {Box{{0, 0, -spacing}, {side, side, 0}}};
    s.model.bodies.at(2).region.boxes = {Box{{0, 0, side}, {side, side, side + spacing}}};
    s.model.supports.at(0).region = s.model.bodies.at(1).region;
    s.model.supports.at(1).region = s.model.bodies.at(2).region;
    CubeRun r = run_cube(s, {}, false, ctx.progress);
    r.json["spacing"] = spacing;
    r.json["peak_change"] = peak_change(r.peak_stress, main.peak_stress);
    fmt::print("   λ = {:.4g} m: peak {:.2f} MPa at {:.3f} % ({:.0f} s)\n", spacing,
               1e-6 * r.peak_stress, 100 * r.peak_strain, *r.json.find("wall_seconds")->number());
    std::fflush(stdout);
    resolution.push_back(r.json);
  }
  out["resolution"] = resolution;
  finish_case(out, {{"peak_stress_vs_ec2", ec2_mean_over_characteristic / ec2_peak_stress}},
              main.completed && s0_consistent && main.peak_stress > 0 && main.failed, start);
  return out;
}

PD_VERIFICATION_RUN("compression-cube", run_compression_cube);
PD_VERIFICATION_RUN("compression-cube-static", run_compression_cube_static);

} // namespace pd::verification
