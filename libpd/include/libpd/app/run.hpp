// Running a scene end to end: build the model, integrate, record probes, write outputs.
// Used by `pd run`, the verification cases and the tests, so all of them produce the same files.
#pragma once

#include "libpd/io/checkpoint.hpp"
#include "libpd/io/output.hpp"
#include "libpd/io/scene.hpp"
#include "libpd/time/simulation.hpp"

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace pd {

/// A probe bound to particles: the mean of one displacement component over them.
struct ResolvedProbe {
  std::string name;
  int component = 0;
  std::vector<std::uint32_t> particles;
};

std::vector<ResolvedProbe> resolve_probes(const std::vector<ProbeSpec>& probes, const Model& model);
double probe_value(const ResolvedProbe& probe, const Simulation& sim);

struct RunOptions {
  std::filesystem::path output_dir; ///< empty: write nothing
  bool progress = false;            ///< progress line on stderr
  bool write_vtu = true;
  bool stop_on_interrupt = true; ///< SIGINT ends the run cleanly with status `interrupted`
  bool keep_final_field = false; ///< return reference positions and final displacements
  /// Checkpoints (checkpoint.hpp): the complete run state every `checkpoint_every` steps (0:
  /// never), at the end of such a run, and when SIGINT interrupts any run that has a checkpoint
  /// path. The path is `checkpoint`, or output_dir/checkpoint.pdcp if that is empty.
  std::size_t checkpoint_every = 0;
  std::filesystem::path checkpoint;
  /// Continue from this checkpoint: it must fingerprint-match the scene (same model, Δt,
  /// integrator, probes); only when the run stops (end_time, max_steps, steady) and the VTU output
  /// may differ. The restored probe history continues, so probes.csv ends as an uninterrupted
  /// run's.
  std::filesystem::path restart;
};

struct ProbeHistory {
  std::vector<double> time;
  std::vector<std::vector<double>> values; ///< one row per sample, one column per probe
};

struct RunOutcome {
  RunResult result;
  double setup_seconds = 0;
  std::size_t particles = 0;
  std::size_t bonds = 0;
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
};

/// What makes a run, for checkpoints: sizes, Δt, integrator, kernel, effects, damping, ramp, probes
/// and a hash of the model's arrays (positions, volumes, bonds, bond parameters, supports, loads).
/// Stop criteria (end_time, max_steps, steady) and output settings other than history_every are
/// left out, so a restart may extend a run.
CheckpointFingerprint run_fingerprint(const Scene& scene, const Simulation& sim,
                                      const std::vector<ResolvedProbe>& probes);

/// Default checkpoint path of a run: options.checkpoint, else output_dir/checkpoint.pdcp (empty
/// if neither is set).
std::filesystem::path checkpoint_path(const RunOptions& options);

/// Run a scene and (if output_dir is set) write summary.json, probes.csv and VTU files there.
/// An unstable run returns status `unstable` with the message; nothing non-finite is written.
RunOutcome run_scene(const Scene& scene, const RunOptions& options);

/// bond updates per second: one update = one bond's force computed once per evaluation,
/// whatever the storage (the CSR gather computes each bond from both ends but counts it once).
inline double bond_updates_per_second(std::size_t bonds, std::size_t evaluations, double seconds) {
  return seconds > 0 ? static_cast<double>(bonds) * static_cast<double>(evaluations) / seconds
                     : 0.0;
}

} // namespace pd
