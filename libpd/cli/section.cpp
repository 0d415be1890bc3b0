// pd section SCENE [--span x] [--depth z] [--plate] [--all-pairs] [--json]
// Section stiffness of the scene's first body (section_stiffness.hpp), for the scene's own
// corrections or for every pair: the a-priori part of a bending structure's error budget.
#include "commands.hpp"
#include "libpd/core/json.hpp"
#include "libpd/discretisation/corrections.hpp"
#include "section_stiffness.hpp"

#include <fmt/format.h>
#include <memory>
#include <utility>
#include <vector>

namespace pd::cli {

namespace {

struct SectionArgs {
  std::string scene;
  std::string span = "x", depth = "z";
  bool plate = false, all_pairs = false, json = false;
};

std::vector<std::pair<SurfaceCorrection, VolumeCorrection>> correction_pairs(const Scene& scene,
                                                                             bool all) {
  std::vector<std::pair<SurfaceCorrection, VolumeCorrection>> pairs;
  if (all) {
    for (auto sc : all_surface_corrections) {
      for (auto vc : all_volume_corrections) {
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
  if (a.span == a.depth) {
    fmt::print(stderr, "error: --span and --depth must be different axes\n");
    return 1;
  }
  if (!a.json) {
    fmt::print("{}: section of body '{}', span {}, depth {}{}; PD / continuum stiffness\n", a.scene,
               scene.model.bodies.front().name, a.span, a.depth,
               a.plate ? ", plate (long in the third axis too)" : "");
    fmt::print("{:<30} {:>9} {:>9} {:>9}\n", "surface + volume correction", "bending", "shear",
               "axial");
  }
  for (const auto& [sc, vc] : correction_pairs(scene, a.all_pairs)) {
    ModelSpec spec = scene.model;
    spec.surface_correction = sc;
    spec.volume_correction = vc;
    const auto s =
        verification::section_stiffness(spec, spec.bodies.front(), verification::axis_of(a.span),
                                        verification::axis_of(a.depth), a.plate);
    if (a.json) {
      Json j;
      j["surface_correction"] = to_string(sc);
      j["volume_correction"] = to_string(vc);
      j["bending"] = s.bending;
      j["shear"] = s.shear;
      j["membrane"] = s.membrane;
      j["section_particles"] = s.section_particles;
      fmt::print("{}", j.dump(0)); // dump ends the line
    } else {
      const std::string name = fmt::format("{} + {}", to_string(sc), to_string(vc));
      fmt::print("{:<30} {:>9.4f} {:>9.4f} {:>9.4f}\n", name, s.bending, s.shear, s.membrane);
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
                 "budget, verification/cases/STRUCTURES.md)");
  cmd->add_option("scene", a->scene, "scene file (YAML)")->required();
  cmd->add_option("--span", a->span, "axis along which the body is long")
      ->check(CLI::IsMember({"x", "y", "z"}))
      ->capture_default_str();
  cmd->add_option("--depth", a->depth, "bending (load) direction")
      ->check(CLI::IsMember({"x", "y", "z"}))
      ->capture_default_str();
  cmd->add_flag("--plate", a->plate, "the third axis is long too (a plate)");
  cmd->add_flag("--all-pairs", a->all_pairs,
                "every surface/volume correction pair instead of the scene's");
  cmd->add_flag("--json", a->json, "JSON lines");
  return {cmd, [a] { return section(*a); }};
}

} // namespace pd::cli
