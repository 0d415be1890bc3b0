// fracture-stop (issue 19): a glass plate with a pre-crack pulled to failure stops on
// solver.stop_when with status `failed`, the failure load the peak of the grip's reaction.
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

} // namespace

PD_VERIFICATION_RUN("fracture-stop", run_fracture_stop);

} // namespace pd::verification
