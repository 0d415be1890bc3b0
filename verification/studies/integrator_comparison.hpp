// Integrator comparison (`pd compare`): the cost and accuracy of libpd's time integrators on two
// shipped scenes, one JSON row per configuration, for the report's integrator plots.
//   dynamic      bar-vibration: free-end history error against the modal series (and against a
//                fine Dormand–Prince PD run, the temporal error alone) vs force evaluations, for
//                Verlet and the ARKode tables at fractions of their stable step.
//   quasistatic  clamped-beam: force evaluations to reach the steady state, and the mid-span
//                deflection against damped-euler's, for damped-euler, ADR and ARKode.
#pragma once

#include "libpd/core/json.hpp"

#include <filesystem>
#include <functional>

namespace pd::verification {

/// Receives each row as soon as it is computed (a full comparison takes long).
using ComparisonRow = std::function<void(const Json&)>;

/// The scenes are the case folders' (cases_dir/bar-vibration/, cases_dir/clamped-beam/).
/// `quick`: fewer time steps, one ARKode table per order and a coarser reference.
void compare_integrators_dynamic(const std::filesystem::path& cases_dir, bool quick,
                                 const ComparisonRow& emit);
/// `quick`: without adaptive Dormand–Prince, by far the most expensive configuration.
void compare_integrators_quasistatic(const std::filesystem::path& cases_dir, bool quick,
                                     const ComparisonRow& emit);

} // namespace pd::verification
