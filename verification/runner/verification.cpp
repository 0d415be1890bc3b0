#include "verification.hpp"

#include "libpd/app/output_folder.hpp"

#include <cmath>
#include <cstdlib>
#include <optional>
#include <utility>

#ifndef PD_SOURCE_SCENES_DIR
#define PD_SOURCE_SCENES_DIR "verification/scenes"
#endif

namespace pd::verification {

RunOptions case_run_options(const Context& ctx, const std::string& name) {
  RunOptions opt;
  opt.output_dir = ctx.output_dir / name;
  opt.progress = ctx.progress;
  opt.overwrite = true;
  // A case folder is pd's own: files of a run from before manifests are its own too.
  std::error_code ec;
  if (!std::filesystem::exists(opt.output_dir / OutputFolder::manifest_name, ec)) {
    for (const auto& entry : std::filesystem::directory_iterator(opt.output_dir, ec)) {
      if (entry.is_regular_file() && is_run_output_name(entry.path().filename().string())) {
        std::filesystem::remove(entry.path(), ec);
      }
    }
  }
  return opt;
}

RunOutcome run_case_scene(const Context& ctx, const Scene& s, const std::string& run_name) {
  RunOptions options = case_run_options(ctx, run_name);
  options.write_vtu = false;
  return run_scene(s, options);
}

double crack_half_length(const Scene& s) {
  const Crack& c = s.model.cracks.at(0);
  return 0.5 * std::abs(c.vertices[1][0] - c.vertices[0][0]);
}

std::filesystem::path default_scenes_dir() {
  if (const char* env = std::getenv("PD_SCENES_DIR")) {
    return env;
  }
  return PD_SOURCE_SCENES_DIR;
}

double relative_error(double value, double reference) {
  return std::abs(value - reference) / std::abs(reference);
}

bool within_gates(const Json& out, const std::vector<Gate>& gates) {
  for (const Gate& g : gates) {
    const bool floor = g.key.starts_with("min_");
    const Json* group = out.find(floor ? "pd" : "error");
    const Json* value = group ? group->find(floor ? g.key.substr(4) : g.key) : nullptr;
    const std::optional<double> v = value ? value->number() : std::nullopt;
    if (!v || !std::isfinite(*v) || !(floor ? *v >= g.limit : std::abs(*v) <= g.limit)) {
      return false;
    }
  }
  return true;
}

void finish_case(Json& out, const std::string& gate, bool passed,
                 std::chrono::steady_clock::time_point start) {
  out["gate"] = gate;
  out["passed"] = passed;
  out["wall_seconds"] =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void finish_case(Json& out, const std::vector<Gate>& gates, bool passed,
                 std::chrono::steady_clock::time_point start) {
  Json& object = out["gate"] = Json::object();
  for (const Gate& g : gates) {
    object[g.key] = g.limit;
  }
  out["passed"] = passed && within_gates(out, gates);
  out["wall_seconds"] =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

} // namespace pd::verification
