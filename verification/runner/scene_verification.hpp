// `pd verify SCENE.yaml`: any linear-elastic scene against the FE solution of the same continuum
// problem (issue 19). The PD run is the scene's own; the FE reference is `pd-fem --scene`, which
// reads the same scene through libpd's reader (fem_reference/), so the two cannot disagree about
// the geometry, the supports, the loads or which particles a probe reads.
#pragma once

#include "verification.hpp"

#include <filesystem>
#include <optional>

namespace pd::verification {

struct SceneVerifyOptions {
  std::optional<int> fe_levels; ///< pd-fem --levels; default: its own
  bool fe_coarse = false;       ///< pd-fem --coarse
  std::optional<double> gate;   ///< fail if |PD − FE| / |FE| exceeds this for a probe
  std::filesystem::path pd_fem; ///< the pd-fem executable; empty: beside this program, or $PD_FEM
};

/// Run the scene and its FE reference; the JSON has one row per probe (PD, FE, the FE's own error
/// estimate, the difference) and the wall time of both. "passed": both ran, every probe has an
/// FE value, and the gate (if any) holds.
Json verify_scene(const std::filesystem::path& scene, const Context& ctx,
                  const SceneVerifyOptions& options);

} // namespace pd::verification
