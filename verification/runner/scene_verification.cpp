#include "scene_verification.hpp"

#include "libpd/app/run.hpp"
#include "libpd/core/atomic_file.hpp"
#include "libpd/io/scene.hpp"

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fmt/format.h>
#include <stdexcept>
#include <sys/wait.h>
#include <yaml-cpp/yaml.h>

namespace pd::verification {

namespace {

std::filesystem::path default_pd_fem() {
  if (const char* env = std::getenv("PD_FEM"); env != nullptr && *env != '\0') {
    return env;
  }
  std::error_code ec;
  const auto self = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::filesystem::path("pd-fem") : self.parent_path() / "pd-fem";
}

std::string quoted(const std::string& s) {
  std::string out = "'";
  for (char c : s) {
    out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  }
  return out + "'";
}

/// Runs pd-fem on the scene into `dir`; returns its fe.json.
YAML::Node run_fe(const std::filesystem::path& scene, const std::filesystem::path& dir,
                  const SceneVerifyOptions& o) {
  const auto exe = o.pd_fem.empty() ? default_pd_fem() : o.pd_fem;
  if (!std::filesystem::exists(exe)) {
    throw std::runtime_error(
        fmt::format("no FE reference: {} does not exist (libpd was built without deal.II, "
                    "LIBPD_WITH_FEM_REFERENCE=OFF; or set PD_FEM to the pd-fem executable)",
                    exe.string()));
  }
  std::string command = fmt::format("{} --scene {} -o {}", quoted(exe.string()),
                                    quoted(scene.string()), quoted(dir.string()));
  if (o.fe_levels) {
    command += fmt::format(" --levels {}", *o.fe_levels);
  }
  if (o.fe_coarse) {
    command += " --coarse";
  }
  const int status = std::system(command.c_str());
  if (status != 0) {
    throw std::runtime_error(fmt::format("pd-fem failed (exit status {}): {}",
                                         WIFEXITED(status) ? WEXITSTATUS(status) : status,
                                         command));
  }
  const auto file = dir / "fe.json";
  try {
    return YAML::LoadFile(file.string());
  } catch (const YAML::Exception& e) {
    throw std::runtime_error("cannot read " + file.string() + ": " + e.msg);
  }
}

} // namespace

Json verify_scene(const std::filesystem::path& scene_path, const Context& ctx,
                  const SceneVerifyOptions& options) {
  const Scene scene = load_scene(scene_path.string());
  const std::string name = scene_path.stem().string();
  const auto dir = ctx.output_dir / name;
  RunOptions run;
  run.output_dir = dir / "pd";
  run.overwrite = true;
  run.progress = ctx.progress;
  run.write_vtu = false;
  const RunOutcome pd = run_scene(scene, run);
  if (pd.result.status == RunStatus::unstable) {
    throw std::runtime_error("the PD run became unstable: " + pd.result.message);
  }
  const auto t0 = std::chrono::steady_clock::now();
  const YAML::Node fe = run_fe(std::filesystem::absolute(scene_path), dir / "fe", options);
  const double fe_wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  Json out;
  out["scene"] = scene_path.string();
  out["title"] = scene.title;
  out["pd_status"] = to_string(pd.result.status);
  out["pd_seconds"] = pd.setup_seconds + pd.result.wall_seconds;
  out["pd_particles"] = pd.particles;
  out["pd_bond_updates"] =
      static_cast<double>(pd.bonds) * static_cast<double>(pd.result.force_evaluations);
  out["fe_seconds"] = fe_wall;
  out["fe_model"] = fe["model"] ? fe["model"].as<std::string>() : std::string();
  bool complete = true;
  double worst = 0;
  Json& rows = out["probes"];
  rows = Json::array();
  fmt::print("   {:<20} {:>15} {:>15} {:>10} {:>12}\n", "probe", "PD", "FE", "PD vs FE",
             "FE error est");
  for (const ProbeSpec& p : scene.probes) {
    const auto value = pd.probes.find(p.name);
    YAML::Node row_fe;
    for (const YAML::Node& r : fe["probes"]) {
      if (r["name"].as<std::string>() == p.name) {
        row_fe = r;
      }
    }
    Json row;
    row["name"] = p.name;
    row["quantity"] = std::string(name_of(p.quantity));
    if (value == pd.probes.end() || !row_fe) {
      row["note"] = "no FE value for this probe";
      complete = false;
      rows.push_back(row);
      fmt::print("   {:<20} (no FE value)\n", p.name);
      continue;
    }
    const double v_pd = value->second;
    const double v_fe = row_fe["value"].as<double>();
    const double estimate = row_fe["error_estimate"] && !row_fe["error_estimate"].IsNull()
                                ? row_fe["error_estimate"].as<double>()
                                : std::nan("");
    const double relative = (v_pd - v_fe) / std::abs(v_fe);
    worst = std::max(worst, std::abs(relative));
    row["pd"] = v_pd;
    row["fe"] = v_fe;
    row["relative_difference"] = relative;
    row["fe_error_estimate"] = estimate;
    row["fe_relative_error_estimate"] = estimate / std::abs(v_fe);
    rows.push_back(row);
    fmt::print("   {:<20} {:>15.8g} {:>15.8g} {:>+9.3f}% {:>11.3g}%\n", p.name, v_pd, v_fe,
               100 * relative, 100 * estimate / std::abs(v_fe));
  }
  fmt::print("   PD {:.2f} s ({} particles), FE {:.2f} s\n",
             pd.setup_seconds + pd.result.wall_seconds, pd.particles, fe_wall);
  out["largest_relative_difference"] = worst;
  bool passed = complete;
  if (options.gate) {
    out["gate"] = *options.gate;
    passed = passed && worst <= *options.gate;
  }
  out["passed"] = passed;
  return out;
}

} // namespace pd::verification
