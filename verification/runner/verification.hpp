// Verification cases: runnable documents that compare libpd with closed-form solutions (and, in
// later cases, deal.II). Each case writes CASE.json with at least
//   case, quantity, pd, reference {name: value}, error {name: relative error}, gate, passed,
//   wall_seconds
// and `pd verify` exits non-zero when a gate fails.
#pragma once

#include "libpd/app/run_options.hpp"
#include "libpd/io/output.hpp"

#include <chrono>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace pd::verification {

struct Context {
  std::filesystem::path scenes_dir; ///< where the shipped scenes live
  std::filesystem::path output_dir; ///< where CASE.json and run outputs go
  bool progress = false;
  /// The default report's extent (pd verify --quick): sweeps run their case file's
  /// `quick_sweep:` lists where it has them, and rc-beam leaves out its s0 sensitivity runs.
  bool quick = false;
};

struct Case {
  std::string name;
  std::string summary;
  /// Returns the case JSON; must set "passed" (bool).
  std::function<Json(const Context&)> run;
};

const std::vector<Case>& all_cases();

/// Run options for a case's run into its own folder ctx.output_dir/name: a rerun of the case
/// replaces its previous run (overwrite), including one written before runs kept a manifest.
RunOptions case_run_options(const Context& ctx, const std::string& name);

/// Default scenes folder: $PD_SCENES_DIR, else the source tree's verification/scenes.
std::filesystem::path default_scenes_dir();

/// Released bar fixed at x = 0, free at x = L, u(x, 0) = εx (bar-vibration): the modal series
/// u(x, t) = Σ a_n sin(k_n x) cos(c k_n t), k_n = (2n − 1)π/(2L), a_n = 2ε(−1)^(n+1)/(L k_n²),
/// summed over 4000 modes.
double bar_modal_series(double x, double t, double strain, double length, double wave_speed);

/// Relative error |a − b|/|b|.
double relative_error(double value, double reference);

/// The last keys of a case's JSON: its gate in words, the verdict and its wall time since `start`.
void finish_case(Json& out, const std::string& gate, bool passed,
                 std::chrono::steady_clock::time_point start);

} // namespace pd::verification
