#include "fe_compliance.hpp"

#include "scene_verification.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <fmt/format.h>
#include <fstream>
#include <map>
#include <stdexcept>
#include <yaml-cpp/yaml.h>

namespace pd::verification {

namespace {

/// Mesh levels of each FE solve: two give the order-1 extrapolation; a third moved the
/// extrapolated load by 0.01 % on the fracture-stop plate.
constexpr int fe_levels = 2;
/// Each tip moves by this fraction of the crack's half-length: small enough for the central
/// difference (its error is second order), large against the FE's coarse mesh size.
constexpr double step_fraction = 0.1;

/// The elastic problem of the scene with the crack's tips (ends inside the body, `tip`) moved
/// outwards by `h` (inwards when negative): damage, stopping rules and output removed, the probes
/// `probes` kept.
std::filesystem::path write_elastic_variant(const std::filesystem::path& scene_file,
                                            const std::vector<std::string>& probes, double h,
                                            const std::array<bool, 2>& tip,
                                            const std::filesystem::path& file) {
  YAML::Node s = YAML::LoadFile(scene_file.string());
  // The variant is written elsewhere, so files the scene names relative to itself would be lost.
  for (const YAML::Node& body : s["bodies"]) {
    for (const char* key : {"mesh", "geometry", "particles"}) {
      if (body[key]) {
        throw std::runtime_error(
            fmt::format("{}: FE compliance of a body read from a file ('{}') is not supported yet",
                        scene_file.string(), key));
      }
    }
  }
  s.remove("effects");
  s.remove("output");
  YAML::Node solver;
  solver["integrator"] = "static";
  s["solver"] = solver;
  YAML::Node kept;
  for (const YAML::Node& p : s["probes"]) {
    if (std::find(probes.begin(), probes.end(), p["name"].as<std::string>()) != probes.end()) {
      kept.push_back(p);
    }
  }
  s["probes"] = kept;
  YAML::Node segment = s["cracks"][0]["segment"];
  const double x0 = segment[0][0].as<double>(), y0 = segment[0][1].as<double>();
  const double x1 = segment[1][0].as<double>(), y1 = segment[1][1].as<double>();
  const double length = std::hypot(x1 - x0, y1 - y0);
  const double ex = (x1 - x0) / length, ey = (y1 - y0) / length;
  if (tip[0]) {
    segment[0][0] = x0 - h * ex;
    segment[0][1] = y0 - h * ey;
  }
  if (tip[1]) {
    segment[1][0] = x1 + h * ex;
    segment[1][1] = y1 + h * ey;
  }
  std::filesystem::create_directories(file.parent_path());
  std::ofstream(file) << s << "\n";
  return file;
}

std::vector<double> probe_levels(const YAML::Node& fe, const std::string& probe) {
  for (const YAML::Node& p : fe["probes"]) {
    if (p["name"].as<std::string>() == probe) {
      return p["values"].as<std::vector<double>>();
    }
  }
  throw std::runtime_error("fe.json has no probe '" + probe + "'");
}

/// The crack's ends that are tips (inside a body; an end on the surface is the crack's mouth).
std::array<bool, 2> crack_tips(const Scene& scene) {
  if (scene.model.cracks.empty() || scene.model.cracks[0].vertices.size() != 2) {
    throw std::runtime_error("FE compliance: the scene's first crack must be a segment");
  }
  const auto& v = scene.model.cracks[0].vertices;
  const double inside = -1e-9 * scene.model.lattice.spacing;
  std::array<bool, 2> tip{false, false};
  for (std::size_t k = 0; k < 2; ++k) {
    for (const BodySpec& body : scene.model.bodies) {
      tip[k] = tip[k] || body.region.contains(v[k], scene.model.dimension.dim, inside);
    }
  }
  if (!tip[0] && !tip[1]) {
    throw std::runtime_error("FE compliance: neither end of the crack lies inside a body");
  }
  return tip;
}

/// Each probe's FE value on each mesh level with every tip moved by `shift`.
std::vector<std::vector<double>> loads_with_tips_moved(const std::filesystem::path& scene_file,
                                                       const std::vector<std::string>& probes,
                                                       double shift, const std::array<bool, 2>& tip,
                                                       const std::filesystem::path& dir) {
  SceneVerifyOptions options;
  options.fe_levels = fe_levels;
  const auto file = write_elastic_variant(scene_file, probes, shift, tip, dir / "scene.yaml");
  const YAML::Node fe = run_pd_fem(file, dir, options);
  std::vector<std::vector<double>> out;
  for (const std::string& probe : probes) {
    out.push_back(probe_levels(fe, probe));
  }
  return out;
}

/// pd-fem halves the mesh size from level to level: order-1 extrapolation to zero mesh size.
double extrapolated(const std::vector<double>& levels) {
  const auto n = levels.size();
  return n < 2 ? levels.back() : 2 * levels[n - 1] - levels[n - 2];
}

} // namespace

ComplianceGriffith griffith_load_from_fe_compliance(const std::filesystem::path& scene_file,
                                                    const Scene& scene, const std::string& probe,
                                                    double grip_opening,
                                                    const std::filesystem::path& dir) {
  return griffith_load_from_fe_compliance(scene_file, scene, {{probe, grip_opening}}, dir);
}

ComplianceGriffith griffith_load_from_fe_compliance(const std::filesystem::path& scene_file,
                                                    const Scene& scene,
                                                    const std::vector<GripPair>& grips,
                                                    const std::filesystem::path& dir) {
  if (grips.empty()) {
    throw std::runtime_error("FE compliance: no grips");
  }
  const std::array<bool, 2> tip = crack_tips(scene);
  const int tips = (tip[0] ? 1 : 0) + (tip[1] ? 1 : 0);
  const auto& v = scene.model.cracks[0].vertices;
  // The length one tip would have if the crack grew from the surface or from its middle.
  const double tip_length = std::hypot(v[1][0] - v[0][0], v[1][1] - v[0][1]) / tips;
  const double h = step_fraction * tip_length;
  const Material& m = scene.model.materials.at(0);
  const double g0 = m.fracture_energy.value_or(0);
  const double thickness = scene.model.dimension.thickness;
  std::vector<std::string> probes;
  for (const GripPair& g : grips) {
    probes.push_back(g.probe);
  }
  std::vector<std::vector<std::vector<double>>> loads; // [a − h, a, a + h][probe][level]
  for (const auto& [name, step] : {std::pair{"shorter", -h}, {"as-given", 0.0}, {"longer", h}}) {
    loads.push_back(loads_with_tips_moved(scene_file, probes, step, tip, dir / name));
  }
  ComplianceGriffith out;
  out.crack_step = h;
  for (std::size_t level = 0; level < loads[1][0].size(); ++level) {
    double g = 0;
    for (std::size_t p = 0; p < grips.size(); ++p) {
      // Each tip moves by 2h between the shorter and the longer crack.
      const double dp_da = (loads[2][p][level] - loads[0][p][level]) / (tips * 2 * h * thickness);
      g -= 0.5 * grips[p].opening * dp_da;
    }
    if (!(g > 0)) {
      throw std::runtime_error(fmt::format("FE compliance: the crack's energy release rate is {} "
                                           "(the force must fall as the crack grows)",
                                           g));
    }
    out.level_loads.push_back(loads[1][0][level] * std::sqrt(g0 / g));
  }
  out.failure_load = extrapolated(out.level_loads);
  return out;
}

ComplianceGrowth lefm_growth_from_fe_compliance(const std::filesystem::path& scene_file,
                                                const Scene& scene, const std::string& probe,
                                                double grip_opening, double step,
                                                double max_extension,
                                                const std::filesystem::path& dir) {
  const std::array<bool, 2> tip = crack_tips(scene);
  const int tips = (tip[0] ? 1 : 0) + (tip[1] ? 1 : 0);
  const double g0 = scene.model.materials.at(0).fracture_energy.value_or(0);
  const double thickness = scene.model.dimension.thickness;
  const auto points = static_cast<int>(std::ceil(max_extension / step - 1e-9)) + 1;
  // The FE load, extrapolated in the mesh size, with the tips moved by k·step, k = −2 … points+1.
  std::map<int, double> load;
  for (int k = -2; k <= points + 1; ++k) {
    const double shift = k * step;
    load[k] = extrapolated(
        loads_with_tips_moved(scene_file, {probe}, shift, tip, dir / fmt::format("tip{:+d}", k))
            .front());
  }
  ComplianceGrowth out;
  for (int k = 0; k < points; ++k) {
    const double dp_da = (8 * (load[k + 1] - load[k - 1]) - (load[k + 2] - load[k - 2])) /
                         (12 * step) / (tips * thickness);
    const double g = -0.5 * grip_opening * dp_da; // at the opening grip_opening
    if (!(g > 0)) {
      throw std::runtime_error(fmt::format("FE compliance: the crack's energy release rate at "
                                           "extension {} is {} (the force must fall as the "
                                           "crack grows)",
                                           k * step, g));
    }
    const double scale = std::sqrt(g0 / g); // G grows as the opening squared
    out.extension.push_back(k * step);
    out.load.push_back(load[k] * scale);
    out.opening.push_back(grip_opening * scale);
  }
  return out;
}

namespace {

/// y at `at` between the points (x, y), x increasing, interpolated linearly in log x (else x) and
/// log y (else y); NaN outside the points.
double interpolate(const std::vector<double>& x, const std::vector<double>& y, double at,
                   bool log_x, bool log_y) {
  for (std::size_t k = 0; k + 1 < x.size(); ++k) {
    if (at >= x[k] && at <= x[k + 1]) {
      const double t =
          log_x ? std::log(at / x[k]) / std::log(x[k + 1] / x[k]) : (at - x[k]) / (x[k + 1] - x[k]);
      return log_y ? y[k] * std::pow(y[k + 1] / y[k], t) : y[k] + t * (y[k + 1] - y[k]);
    }
  }
  return std::nan("");
}

} // namespace

double ComplianceGrowth::load_at(double at) const {
  return interpolate(opening, load, at, true, true);
}

double ComplianceGrowth::extension_at(double at) const {
  return interpolate(opening, extension, at, true, false);
}

double ComplianceGrowth::extension_at_compliance(double compliance) const {
  std::vector<double> c(load.size());
  for (std::size_t k = 0; k < c.size(); ++k) {
    c[k] = opening[k] / load[k];
  }
  return interpolate(c, extension, compliance, false, false);
}

} // namespace pd::verification
