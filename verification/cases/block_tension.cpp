// block-tension (Pasupathy, Table 1): 1 × 0.1 × 0.1 m block, left end held, 200 MPa on the right
// end. Uniaxial stress gives u_x(x) = σx/E along the centre line and a lateral strain −νσ/E with
// the bond-based ν = 1/4. Without surface correction the outer particles are too soft, so the
// block stretches more than σL/E; the error is reported, the gate comes with the corrections.
#include "cases.hpp"
#include "libpd/run.hpp"
#include "libpd/scene.hpp"

#include <fmt/format.h>

namespace pd::verification {

Json run_block_tension(const Context& ctx) {
  const Scene scene = load_scene((ctx.scenes_dir / "block-tension.yaml").string());
  RunOptions opt;
  opt.output_dir = ctx.output_dir / "block-tension";
  opt.progress = ctx.progress;
  const RunOutcome run = run_scene(scene, opt);

  const double E = scene.model.materials.front().youngs_modulus;
  const double sigma = scene.model.loads.front().load.value[0];
  const double nu = 0.25; // bond-based PD in 3D
  const double x_end = 0.995, x_mid = 0.495, width = 0.09;
  const double elongation_ref = sigma * x_end / E;
  const double mid_ref = sigma * x_mid / E;
  const double lateral_ref = -nu * sigma / E;
  const double elongation = run.probes.at("end_displacement");
  const double mid = run.probes.at("mid_displacement");
  const double lateral = (run.probes.at("mid_top_y") - run.probes.at("mid_bottom_y")) / width;

  Json out;
  out["case"] = "block-tension";
  out["quantity"] = "centre-line u_x at x = 0.995 m and lateral strain at mid-length";
  out["pd"]["end_displacement"] = elongation;
  out["pd"]["mid_displacement"] = mid;
  out["pd"]["lateral_strain"] = lateral;
  out["reference"]["end_displacement"] = elongation_ref;
  out["reference"]["mid_displacement"] = mid_ref;
  out["reference"]["lateral_strain"] = lateral_ref;
  out["error"]["elongation"] = relative_error(elongation, elongation_ref);
  out["error"]["mid_displacement"] = relative_error(mid, mid_ref);
  out["error"]["lateral_contraction"] = relative_error(lateral, lateral_ref);
  out["gate"] = "none yet: reported only (gates arrive with the surface-correction issue)";
  out["steady_state"]["status"] = to_string(run.result.status);
  out["steady_state"]["residual"] = run.result.residual;
  out["run"] = run.summary;
  out["passed"] = run.result.status == RunStatus::converged;
  fmt::print(
      "   u_x(0.995) = {:.6e} m vs sigma x/E = {:.6e} m (error {:.2f} %); lateral strain {:.4e} "
      "vs {:.4e} (error {:.2f} %); {} after {} steps\n",
      elongation, elongation_ref, 100 * relative_error(elongation, elongation_ref), lateral,
      lateral_ref, 100 * relative_error(lateral, lateral_ref), to_string(run.result.status),
      run.result.steps);
  return out;
}

} // namespace pd::verification
