// summary.json of a run: what was run (scene, sizes, integrator, kernel, effects), how it ended
// (status, steps, energies, residual), its cost (wall time, bond updates per second, memory), the
// final probe values and the checkpoint/restart it wrote or continued from.
#pragma once

#include "libpd/app/run_options.hpp"
#include "libpd/app/run_outcome.hpp"
#include "libpd/core/json.hpp"
#include "libpd/io/scene.hpp"
#include "libpd/time/simulation.hpp"

namespace pd {

Json run_summary(const Scene& scene, const Simulation& sim, const RunOutcome& out,
                 const RunOptions& options);

} // namespace pd
