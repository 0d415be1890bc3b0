#include "scene_verification.hpp"

#include "libpd/app/run.hpp"
#include "libpd/core/atomic_file.hpp"
#include "libpd/core/child_process.hpp"
#include "libpd/io/scene.hpp"

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fmt/format.h>
#include <map>
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

/// Where a probe's own value is small, the gate judges its difference against this fraction of
/// the largest value of the same quantity among the scene's probes.
constexpr double probe_floor_fraction = 0.1;

/// Bond-based PD represents one ν per setting (material.hpp); a scene that gives another one
/// would be verified against an FE solution of a different material, so it is refused.
void require_representable_poisson_ratio(const Scene& scene) {
  if (scene.model.effects.bond_model != BondModel::micro_elastic) {
    return;
  }
  const auto represented = bond_based_poisson_ratio(scene.model.dimension);
  for (const Material& m : scene.model.materials) {
    if (represented && std::abs(m.poisson_ratio - *represented) > 1e-9) {
      throw std::runtime_error(fmt::format(
          "{}: material '{}' gives poisson_ratio {} but bond-based PD represents {:.6g} here, "
          "so PD and FE would solve different problems; remove poisson_ratio (the model's own "
          "ν is then used by both) or use model.bond_model: virtual-fibres, which honours it",
          scene.path, m.name, m.poisson_ratio, *represented));
    }
  }
}

/// The FE's record of its materials (fe.json `materials`) against PD's: the same E and ν.
std::string material_mismatch(const Scene& scene, const YAML::Node& fe) {
  if (!fe["materials"]) {
    return "fe.json records no materials";
  }
  for (const YAML::Node& row : fe["materials"]) {
    const auto name = row["name"].as<std::string>();
    for (const Material& m : scene.model.materials) {
      if (m.name == name &&
          (row["youngs_modulus"].as<double>() != m.youngs_modulus * m.stiffness_factor ||
           row["poisson_ratio"].as<double>() != m.poisson_ratio)) {
        return fmt::format("material '{}': PD E = {}, ν = {}; FE E = {}, ν = {}", name,
                           m.youngs_modulus * m.stiffness_factor, m.poisson_ratio,
                           row["youngs_modulus"].as<double>(), row["poisson_ratio"].as<double>());
      }
    }
  }
  return {};
}

/// Per quantity (displacement, stress, reaction), the largest |FE value| among the probes: a
/// probe whose own value is near zero (σ_xx beside a hole) is judged against a tenth of it.
std::map<std::string, double> quantity_scales(const Scene& scene, const YAML::Node& fe) {
  std::map<std::string, double> scale;
  for (const ProbeSpec& p : scene.probes) {
    for (const YAML::Node& r : fe["probes"]) {
      if (r["name"].as<std::string>() == p.name) {
        double& s = scale[std::string(name_of(p.quantity))];
        s = std::max(s, std::abs(r["value"].as<double>()));
      }
    }
  }
  return scale;
}

/// A probe's row in the scene's JSON: its name and quantity, and for a point of a line probe the
/// line, its index and distance along it (the report plots the line's points as a profile).
Json probe_row(const ProbeSpec& p) {
  Json row;
  row["name"] = p.name;
  row["quantity"] = std::string(name_of(p.quantity));
  if (!p.line.empty()) {
    row["line"] = p.line;
    row["line_index"] = p.line_index;
    row["line_distance"] = p.line_distance;
  }
  return row;
}

/// One probe's line of the table: PD, FE, their difference and the FE's own error estimate
/// (none when the FE ran on one level: the next would not fit in memory, or --fe-levels 1).
void print_probe_row(const std::string& name, double v_pd, double v_fe, double relative,
                     double estimate) {
  const std::string shown = std::isfinite(estimate)
                                ? fmt::format("{:>11.3g}%", 100 * estimate / std::abs(v_fe))
                                : fmt::format("{:>12}", "none");
  fmt::print("   {:<20} {:>15.8g} {:>15.8g} {:>+9.3f}% {}\n", name, v_pd, v_fe, 100 * relative,
             shown);
}

/// What each side made of the scene: PD's bodies (a mesh body names its file) and the FE's
/// domain and meshes, as fe.json states them, so a verdict says which continuum it compares.
void describe_sides(const Scene& scene, const YAML::Node& fe, Json& out) {
  Json& bodies = out["pd_bodies"];
  bodies = Json::array();
  for (const BodySpec& b : scene.model.bodies) {
    Json row;
    row["name"] = b.name;
    row["source"] = b.mesh ? std::string(b.mesh_is_geometry ? "geometry " : "mesh ") + b.mesh_file
                    : b.points ? std::string("particles")
                               : std::string("lattice");
    if (b.mesh) {
      row["fill"] = std::string(name_of(b.fill));
    }
    bodies.push_back(row);
  }
  if (fe["domain"] && fe["domain"]["description"]) {
    out["fe_domain"] = fe["domain"]["description"].as<std::string>();
    fmt::print("   FE: {}\n", fe["domain"]["description"].as<std::string>());
  }
  fmt::print("   PD: {}\n", scene.solver.small_displacements
                                ? "small displacements (bond forces linearised), as the FE"
                                : "finite displacements (the scene's effects need them); the FE "
                                  "is linear");
}

/// The FE solves linear elasticity: PD solves the same small-displacement problem where its
/// model allows (elastic bonds), without the rotation stiffening of the finite stretch (the
/// double cantilever's opened arms: 2.4 % of its force).
void solve_small_displacements_where_the_model_allows(Scene& scene) {
  scene.solver.small_displacements =
      scene.solver.small_displacements || scene.model.effects.elastic_bonds_only();
}

/// Why PD's result cannot be compared with the FE's: different materials, a PD state that is
/// not an equilibrium, a probe missing on one side.
std::vector<std::string> why_not_comparable(const Scene& scene, const YAML::Node& fe,
                                            RunStatus pd_status, bool complete) {
  std::vector<std::string> reasons;
  if (const std::string mismatch = material_mismatch(scene, fe); !mismatch.empty()) {
    reasons.push_back("PD and FE did not solve the same materials: " + mismatch);
  }
  if (pd_status != RunStatus::converged) {
    reasons.push_back(fmt::format(
        "the PD run ended with status '{}', not at an equilibrium: a transient or unconverged "
        "state is not a verified result (solve statically, or set solver.steady)",
        to_string(pd_status)));
  }
  if (!complete) {
    reasons.push_back("a probe has no FE value");
  }
  return reasons;
}

/// Why a scene with a comparable PD and FE gets no verdict, empty if it gets one: no tolerance,
/// or an FE reference whose own error estimate for some probe exceeds half the tolerance (too
/// coarse to tell PD's error from its own; --fe-coarse on a scene with small supports: 2.2 %).
std::string why_not_judged(const Json& out, const SceneVerifyOptions& options) {
  if (!options.gate) {
    return "no --gate";
  }
  for (const Json& row : *out.find("probes")->items()) {
    const Json* estimate = row.find("fe_error_estimate");
    const Json* tolerance = row.find("tolerance");
    const double e = estimate != nullptr ? estimate->number().value_or(0.0) : 0.0;
    const double t = tolerance != nullptr ? tolerance->number().value_or(0.0) : 0.0;
    if (std::isfinite(e) && t > 0 && e > 0.5 * t) {
      return fmt::format("the FE's own error estimate for {}, {:.3g}, is more than half its "
                         "tolerance {:.3g}; refine the FE (without --fe-coarse, or more "
                         "--fe-levels)",
                         row.find("name")->text().value_or("a probe"), e, t);
    }
  }
  return {};
}

} // namespace

YAML::Node run_pd_fem(const std::filesystem::path& scene, const std::filesystem::path& dir,
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
  const int status = run_shell_command(command);
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

Json verify_scene(const std::filesystem::path& scene_path, const Context& ctx,
                  const SceneVerifyOptions& options) {
  Scene scene = load_scene(scene_path.string());
  require_representable_poisson_ratio(scene);
  solve_small_displacements_where_the_model_allows(scene);
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
  const YAML::Node fe = run_pd_fem(std::filesystem::absolute(scene_path), dir / "fe", options);
  const double fe_wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  Json out;
  out["scene"] = scene_path.string();
  out["title"] = scene.title;
  out["pd_status"] = to_string(pd.result.status);
  out["pd_small_displacements"] = scene.solver.small_displacements;
  out["pd_seconds"] = pd.setup_seconds + pd.result.wall_seconds;
  out["pd_particles"] = pd.particles;
  out["pd_bond_updates"] =
      static_cast<double>(pd.bonds) * static_cast<double>(pd.result.force_evaluations);
  out["fe_seconds"] = fe_wall;
  out["fe_model"] = fe["model"] ? fe["model"].as<std::string>() : std::string();
  describe_sides(scene, fe, out);
  // The materials PD's summary.json records, beside fe.json's: both solvers solved one problem.
  if (const Json* materials = pd.summary.find("materials")) {
    out["materials"] = *materials;
  }
  const std::map<std::string, double> scales = quantity_scales(scene, fe);
  bool complete = true;
  bool within = true;
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
    Json row = probe_row(p);
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
    // Relative to the FE value itself: + means PD is larger in magnitude, whatever the sign.
    const double relative = (v_pd - v_fe) / v_fe;
    // What the gate judges: the difference over the probe's value, or over a tenth of the
    // largest value of its quantity where the probe's own value is smaller than that.
    const double scale = std::max(std::abs(v_fe), probe_floor_fraction *
                                                      scales.at(std::string(name_of(p.quantity))));
    const double judged = std::abs(v_pd - v_fe) / scale;
    worst = std::max(worst, judged);
    row["pd"] = v_pd;
    row["fe"] = v_fe;
    row["relative_difference"] = relative;
    row["judged_difference"] = judged;
    if (options.gate) {
      row["tolerance"] = *options.gate * scale;
      row["within_tolerance"] = judged <= *options.gate;
      within = within && judged <= *options.gate;
    }
    row["fe_error_estimate"] = estimate;
    row["fe_relative_error_estimate"] = estimate / std::abs(v_fe);
    rows.push_back(row);
    print_probe_row(p.name, v_pd, v_fe, relative, estimate);
  }
  fmt::print("   PD {:.2f} s ({} particles), FE {:.2f} s\n",
             pd.setup_seconds + pd.result.wall_seconds, pd.particles, fe_wall);
  out["largest_judged_difference"] = worst;
  // A verdict needs the same problem on both sides, a PD state that is an equilibrium, every
  // probe on both sides, and a tolerance; without a tolerance the result is measured.
  std::vector<std::string> reasons = why_not_comparable(scene, fe, pd.result.status, complete);
  // Where PD and FE are comparable but the FE cannot judge (or there is no gate), the result is
  // measured, whatever the gate would say.
  const std::string not_judged = reasons.empty() ? why_not_judged(out, options) : std::string();
  if (options.gate) {
    out["gate"] = *options.gate;
    if (!within && not_judged.empty()) {
      reasons.push_back(
          fmt::format("a probe differs from FE by more than the gate {}", *options.gate));
    }
  }
  out["verdict"] = !reasons.empty() ? "failed" : not_judged.empty() ? "passed" : "measured";
  out["reasons"] = Json::array_of(reasons);
  out["passed"] = reasons.empty() && not_judged.empty();
  if (!not_judged.empty()) {
    out["not_judged"] = not_judged;
  }
  for (const std::string& why : reasons) {
    fmt::print("   not verified: {}\n", why);
  }
  return out;
}

} // namespace pd::verification
