// `pd verify SCENE.yaml`: any linear-elastic scene against the FE solution of the same continuum
// problem (issue 19). The PD run is the scene's own; the FE reference is `pd-fem --scene`, which
// reads the same scene through libpd's reader (fem_reference/), so the two cannot disagree about
// the geometry, the supports, the loads or which particles a probe reads.
#pragma once

#include "verification.hpp"

#include <filesystem>
#include <optional>
#include <yaml-cpp/yaml.h>

namespace pd::verification {

struct SceneVerifyOptions {
  std::optional<int> fe_levels; ///< pd-fem --levels; default: its own
  bool fe_coarse = false;       ///< pd-fem --coarse
  /// Fail if a probe's |PD − FE| exceeds this fraction of max(|FE|, a tenth of the largest |FE|
  /// of its quantity); without it the result is measured, not passed.
  std::optional<double> gate;
  std::filesystem::path pd_fem; ///< the pd-fem executable; empty: beside this program, or $PD_FEM
};

/// Runs pd-fem on the scene file into `dir` (with the options' levels); returns its fe.json.
YAML::Node run_pd_fem(const std::filesystem::path& scene, const std::filesystem::path& dir,
                      const SceneVerifyOptions& options);

/// Run the scene and its FE reference; the JSON has one row per probe (PD, FE, the FE's own error
/// estimate, the difference and, with a gate, the probe's tolerance), the materials both solved
/// and the wall time of both. "verdict": `passed` (a gate was given and every probe is within
/// it), `failed` (a probe is outside the gate, a probe has no FE value, the two solvers' materials
/// differ, or the PD run did not end at an equilibrium: "reasons" says which) or `measured` (no
/// gate: the differences are reported, not judged). Throws if the scene gives a ν that the bond
/// model cannot represent (PD and FE would solve different problems).
Json verify_scene(const std::filesystem::path& scene, const Context& ctx,
                  const SceneVerifyOptions& options);

} // namespace pd::verification
