// pd info SCENE [--json]
// Sizes, memory and stable time step of a scene, beside the estimate the scene parser's memory
// guard used, so that its accuracy can be checked on any scene.
#include "commands.hpp"
#include "libpd/app/run_summary.hpp"
#include "libpd/core/json.hpp"
#include "libpd/io/resources.hpp"
#include "libpd/kernel/stable_time_step.hpp"

#include <algorithm>
#include <fmt/format.h>
#include <memory>
#include <optional>

namespace pd::cli {

namespace {

struct InfoArgs {
  std::string scene;
  bool json = false;
};

void print_table(const std::string& scene_path, const Model& model, const ResourceEstimate& est,
                 const std::optional<MemoryBudget>& budget, double per_particle, double dt) {
  fmt::print("scene              {}\n", scene_path);
  fmt::print("                   {:>14} {:>14}\n", "actual", "estimate");
  fmt::print("particles          {:>14} {:>14.0f}\n", model.size(), est.particles);
  fmt::print("bonds              {:>14} {:>14.0f}\n", model.family.bond_count(), est.bonds);
  fmt::print("bonds per particle {:>14.2f} {:>14.2f} (family size, both directions; estimate: "
             "bulk)\n",
             per_particle, est.bonds_per_particle);
  fmt::print("model memory       {:>14} {:>14}\n",
             format_bytes(static_cast<double>(model.memory_bytes())),
             format_bytes(est.model_bytes));
  fmt::print("memory guard       {:>14} {:>14} (estimate with integrator and build transients; "
             "{})\n",
             "", format_bytes(est.bytes),
             budget ? fmt::format("{} available, {}", format_bytes(budget->bytes), budget->source)
                    : std::string("available memory unknown"));
  fmt::print("horizon            {:.6g} m\n", model.horizon());
  fmt::print("stable dt (eq. 31) {:.6g} s\n", dt);
  fmt::print("effects            {}\n", fmt::join(model.effects.names(), ", "));
  if (const std::string note = mesh_corrections_note(model.spec); !note.empty()) {
    fmt::print("corrections        {}\n", note);
  }
  if (const ParticleGradientWeights& w = model.particle_weights; w.particles() > 0) {
    // What a mesh body's per-particle `gradient` solve met: a particle that keeps the moments
    // only stores more energy under a strain gradient (bending) than one that matched.
    fmt::print("gradient weights   {} of {} particles matched, {} moments only, {} neither "
               "({:.3g} s)\n",
               w.matched, w.particles(), w.moments_only, w.unmatched, w.seconds);
  }
}

int info(const InfoArgs& a) {
  const Scene scene = load_or_explain(a.scene);
  const ResourceEstimate est = estimate_resources(scene.model, scene.solver);
  const auto budget = available_memory();
  const Model model = build_model(scene);
  const double dt = stable_time_step(model);
  const double per_particle = 2.0 * static_cast<double>(model.family.bond_count()) /
                              static_cast<double>(std::max<std::size_t>(model.size(), 1));
  if (!a.json) {
    print_table(a.scene, model, est, budget, per_particle, dt);
    return 0;
  }
  Json j;
  j["scene"] = a.scene;
  j["particles"] = model.size();
  j["bonds"] = model.family.bond_count();
  j["bonds_per_particle"] = per_particle;
  j["horizon"] = model.horizon();
  j["memory_bytes"] = model.memory_bytes();
  j["memory_estimate_bytes"] = est.model_bytes;
  j["estimate_particles"] = est.particles;
  j["estimate_bonds"] = est.bonds;
  j["estimate_total_bytes"] = est.bytes;
  if (budget) {
    j["memory_available_bytes"] = budget->bytes;
  }
  j["dt_stable"] = dt;
  j["effects"] = Json::array_of(model.effects.names());
  if (const std::string note = mesh_corrections_note(model.spec); !note.empty()) {
    j["mesh_corrections"] = note;
  }
  if (Json weights = particle_weights_json(model); weights.is_object()) {
    j["particle_weights"] = std::move(weights);
  }
  fmt::print("{}", j.dump());
  return 0;
}

} // namespace

Command add_info_command(CLI::App& app) {
  auto a = std::make_shared<InfoArgs>();
  auto* cmd = app.add_subcommand("info", "Particles, bonds, memory estimate and stable time step");
  cmd->add_option("scene", a->scene, "scene file (YAML)")->required();
  cmd->add_flag("--json", a->json, "machine-readable output");
  return {cmd, [a] { return info(*a); }};
}

} // namespace pd::cli
