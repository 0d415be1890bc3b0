// Cases on the scenes a new user writes (issue 19), beside `pd verify SCENE.yaml`, which compares
// any elastic scene with deal.II:
//
// * symmetry-half-full: a half model on a symmetry plane against the full model. The plate of
//   Miranda §5.1.2 (plate-3clamped, symmetric about x = 2) gates at 0.1 % (issue 19). The clamped
//   plate with a hole is reported beside it: where the plane cuts the hole, the ghosts inside the
//   hole are fitted from one side only in the half model (their images are not sources), so its
//   transverse displacement there differs by 0.3 % (measured), a limit of the construction and
//   not of the scene.
// * crack-opening: a plate with a central crack (a segment no bond crosses) against the closed
//   form of its opening, 4 σ a / E at the centre (Inglis/Griffith, plane stress), with σ from the
//   grip's reaction, at three spacings: the error must fall as the spacing does.
// * fracture-stop: a glass plate with a pre-crack pulled to failure stops on solver.stop_when with
//   status `failed`, the failure load the peak of the grip's reaction.
#include "cases.hpp"
#include "libpd/app/run.hpp"
#include "libpd/io/scene.hpp"

#include <chrono>
#include <cmath>
#include <fmt/format.h>
#include <map>
#include <string>

namespace pd::verification {

namespace {

/// A run of the case into its folder ctx.output_dir/run_name, without VTU files.
RunOutcome run_case_scene(const Context& ctx, const Scene& s, const std::string& run_name) {
  RunOptions options = case_run_options(ctx, run_name);
  options.write_vtu = false;
  return run_scene(s, options);
}

std::map<std::string, double> run_probes(const Context& ctx, const std::string& scene,
                                         const std::string& run_name) {
  const RunOutcome out =
      run_case_scene(ctx, load_scene((ctx.scenes_dir / scene).string()), run_name);
  if (out.result.status == RunStatus::unstable) {
    throw std::runtime_error(scene + ": " + out.result.message);
  }
  return out.probes;
}

/// Half the length of the scene's first crack (a segment along x).
double crack_half_length(const Scene& s) {
  const Crack& c = s.model.cracks.at(0);
  return 0.5 * std::abs(c.vertices[1][0] - c.vertices[0][0]);
}

/// half / full − 1 for every probe of the half model; reactions of the half carry half the load.
Json compare_half_full(const std::map<std::string, double>& full,
                       const std::map<std::string, double>& half, double& worst) {
  Json rows = Json::object();
  for (const auto& [name, value] : half) {
    const double factor = name.find("reaction") != std::string::npos ? 2.0 : 1.0;
    const double difference = factor * value / full.at(name) - 1.0;
    rows[name] = difference;
    worst = std::max(worst, std::abs(difference));
    fmt::print("   {:<24} full {:>14.8g}  half {:>14.8g}  half/full − 1 = {:+.2e}\n", name,
               full.at(name), factor * value, difference);
  }
  return rows;
}

} // namespace

Json run_symmetry_half_full(const Context& ctx) {
  const auto start = std::chrono::steady_clock::now();
  Json out;
  out["case"] = "symmetry-half-full";
  out["quantity"] = "half model on a symmetry plane / full model − 1, per probe";
  double worst = 0;
  out["plate-3clamped"] = compare_half_full(
      run_probes(ctx, "plate-3clamped.yaml", "symmetry-half-full/full"),
      run_probes(ctx, "user/plate-3clamped-half.yaml", "symmetry-half-full/half"), worst);
  out["largest_difference"] = worst;
  double hole_worst = 0;
  out["plate-hole-clamped (reported, not gated)"] = compare_half_full(
      run_probes(ctx, "user/plate-hole-clamped.yaml", "symmetry-half-full/hole-full"),
      run_probes(ctx, "user/plate-hole-clamped-half.yaml", "symmetry-half-full/hole-half"),
      hole_worst);
  out["hole_largest_difference"] = hole_worst;
  finish_case(out, "plate-3clamped: every probe of the half model within 0.1 % of the full model",
              worst <= 1e-3, start);
  return out;
}

Json run_crack_opening(const Context& ctx) {
  const auto start = std::chrono::steady_clock::now();
  Json out;
  out["case"] = "crack-opening";
  out["quantity"] = "crack opening at the centre / (4 σ a / E), σ = grip force / (W t)";
  const Scene base = load_scene((ctx.scenes_dir / "user/crack-plate-2d.yaml").string());
  const double a = crack_half_length(base);
  const double width = base.model.bodies.at(0).region.boxes.at(0).hi[0] -
                       base.model.bodies.at(0).region.boxes.at(0).lo[0];
  const double thickness = base.model.dimension.thickness;
  const double youngs = base.model.materials.at(0).youngs_modulus;
  Json& rows = out["runs"];
  rows = Json::array();
  std::vector<double> errors;
  // The scene's spacing, twice it and half of it: the grips and the probes are one layer / half
  // a spacing from their faces, so they move with the spacing.
  for (const double factor : {2.0, 1.0, 0.5}) {
    Scene s = base;
    const double h = base.model.lattice.spacing * factor;
    s.model.lattice.spacing = h;
    s.particles.reset();
    const double top = base.model.bodies[0].region.boxes[0].hi[1];
    const double mid = 0.5 * top;
    s.model.supports[0].region.boxes[0].hi[1] = h;
    s.model.supports[1].region.boxes[0].lo[1] = top - h;
    s.probes[0].point[1] = mid + 0.5 * h;
    s.probes[1].point[1] = mid - 0.5 * h;
    const RunOutcome r = run_case_scene(ctx, s, fmt::format("crack-opening/h{}", h));
    const double opening = r.probes.at("upper_face") - r.probes.at("lower_face");
    const double sigma = r.probes.at("grip_force") / (width * thickness);
    const double closed_form = 4 * sigma * a / youngs;
    const double error = opening / closed_form - 1;
    errors.push_back(error);
    Json row;
    row["spacing"] = h;
    row["a_over_spacing"] = a / h;
    row["particles"] = r.particles;
    row["opening"] = opening;
    row["closed_form"] = closed_form;
    row["error"] = error;
    row["wall_seconds"] = r.setup_seconds + r.result.wall_seconds;
    rows.push_back(row);
    fmt::print("   λ = {:g} m (a = {:.0f} λ): opening {:.5g} m, 4σa/E {:.5g} m, error {:+.2f} %\n",
               h, a / h, opening, closed_form, 100 * error);
  }
  const double order = std::log2((errors[0] - errors[1]) / (errors[1] - errors[2]));
  out["observed_order"] = order;
  out["note"] = "the closed form is the infinite plate's; this plate is 10 half-lengths wide "
                "with clamped grips one width apart, which the error keeps as λ → 0";
  const bool falling =
      std::abs(errors[2]) < std::abs(errors[1]) && std::abs(errors[1]) < std::abs(errors[0]);
  finish_case(out, "the error falls at every refinement", falling, start);
  return out;
}

Json run_fracture_stop(const Context& ctx) {
  const auto start = std::chrono::steady_clock::now();
  Json out;
  out["case"] = "fracture-stop";
  out["quantity"] = "failure load of a pre-cracked glass plate from the grip's reaction";
  const Scene s = load_scene((ctx.scenes_dir / "user/fracture-centre-crack.yaml").string());
  const RunOutcome r = run_case_scene(ctx, s, "fracture-stop");
  out["status"] = to_string(r.result.status);
  out["message"] = r.result.message;
  const double width = s.model.bodies.at(0).region.boxes.at(0).hi[0];
  const double a = crack_half_length(s);
  const Material& m = s.model.materials.at(0);
  // Griffith, plane stress: σ_f = √(E G / (π a)); reported beside the PD value, not gated: a is
  // a few spacings here and the ramp is not quasi-static.
  out["griffith_stress"] =
      std::sqrt(m.youngs_modulus * m.fracture_energy.value_or(0) / (3.141592653589793 * a));
  out["plate_width"] = width;
  out["failure_load"] = r.stop_peak;
  out["failure_stress"] = r.stop_peak / (width * s.model.dimension.thickness);
  fmt::print("   status {}: {}\n", to_string(r.result.status), r.result.message);
  finish_case(out, "the run ends with status failed (solver.stop_when), not unstable",
              r.result.status == RunStatus::failed, start);
  return out;
}

} // namespace pd::verification
