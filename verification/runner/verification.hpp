// Verification cases: runnable documents that compare libpd with closed-form solutions (and, in
// later cases, deal.II). Each case writes CASE.json with at least
//   case, quantity, pd, reference {name: value}, error {name: relative error}, gate, passed,
//   wall_seconds
// and `pd verify` exits non-zero when a gate fails.
//
// A case is a folder verification/cases/<folder>/ (or under $PD_CASES_DIR): case.yaml describes
// it and its runs (each one `pd verify NAME`), beside the scenes it runs. The runs of a folder of
// kind `code` are C++ functions that register themselves with PD_VERIFICATION_RUN; kind
// `structure` and `scene` folders are data only (case_folders.cpp runs them).
#pragma once

#include "libpd/app/run.hpp"
#include "libpd/app/run_options.hpp"
#include "libpd/io/output.hpp"
#include "libpd/io/scene.hpp"

#include <chrono>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace pd::verification {

struct CaseFolder;
struct RunInfo;

struct Context {
  std::filesystem::path scenes_dir; ///< shared scenes no case folder owns (verification/scenes)
  std::filesystem::path folder;     ///< the case's folder: its case.yaml and its scenes
  const CaseFolder* case_folder = nullptr; ///< the folder's parsed case.yaml
  const RunInfo* run = nullptr;            ///< this run's entry in it
  std::filesystem::path output_dir;        ///< where CASE.json and run outputs go
  bool progress = false;
  /// The default report's extent (pd verify --quick): sweeps run their case file's
  /// `quick_sweep:` lists where it has them, and rc-beam leaves out its s0 sensitivity runs.
  bool quick = false;
};

/// A case's run: returns the case JSON, which must set "passed" (bool).
using RunFunction = Json (*)(const Context&);

/// The code runs of every linked case folder, by run name (filled by PD_VERIFICATION_RUN).
std::map<std::string, RunFunction>& registered_runs();

struct RunRegistrar {
  RunRegistrar(const char* name, RunFunction run);
};

#define PD_VERIFICATION_CONCAT_(a, b) a##b
#define PD_VERIFICATION_CONCAT(a, b) PD_VERIFICATION_CONCAT_(a, b)
/// Registers `function` as the run NAME of the case folder whose case.yaml lists it.
#define PD_VERIFICATION_RUN(name, function)                                                        \
  static const ::pd::verification::RunRegistrar PD_VERIFICATION_CONCAT(pd_verification_run_,       \
                                                                       __LINE__) {                 \
    name, function                                                                                 \
  }

/// Run options for a case's run into its own folder ctx.output_dir/name (overwrite), without VTU
/// files: what the cases on a user's scene run.
RunOutcome run_case_scene(const Context& ctx, const Scene& s, const std::string& run_name);

/// Half the length of the scene's first crack (a segment along x).
double crack_half_length(const Scene& s);

/// Run options for a case's run into its own folder ctx.output_dir/name: a rerun of the case
/// replaces its previous run (overwrite), including one written before runs kept a manifest.
RunOptions case_run_options(const Context& ctx, const std::string& name);

/// Default folder of the shared scenes: $PD_SCENES_DIR, else the source tree's
/// verification/scenes.
std::filesystem::path default_scenes_dir();

/// Released bar fixed at x = 0, free at x = L, u(x, 0) = εx (bar-vibration): the modal series
/// u(x, t) = Σ a_n sin(k_n x) cos(c k_n t), k_n = (2n − 1)π/(2L), a_n = 2ε(−1)^(n+1)/(L k_n²),
/// summed over 4000 modes.
double bar_modal_series(double x, double t, double strain, double length, double wave_speed);

/// Relative error |a − b|/|b|.
double relative_error(double value, double reference);

/// A numeric gate of a case: `limit` bounds out["error"][key] (|error| ≤ limit), or, for a key
/// "min_X", is a floor on out["pd"][X]. The report's scorecard draws a line per gate.
struct Gate {
  std::string key;
  double limit = 0;
};

/// Whether every gate holds on the case's JSON; a gated value the case did not write fails.
bool within_gates(const Json& out, const std::vector<Gate>& gates);

/// The last keys of a case's JSON: its gate in words, the verdict and its wall time since `start`.
void finish_case(Json& out, const std::string& gate, bool passed,
                 std::chrono::steady_clock::time_point start);

/// finish_case for numeric gates: `gate` becomes the object {key: limit}, and the case passes
/// when `passed` (what the gates do not cover: the run completed, ...) and every gate holds.
void finish_case(Json& out, const std::vector<Gate>& gates, bool passed,
                 std::chrono::steady_clock::time_point start);

} // namespace pd::verification
