// pd bench --lammps: one LAMMPS peri/pmb run (reports/lammps/model-a.in), timed by its own log.
#pragma once

#include <cstddef>
#include <optional>
#include <string>

namespace pd::cli {

/// Wall seconds of the MD loop and the unordered bond count of one LAMMPS run.
struct LammpsRun {
  double loop_seconds = 0;
  std::size_t bonds = 0;
};

/// Run `lmp -in input -var steps N` on one thread; nullopt if it failed or printed no timing.
std::optional<LammpsRun> run_lammps(const std::string& lmp, const std::string& input,
                                    std::size_t steps);

} // namespace pd::cli
