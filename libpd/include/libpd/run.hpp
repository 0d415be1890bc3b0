// Running a scene end to end: build the model, integrate, record probes, write outputs.
// Used by `pd run`, the verification cases and the tests, so all of them produce the same files.
#pragma once

#include "libpd/output.hpp"
#include "libpd/scene.hpp"
#include "libpd/simulation.hpp"

#include <filesystem>
#include <map>
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
};

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
