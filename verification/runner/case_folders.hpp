// The case folders: verification/cases/<folder>/case.yaml read into one schema, and the runs they
// list, each bound to what runs it (a registered C++ function, the structure runner or the scene
// comparison). `pd verify`, `pd verify --list [--json]` and the ctest include script
// (verification_tests.cmake) all read the folders through this, so a new folder is a new case.
#pragma once

#include "verification.hpp"

#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace pd::verification {

/// One `runs:` entry of a case.yaml: one `pd verify NAME`.
struct RunInfo {
  std::string name;
  std::string summary; ///< what `pd verify --list` prints
  std::string label; ///< ctest label: verification (default run), verification-full; none: no test
  double cpu_seconds = 0;       ///< expected CPU seconds (the report's estimate)
  std::optional<int> threads;   ///< OMP_NUM_THREADS of its ctest run; none: ctest's own
  int timeout = 0;              ///< ctest TIMEOUT in seconds
  std::string reference_kind;   ///< what the report's scorecard calls the reference
  std::string gate;             ///< the gate in words
  std::string scene;            ///< kind scene: the scene file, relative to the folder
  double tolerance = 0;         ///< kind scene: the relative gate (pd verify SCENE --gate)
  std::optional<int> fe_levels; ///< kind scene: pd-fem --levels
};

struct CaseFolder {
  std::filesystem::path path; ///< the folder
  std::string summary;
  std::string kind; ///< code | structure | scene
  std::vector<std::string> references;
  std::vector<RunInfo> runs;
};

/// A run ready to go: its folder and entry, and what runs it.
struct Case {
  std::string name;
  std::string summary;
  const CaseFolder* folder = nullptr;
  const RunInfo* info = nullptr;
  std::function<Json(const Context&)> run;
};

/// The folders' case.yaml files read, checked and bound to their runners.
struct CaseSet {
  CaseSet() = default;
  CaseSet(CaseSet&&) = default; ///< a move keeps the folders where `cases` points
  CaseSet& operator=(CaseSet&&) = default;
  CaseSet(const CaseSet&) = delete;
  CaseSet& operator=(const CaseSet&) = delete;

  std::vector<CaseFolder> folders;
  std::vector<Case> cases; ///< folder by folder (folder name order), runs in case.yaml order
};

/// Read CASES_DIR/*/case.yaml. `code` runs are looked up in `registry`; a listed run with no
/// function, a registered function no folder lists, a run name used twice or a missing key is an
/// error (std::runtime_error) naming the folder or the run.
CaseSet discover_cases(const std::filesystem::path& cases_dir,
                       const std::map<std::string, RunFunction>& registry = registered_runs());

/// Default case folders: $PD_CASES_DIR, else the source tree's verification/cases.
std::filesystem::path default_cases_dir();

/// `pd verify --list --json`: one object per run (name, summary, folder, kind, label,
/// cpu_seconds, threads, timeout, reference_kind, gate).
Json cases_json(const CaseSet& set);

} // namespace pd::verification
