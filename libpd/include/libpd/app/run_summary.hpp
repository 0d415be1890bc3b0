// summary.json of a run: what was run (scene, sizes, integrator, kernel, effects), how it ended
// (status, steps, energies, residual), its cost (set-up and solve time, bond updates per second,
// memory, peak resident memory), the final probe values and the checkpoint/restart it wrote or
// continued from.
#pragma once

#include "libpd/app/run_options.hpp"
#include "libpd/app/run_outcome.hpp"
#include "libpd/core/json.hpp"
#include "libpd/io/scene.hpp"
#include "libpd/time/simulation.hpp"

#include <cstdint>

namespace pd {

/// The process's peak resident set size (VmHWM of /proc/self/status) in bytes; 0 if unknown.
std::uint64_t peak_resident_bytes();

/// What a mesh body's per-particle `gradient` solve met (Model::particle_weights), as summary.json
/// and `pd info --json` write it; null where no such solve ran.
Json particle_weights_json(const Model& model);

Json run_summary(const Scene& scene, const Simulation& sim, const RunOutcome& out,
                 const RunOptions& options);

} // namespace pd
