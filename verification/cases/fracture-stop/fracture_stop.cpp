// fracture-stop (issues 19, 36): a glass plate with a pre-crack pulled quasi-statically to
// failure stops on solver.stop_when with status `failed`, the failure load the peak of the grip's
// reaction, within 5 % of Griffith's load for this plate: LEFM with the FE compliance of the same
// gripped plate (fe_compliance.hpp), which is the width correction made exact for its height and
// grips. Feddersen's formula, for an infinitely long plate under uniform stress, is reported
// beside.
#include "fe_compliance.hpp"
#include "libpd/app/run.hpp"
#include "libpd/io/scene.hpp"
#include "verification.hpp"

#include <chrono>
#include <cmath>
#include <fmt/format.h>

namespace pd::verification {

namespace {

Json run_fracture_stop(const Context& ctx) {
  const auto start = std::chrono::steady_clock::now();
  Json out;
  out["case"] = "fracture-stop";
  out["quantity"] = "failure load of a pre-cracked glass plate from the grip's reaction";
  const auto scene_file = ctx.scenes_dir / "user/fracture-centre-crack.yaml";
  const Scene s = load_scene(scene_file.string());
  const RunOutcome r = run_case_scene(ctx, s, "fracture-stop");
  out["status"] = to_string(r.result.status);
  out["message"] = r.result.message;
  const double width = s.model.bodies.at(0).region.boxes.at(0).hi[0];
  const double thickness = s.model.dimension.thickness;
  const double a = crack_half_length(s);
  const Material& m = s.model.materials.at(0);
  // Feddersen: K_I = σ √(π a) F(a/W), F = √(sec(π a / W)) (Tada's handbook, within 0.3 % for
  // a/W ≤ 0.35), plane stress, so σ_f = √(E G / (π a)) / F. The scene loads the plate
  // quasi-statically (static with damage), so its failure load is that of equilibrium states and
  // depends on neither a ramp rate nor the number of load levels.
  const double pi = 3.141592653589793;
  const double infinite = std::sqrt(m.youngs_modulus * m.fracture_energy.value_or(0) / (pi * a));
  const double feddersen = infinite / std::sqrt(1 / std::cos(pi * a / width));
  const auto grip = [&](const char* name) {
    for (const SupportSpec& support : s.model.supports) {
      if (support.name == name) {
        return support.displacement[1];
      }
    }
    throw std::runtime_error(std::string("fracture-stop: the scene has no support ") + name);
  };
  const ComplianceGriffith fe = griffith_load_from_fe_compliance(
      scene_file, s, "force", grip("top") - grip("bottom"), ctx.output_dir / "fe-compliance");
  const double griffith = fe.failure_load / (width * thickness);
  const double stress = r.stop_peak / (width * thickness);
  out["griffith_stress_infinite_plate"] = infinite;
  out["griffith_stress_feddersen"] = feddersen;
  out["griffith_stress"] = griffith;
  out["griffith_stress_fe_levels"] = [&] {
    Json levels = Json::array();
    for (const double load : fe.level_loads) {
      levels.push_back(load / (width * thickness));
    }
    return levels;
  }();
  out["fe_crack_step"] = fe.crack_step;
  out["plate_width"] = width;
  out["failure_load"] = r.stop_peak;
  out["failure_stress"] = stress;
  out["error"] = stress / griffith - 1;
  out["error_against_feddersen"] = stress / feddersen - 1;
  fmt::print("   status {}: {}\n   failure stress {:.4g} MPa, Griffith for this plate (FE "
             "compliance) {:.4g} MPa: {:+.1f} % (Feddersen's long plate {:.4g} MPa: {:+.1f} %)\n",
             to_string(r.result.status), r.result.message, stress / 1e6, griffith / 1e6,
             100 * (stress / griffith - 1), feddersen / 1e6, 100 * (stress / feddersen - 1));
  finish_case(out,
              "the run ends with status failed (solver.stop_when) and the failure stress is "
              "within 5 % of Griffith's for this plate (FE compliance)",
              r.result.status == RunStatus::failed && relative_error(stress, griffith) <= 0.05,
              start);
  return out;
}

} // namespace

PD_VERIFICATION_RUN("fracture-stop", run_fracture_stop);

} // namespace pd::verification
