// Running a scene end to end: build the model, integrate, record probes, write outputs.
// Used by `pd run`, the verification cases and the tests, so all of them produce the same files.
// The run's parts have their own headers: probes.hpp, run_options.hpp, run_outcome.hpp,
// run_checkpoints.hpp (policy and fingerprint), run_output.hpp (files), run_summary.hpp.
#pragma once

#include "libpd/app/probes.hpp"
#include "libpd/app/run_checkpoints.hpp"
#include "libpd/app/run_options.hpp"
#include "libpd/app/run_outcome.hpp"
#include "libpd/io/scene.hpp"

namespace pd {

/// Run a scene and (if output_dir is set) write summary.json, probes.csv and VTU files there.
/// An unstable run returns status `unstable` with the message; nothing non-finite is written.
RunOutcome run_scene(const Scene& scene, const RunOptions& options);

} // namespace pd
