// pd section SCENE [--span x] [--depth z] [--plate] [--all-pairs] [--beam CASE] [--json]
// Section stiffness of the scene's first body (section_stiffness.hpp), for the scene's own
// corrections or for every pair, and the deflection factor it predicts for a beam of the body's
// span: the a-priori part of a bending structure's error budget.
#include "commands.hpp"
#include "libpd/core/json.hpp"
#include "libpd/discretisation/corrections.hpp"
#include "section_stiffness.hpp"

#include <fmt/format.h>
#include <map>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

namespace pd::cli {

namespace {

struct SectionArgs {
  std::string scene;
  std::string span = "x", depth;
  std::string beam = "auto";
  bool plate = false, all_pairs = false, json = false;
};

/// The beam case for the deflection factor: --beam, or what the scene's supports and loads say.
std::optional<verification::BeamCase> beam_case(const SectionArgs& a, const ModelSpec& spec,
                                                int span, int depth) {
  using verification::BeamCase;
  static const std::map<std::string, BeamCase> named{
      {"cantilever", BeamCase::cantilever_uniform}, {"cantilever-tip", BeamCase::cantilever_tip},
      {"clamped", BeamCase::clamped_uniform},       {"clamped-centre", BeamCase::clamped_centre},
      {"simple", BeamCase::simple_uniform},         {"simple-centre", BeamCase::simple_centre}};
  if (a.plate || a.beam == "none") {
    return std::nullopt;
  }
  if (const auto it = named.find(a.beam); it != named.end()) {
    return it->second;
  }
  return verification::beam_case_of(spec, span, depth);
}

std::vector<std::pair<SurfaceCorrection, VolumeCorrection>> correction_pairs(const Scene& scene,
                                                                             bool all) {
  std::vector<std::pair<SurfaceCorrection, VolumeCorrection>> pairs;
  if (all) {
    for (auto sc : all_surface_corrections) {
      for (auto vc : all_volume_corrections) {
        if (vc == VolumeCorrection::fitted) {
          continue; // weights for sets that are not a lattice: not a lattice table's row
        }
        pairs.emplace_back(sc, vc);
      }
    }
  } else {
    pairs.emplace_back(scene.model.surface_correction, scene.model.volume_correction);
  }
  return pairs;
}

int section(const SectionArgs& a) {
  const Scene scene = load_scene(a.scene);
  const int dim = scene.model.dimension.dim;
  // 2D: the depth is the other in-plane axis, the thickness is out of plane.
  const std::string depth = !a.depth.empty() ? a.depth
                            : dim == 2       ? (a.span == "y" ? "x" : "y")
                                             : "z";
  if (a.span == depth) {
    fmt::print(stderr, "error: --span and --depth must be different axes\n");
    return 1;
  }
  const int span_axis = verification::axis_of(a.span), depth_axis = verification::axis_of(depth);
  const auto beam = beam_case(a, scene.model, span_axis, depth_axis);
  const Box& box = scene.model.bodies.front().region.boxes.front();
  const double length = box.hi[span_axis] - box.lo[span_axis];
  if (!a.json) {
    fmt::print("{}: section of body '{}', span {}, depth {}{}; PD / continuum stiffness\n", a.scene,
               scene.model.bodies.front().name, a.span, depth,
               a.plate ? ", plate (long in the third axis too)"
               : dim == 2
                   ? fmt::format(", 2D plane {} (thickness {:g} m out of plane)",
                                 scene.model.dimension.plane == PlaneMode::plane_stress ? "stress"
                                                                                        : "strain",
                                 scene.model.dimension.thickness)
                   : "");
    fmt::print("{:<30} {:>9} {:>9} {:>9}{}\n", "surface + volume correction", "bending", "shear",
               "axial", beam ? fmt::format(" {:>10}", "deflection") : "");
  }
  double ratio = 0;
  for (const auto& [sc, vc] : correction_pairs(scene, a.all_pairs)) {
    ModelSpec spec = scene.model;
    spec.surface_correction = sc;
    spec.volume_correction = vc;
    const auto s =
        verification::section_stiffness(spec, spec.bodies.front(), span_axis, depth_axis, a.plate);
    ratio = beam ? verification::timoshenko_shear_ratio(s, *beam, length) : 0.0;
    const double factor = verification::deflection_factor(s, ratio);
    if (a.json) {
      Json j;
      j["surface_correction"] = to_string(sc);
      j["volume_correction"] = to_string(vc);
      j["bending"] = s.bending;
      j["shear"] = s.shear;
      j["membrane"] = s.membrane;
      j["section_particles"] = s.section_particles;
      if (beam) {
        j["beam"] = verification::to_string(*beam);
        j["span_length"] = length;
        j["shear_over_bending_deflection"] = ratio;
        j["deflection_factor"] = factor;
      }
      fmt::print("{}", j.dump(0)); // dump ends the line
    } else {
      const std::string name = fmt::format("{} + {}", to_string(sc), to_string(vc));
      fmt::print("{:<30} {:>9.4f} {:>9.4f} {:>9.4f}{}\n", name, s.bending, s.shear, s.membrane,
                 beam ? fmt::format(" {:>10.4f}", factor) : "");
    }
  }
  if (!a.json) {
    if (beam) {
      fmt::print("deflection: PD / continuum deflection the section predicts for a beam of span "
                 "L = {:g} m, {}: Timoshenko's bending and shear parts each divided by their "
                 "stiffness, (1/bending + r/shear) / (1 + r) with r = shear / bending deflection "
                 "= α EI/(κ GA L²) = {:.4g} (κ = 5/6); supports, load and ends not included\n",
                 length, verification::to_string(*beam), ratio);
    } else if (a.plate) {
      fmt::print("deflection: not for a plate (its split into bending and shear needs the plate's "
                 "own solution; the verification case takes it from FE)\n");
    } else if (a.beam != "none") {
      fmt::print("deflection: no beam case recognised in the scene's supports and loads; give one "
                 "with --beam\n");
    }
  }
  return 0;
}

} // namespace

Command add_section_command(CLI::App& app) {
  auto a = std::make_shared<SectionArgs>();
  auto* cmd = app.add_subcommand(
      "section", "PD / continuum bending, shear and axial stiffness of the cross-section of the "
                 "scene's first body, infinitely long (the a-priori part of a structure's error "
                 "budget, docs/theory/structures.md)");
  cmd->add_option("scene", a->scene, "scene file (YAML)")->required();
  cmd->add_option("--span", a->span, "axis along which the body is long")
      ->check(CLI::IsMember({"x", "y", "z"}))
      ->capture_default_str();
  cmd->add_option("--depth", a->depth,
                  "bending (load) direction (default z; in 2D the other "
                  "in-plane axis)")
      ->check(CLI::IsMember({"x", "y", "z"}));
  cmd->add_flag("--plate", a->plate, "the third axis is long too (a plate)");
  cmd->add_flag("--all-pairs", a->all_pairs,
                "every surface/volume correction pair instead of the scene's");
  cmd->add_option("--beam", a->beam,
                  "beam case of the deflection factor: auto (from the scene's supports and "
                  "loads), cantilever, cantilever-tip, clamped, clamped-centre, simple, "
                  "simple-centre or none")
      ->check(CLI::IsMember({"auto", "cantilever", "cantilever-tip", "clamped", "clamped-centre",
                             "simple", "simple-centre", "none"}))
      ->capture_default_str();
  cmd->add_flag("--json", a->json, "JSON lines");
  return {cmd, [a] { return section(*a); }};
}

} // namespace pd::cli
