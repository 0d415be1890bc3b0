// What a run of a scene returns: the integrator's result, sizes, probes, the summary and the
// checkpoints written.
#pragma once

#include "libpd/app/probes.hpp"
#include "libpd/core/geometry.hpp"
#include "libpd/core/json.hpp"
#include "libpd/time/simulation.hpp"

#include <cstddef>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace pd {

struct RunOutcome {
  RunResult result;
  /// Set-up: from the start of run_scene to the first step (output folder, model, simulation,
  /// restored checkpoint); its parts below. The run's solve time is result.wall_seconds.
  double setup_seconds = 0;
  double model_seconds = 0; ///< build_model: bonds, corrections, supports, bond fields
  double simulation_seconds =
      0; ///< Simulation: force evaluator, stable Δt, the integrator's set-up
  std::size_t particles = 0;
  std::size_t bonds = 0;
  /// A run split over ranks: ranks, partition, and per rank the particles owned, the halo
  /// copies, the model's bytes, the peak resident bytes and the halo bytes sent per step
  /// (summary.json `distribution`; null in one process).
  Json distribution;
  /// Per point load: how many particles share it, counted on the whole model before any split.
  std::map<std::string, std::size_t> point_load_particles;
  std::map<std::string, double> probes;
  ProbeHistory history;
  Json summary;
  /// With RunOptions::keep_final_field: reference positions and final displacements (3 per
  /// particle), e.g. to extract deflection lines.
  std::vector<Vec3> positions;
  std::vector<double> displacement;
  std::filesystem::path checkpoint; ///< last checkpoint written (empty: none)
  std::size_t checkpoint_step = 0;  ///< its step
  std::size_t checkpoints_written = 0;
  std::optional<std::size_t> restarted_from_step; ///< set when RunOptions::restart was used
  std::string checkpoint_note; ///< why no checkpoint was written on interrupt, if none was
  /// Force evaluations done by this process: a restart's throughput counts only these, not
  /// those of the run it continued.
  std::size_t evaluations_this_run = 0;
  int stop_signal = 0; ///< the signal that interrupted the run, 0 if none
  /// solver.stop_when: the peak |value| of the watched probe (the failure load of a fracture
  /// test when the run ends `failed`) and the time it was reached.
  double stop_peak = 0;
  double stop_peak_time = 0;
  /// Quasi-static fracture (integrator static with damage): levels, solves, break events,
  /// bonds broken, the energy they dissipated and the peak load factor (summary.json
  /// `quasi_static`; null otherwise).
  Json quasi_static;
  std::vector<std::string> warnings; ///< about the run's set-up (disk space), for the summary
};

/// bond updates per second: one update = one bond's force computed once per evaluation,
/// whatever the storage (the CSR gather computes each bond from both ends but counts it once).
inline double bond_updates_per_second(std::size_t bonds, std::size_t evaluations, double seconds) {
  return seconds > 0 ? static_cast<double>(bonds) * static_cast<double>(evaluations) / seconds
                     : 0.0;
}

} // namespace pd
