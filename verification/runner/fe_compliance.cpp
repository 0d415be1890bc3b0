#include "fe_compliance.hpp"

#include "scene_verification.hpp"

#include <array>
#include <cmath>
#include <fmt/format.h>
#include <fstream>
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
/// outwards by `h` (inwards when negative): damage, stopping rules and output removed, the one
/// probe kept.
std::filesystem::path write_elastic_variant(const std::filesystem::path& scene_file,
                                            const std::string& probe, double h,
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
    if (p["name"].as<std::string>() == probe) {
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

} // namespace

ComplianceGriffith griffith_load_from_fe_compliance(const std::filesystem::path& scene_file,
                                                    const Scene& scene, const std::string& probe,
                                                    double grip_opening,
                                                    const std::filesystem::path& dir) {
  if (scene.model.cracks.empty() || scene.model.cracks[0].vertices.size() != 2) {
    throw std::runtime_error("griffith_load_from_fe_compliance: the scene's first crack must be a "
                             "segment");
  }
  const auto& v = scene.model.cracks[0].vertices;
  // An end is a tip when it lies inside a body; an end on the surface is the crack's mouth.
  const double inside = -1e-9 * scene.model.lattice.spacing;
  std::array<bool, 2> tip{false, false};
  for (std::size_t k = 0; k < 2; ++k) {
    for (const BodySpec& body : scene.model.bodies) {
      tip[k] = tip[k] || body.region.contains(v[k], scene.model.dimension.dim, inside);
    }
  }
  const int tips = (tip[0] ? 1 : 0) + (tip[1] ? 1 : 0);
  if (tips == 0) {
    throw std::runtime_error("griffith_load_from_fe_compliance: neither end of the crack lies "
                             "inside a body");
  }
  // The length one tip would have if the crack grew from the surface or from its middle.
  const double tip_length = std::hypot(v[1][0] - v[0][0], v[1][1] - v[0][1]) / tips;
  const double h = step_fraction * tip_length;
  const Material& m = scene.model.materials.at(0);
  const double g0 = m.fracture_energy.value_or(0);
  const double thickness = scene.model.dimension.thickness;
  SceneVerifyOptions options;
  options.fe_levels = fe_levels;
  std::vector<std::vector<double>> loads; // at a − h, a, a + h
  for (const auto& [name, step] : {std::pair{"shorter", -h}, {"as-given", 0.0}, {"longer", h}}) {
    const auto file =
        write_elastic_variant(scene_file, probe, step, tip, dir / name / "scene.yaml");
    loads.push_back(probe_levels(run_pd_fem(file, dir / name, options), probe));
  }
  ComplianceGriffith out;
  out.crack_step = h;
  for (std::size_t level = 0; level < loads[1].size(); ++level) {
    // Each tip moves by 2h between the shorter and the longer crack.
    const double dp_da = (loads[2][level] - loads[0][level]) / (tips * 2 * h * thickness);
    const double g = -0.5 * grip_opening * dp_da;
    if (!(g > 0)) {
      throw std::runtime_error(fmt::format("FE compliance: the crack's energy release rate is {} "
                                           "(the force must fall as the crack grows)",
                                           g));
    }
    out.level_loads.push_back(loads[1][level] * std::sqrt(g0 / g));
  }
  // pd-fem halves the mesh size from level to level.
  const auto n = out.level_loads.size();
  out.failure_load =
      n < 2 ? out.level_loads.back() : 2 * out.level_loads[n - 1] - out.level_loads[n - 2];
  return out;
}

} // namespace pd::verification
