// symmetry-half-full (issue 19): a half model on a symmetry plane against the full model, for the
// plate of Miranda §5.1.2 (plate-3clamped, symmetric about x = 2) and a clamped plate with a hole
// the plane cuts (plate-hole-clamped, symmetric about y = 0.1). The half model's energy is exactly
// half the full model's, so the two agree to the direct solver's round-off; the gate of 1e-6
// leaves room for its residual (5e-8 of the load) and nothing else. It caught a ghost fit that
// chose among equally near sources by index (0.3 % at the hole) and images whose sources were
// themselves dependants (0.01 % at the clamped plate's centre).
#include "libpd/app/run.hpp"
#include "libpd/io/scene.hpp"
#include "verification.hpp"

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fmt/format.h>
#include <map>
#include <string>

namespace pd::verification {

namespace {

std::map<std::string, double> run_probes(const Context& ctx, const std::filesystem::path& scene,
                                         const std::string& run_name) {
  const RunOutcome out = run_case_scene(ctx, load_scene(scene.string()), run_name);
  if (out.result.status == RunStatus::unstable) {
    throw std::runtime_error(scene.filename().string() + ": " + out.result.message);
  }
  return out.probes;
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
      run_probes(ctx, ctx.folder / "../plate-3clamped/plate-3clamped.yaml",
                 "symmetry-half-full/full"),
      run_probes(ctx, ctx.scenes_dir / "user/plate-3clamped-half.yaml", "symmetry-half-full/half"),
      worst);
  out["plate-hole-clamped"] =
      compare_half_full(run_probes(ctx, ctx.scenes_dir / "user/plate-hole-clamped.yaml",
                                   "symmetry-half-full/hole-full"),
                        run_probes(ctx, ctx.scenes_dir / "user/plate-hole-clamped-half.yaml",
                                   "symmetry-half-full/hole-half"),
                        worst);
  out["largest_difference"] = worst;
  finish_case(out,
              "plate-3clamped and plate-hole-clamped: every probe of the half model within 1e-6 "
              "of the full model",
              worst <= 1e-6, start);
  return out;
}

PD_VERIFICATION_RUN("symmetry-half-full", run_symmetry_half_full);

} // namespace pd::verification
