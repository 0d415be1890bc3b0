// crack-opening (issue 19): a plate with a central crack (a segment no bond crosses) against the
// closed form of its opening, 4 σ a / E at the centre (Inglis/Griffith, plane stress), with σ from
// the grip's reaction, at three spacings: the error must fall as the spacing does.
#include "libpd/app/run.hpp"
#include "libpd/io/scene.hpp"
#include "verification.hpp"

#include <chrono>
#include <cmath>
#include <fmt/format.h>
#include <string>
#include <vector>

namespace pd::verification {

namespace {

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

} // namespace

PD_VERIFICATION_RUN("crack-opening", run_crack_opening);

} // namespace pd::verification
