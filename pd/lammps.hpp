// pd bench --lammps: one LAMMPS peri/pmb run (reports/lammps/model-a.in), timed by its own log.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace pd::cli {

/// Wall seconds of the MD loop and the unordered bond count of one LAMMPS run.
struct LammpsRun {
  double loop_seconds = 0;
  std::size_t bonds = 0;
};

/// Run `lmp -in input -var steps N [-var NAME VALUE ...]` on one thread; nullopt if it failed or
/// printed no timing. `vars` holds "NAME=VALUE" strings already checked by lammps_var_error.
std::optional<LammpsRun> run_lammps(const std::string& lmp, const std::string& input,
                                    std::size_t steps, const std::vector<std::string>& vars);

/// Empty if `var` is a LAMMPS variable setting NAME=VALUE that is safe to put on a shell command
/// line (a name of letters, digits and _; a value of letters, digits and .+-_), else why not.
std::string lammps_var_error(const std::string& var);

} // namespace pd::cli
