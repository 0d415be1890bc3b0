// summary.json of a run.
#include "libpd/app/run_summary.hpp"

#include "libpd/core/threads.hpp"

#include <fstream>
#include <string>
#include <utility>

namespace pd {

std::uint64_t peak_resident_bytes() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("VmHWM:", 0) == 0) {
      return std::stoull(line.substr(6)) * 1024; // "VmHWM:   123456 kB"
    }
  }
  return 0;
}

namespace {

/// A fracture run's sections: `quasi_static` (integrator static with damage) and `stop_when`.
void failure_sections(const Scene& scene, const RunOutcome& out, Json& j) {
  if (out.quasi_static.is_object()) {
    j["quasi_static"] = out.quasi_static;
  }
  if (scene.stop_when.enabled()) {
    Json& sj = j["stop_when"];
    sj["probe"] = scene.stop_when.probe;
    sj["peak"] = out.stop_peak; // the failure value when status is `failed`
    sj["peak_time"] = out.stop_peak_time;
  }
}

/// How the arms of a virtual-fibre point cloud were balanced; null where they were not.
Json fibre_balance_json(const Model& model) {
  Json fb;
  if (model.fibre_arms.balance_passes > 0) {
    fb["balanced_particles"] = model.fibre_arms.balanced;
    fb["relative_residual"] = model.fibre_arms.balance_residual;
    fb["arms_at_floor"] = model.fibre_arms.balance_floored;
    fb["passes"] = model.fibre_arms.balance_passes;
    fb["applied"] = model.fibre_arms.balance_applied;
    if (const auto& r = model.fibre_arms.relaxed; r.applied) {
      Json& rj = fb["relaxed_moduli"]; // discretisation/fibre_relaxation.cpp
      rj["relaxed_particles"] = r.free;
      rj["bulk_energy_released"] = r.bulk;
      rj["shear_energy_released"] = r.shear;
      rj["shear_fraction_range"] = Json::array_of(std::vector<double>{r.shear_low, r.shear_high});
      rj["fractions_bounded"] = r.bounded;
    }
  }
  return fb;
}

} // namespace

Json particle_weights_json(const Model& model) {
  const ParticleGradientWeights& w = model.particle_weights;
  Json j;
  if (w.particles() > 0) {
    j["matched"] = w.matched;
    j["moments_only"] = w.moments_only;
    j["unmatched"] = w.unmatched;
    j["largest_residual"] = w.residual;
    j["seconds"] = w.seconds;
  }
  return j;
}

Json run_summary(const Scene& scene, const Simulation& sim, const RunOutcome& out,
                 const RunOptions& options) {
  const Model& model = sim.model();
  Json j;
  j["scene"] = scene.path;
  j["title"] = scene.title;
  j["status"] = to_string(out.result.status);
  if (!out.result.message.empty()) {
    j["message"] = out.result.message;
  }
  j["dimension"] = scene.model.dimension.dim;
  // The constants as the scene resolved them (a bond-based ν the model fixes included), so that
  // a reference solution can be checked against the same material.
  Json& materials = j["materials"];
  materials = Json::array();
  for (const Material& m : scene.model.materials) {
    Json row;
    row["name"] = m.name;
    row["youngs_modulus"] = m.youngs_modulus * m.stiffness_factor;
    row["poisson_ratio"] = m.poisson_ratio;
    row["density"] = m.density;
    materials.push_back(row);
  }
  j["particles"] = out.particles;
  j["bonds"] = out.bonds;
  j["bonds_per_particle"] =
      2.0 * static_cast<double>(out.bonds) / static_cast<double>(out.particles);
  j["horizon"] = model.horizon();
  j["spacing"] = scene.model.lattice.spacing;
  j["integrator"] = to_string(scene.solver.integrator);
  j["kernel"] = sim.forces().description();
  j["small_displacements"] = scene.solver.small_displacements;
  j["effects"] = Json::array_of(model.effects.names());
  if (const std::string note = mesh_corrections_note(scene.model); !note.empty()) {
    j["mesh_corrections"] = note;
  }
  j["steps"] = out.result.steps;
  j["time"] = out.result.time;
  j["dt"] = out.result.dt;
  j["dt_stable"] = out.result.dt_stable;
  j["force_evaluations"] = out.result.force_evaluations;
  j["setup_seconds"] = out.setup_seconds;
  Json& setup = j["setup"];
  setup["scene_seconds"] = options.scene_seconds;
  setup["model_seconds"] = out.model_seconds;
  setup["simulation_seconds"] = out.simulation_seconds;
  j["solve_seconds"] = out.result.wall_seconds;
  j["wall_seconds"] = out.result.wall_seconds;
  j["bond_updates"] =
      static_cast<double>(out.bonds) * static_cast<double>(out.result.force_evaluations);
  j["force_evaluations_this_run"] = out.evaluations_this_run;
  j["bond_updates_per_second"] =
      bond_updates_per_second(out.bonds, out.evaluations_this_run, out.result.wall_seconds);
  j["kinetic_energy"] = out.result.kinetic_energy;
  j["strain_energy"] = out.result.strain_energy;
  j["residual"] = out.result.residual;
  if (scene.solver.steady.enabled) {
    j["force_tolerance"] = out.result.force_tolerance; // the one the check used
    j["residual_floor"] = out.result.residual_floor;
  }
  j["memory_bytes"] = model.memory_bytes();
  if (out.distribution.is_object()) {
    j["distribution"] = out.distribution;
  }
  j["peak_memory_bytes"] = peak_resident_bytes();
  // What the times were measured on: the threads at the end, fixed or following core/threads.hpp.
  j["threads"] = current_thread_count();
  j["threads_follow_idle_processors"] = following_idle_processors();
  if (Json details = sim.integrator().summary(); details.is_object()) {
    j["integrator_details"] = std::move(details);
  }
  if (Json balance = fibre_balance_json(model); balance.is_object()) {
    j["fibre_balance"] = std::move(balance); // fibre_arms.hpp: point clouds' arms balanced
  }
  if (Json weights = particle_weights_json(model); weights.is_object()) {
    j["particle_weights"] = std::move(weights);
  }
  if (!scene.model.cracks.empty()) {
    Json& cj = j["cracks"]; // pairs of particles a crack kept from bonding
    for (std::size_t c = 0; c < scene.model.cracks.size(); ++c) {
      cj[scene.model.cracks[c].name]["bonds_not_created"] = model.bonds_cut_by_crack[c];
    }
  }
  for (const auto& [name, count] : out.point_load_particles) {
    j["point_loads"][name]["particles"] = count;
  }
  failure_sections(scene, out, j);
  Json& pj = j["probes"];
  pj = Json::object();
  for (const auto& [name, value] : out.probes) {
    pj[name] = value;
  }
  std::vector<std::string> warnings = scene.warnings;
  warnings.insert(warnings.end(), out.warnings.begin(), out.warnings.end());
  if (!warnings.empty()) {
    j["warnings"] = Json::array_of(warnings);
  }
  if (out.stop_signal != 0) {
    j["stop_signal"] = out.stop_signal;
  }
  if (!out.checkpoint.empty()) {
    j["checkpoint"] = out.checkpoint.string();
    j["checkpoint_step"] = out.checkpoint_step;
  }
  if (out.restarted_from_step) {
    Json& rj = j["restarted_from"];
    rj["file"] = options.restart.string();
    rj["step"] = *out.restarted_from_step;
  }
  return j;
}

} // namespace pd
