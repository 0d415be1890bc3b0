#include "case_folders.hpp"

#include "scene_verification.hpp"
#include "structures.hpp"

#include <algorithm>
#include <cstdlib>
#include <fmt/format.h>
#include <set>
#include <stdexcept>
#include <yaml-cpp/yaml.h>

#ifndef PD_SOURCE_CASES_DIR
#define PD_SOURCE_CASES_DIR "verification/cases"
#endif

namespace pd::verification {

std::map<std::string, RunFunction>& registered_runs() {
  static std::map<std::string, RunFunction> runs;
  return runs;
}

RunRegistrar::RunRegistrar(const char* name, RunFunction run) {
  if (!registered_runs().emplace(name, run).second) {
    // Static initialisation: no one could catch an exception; two runs of one name is a build
    // mistake that must not reach a user.
    std::fprintf(stderr, "pd: verification run '%s' registered twice\n", name);
    std::abort();
  }
}

std::filesystem::path default_cases_dir() {
  if (const char* env = std::getenv("PD_CASES_DIR"); env != nullptr && *env != '\0') {
    return env;
  }
  return PD_SOURCE_CASES_DIR;
}

namespace {

std::runtime_error folder_error(const std::filesystem::path& file, const std::string& what) {
  return std::runtime_error(fmt::format("{}: {}", file.string(), what));
}

template <class T>
T required(const YAML::Node& node, const char* key, const std::filesystem::path& file,
           const std::string& where) {
  const YAML::Node value = node[key];
  if (!value) {
    throw folder_error(file, fmt::format("{}no `{}:`", where, key));
  }
  return value.as<T>();
}

RunInfo read_run(const YAML::Node& r, const std::string& kind, const std::filesystem::path& file) {
  RunInfo run;
  run.name = required<std::string>(r, "name", file, "a run has ");
  const std::string where = "run " + run.name + " has ";
  run.summary = required<std::string>(r, "summary", file, where);
  run.label = required<std::string>(r, "label", file, where);
  run.cpu_seconds = required<double>(r, "cpu_seconds", file, where);
  // label `none`: no ctest test (a sweep the report runs), so no ctest timeout either.
  run.timeout =
      run.label == "none" ? r["timeout"].as<int>(0) : required<int>(r, "timeout", file, where);
  run.gate = required<std::string>(r, "gate", file, where);
  if (r["threads"]) {
    run.threads = r["threads"].as<int>();
  }
  run.reference_kind = r["reference_kind"].as<std::string>("");
  if (kind == "scene") {
    run.scene = required<std::string>(r, "scene", file, where);
    run.tolerance = required<double>(r, "tolerance", file, where);
    if (r["fe_levels"]) {
      run.fe_levels = r["fe_levels"].as<int>();
    }
  }
  return run;
}

CaseFolder read_folder(const std::filesystem::path& folder) {
  const std::filesystem::path file = folder / "case.yaml";
  CaseFolder f;
  f.path = folder;
  try {
    const YAML::Node root = YAML::LoadFile(file.string());
    f.summary = required<std::string>(root, "summary", file, "");
    f.kind = required<std::string>(root, "kind", file, "");
    if (f.kind != "code" && f.kind != "structure" && f.kind != "scene") {
      throw folder_error(file, "kind '" + f.kind + "' is none of code, structure, scene");
    }
    f.references = root["references"].as<std::vector<std::string>>(std::vector<std::string>{});
    for (const YAML::Node& r : root["runs"]) {
      f.runs.push_back(read_run(r, f.kind, file));
    }
    if (f.runs.empty()) {
      throw folder_error(file, "no `runs:`");
    }
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(
        fmt::format("{}:{}:{}: {}", file.string(), e.mark.line + 1, e.mark.column + 1, e.msg));
  }
  return f;
}

/// What runs a structure folder's run: NAME at the paper's resolution, NAME-fast, NAME-sweep.
std::function<Json(const Context&)> structure_run(const CaseFolder& f, const RunInfo& run) {
  const std::string base = structure_case_name(f.path / "case.yaml");
  if (run.name == base) {
    return [](const Context& c) { return run_structure_case(c, false); };
  }
  if (run.name == base + "-fast") {
    return [](const Context& c) { return run_structure_case(c, true); };
  }
  if (run.name == base + "-sweep") {
    return [](const Context& c) { return run_structure_sweep_case(c); };
  }
  throw folder_error(f.path / "case.yaml",
                     fmt::format("run {} of a structure case '{}' is none of {}, {}-fast, {}-sweep",
                                 run.name, base, base, base, base));
}

/// `pd verify SCENE.yaml --gate T [--fe-levels N]` on the folder's scene.
std::function<Json(const Context&)> scene_run(const RunInfo& run) {
  SceneVerifyOptions options;
  options.gate = run.tolerance;
  options.fe_levels = run.fe_levels;
  const std::string scene = run.scene;
  return [options, scene](const Context& c) { return verify_scene(c.folder / scene, c, options); };
}

} // namespace

CaseSet discover_cases(const std::filesystem::path& cases_dir,
                       const std::map<std::string, RunFunction>& registry) {
  std::vector<std::filesystem::path> folders;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(cases_dir, ec)) {
    if (entry.is_directory() && std::filesystem::exists(entry.path() / "case.yaml")) {
      folders.push_back(entry.path());
    }
  }
  if (ec) {
    throw std::runtime_error(
        fmt::format("cannot read the case folders in {}: {}", cases_dir.string(), ec.message()));
  }
  std::sort(folders.begin(), folders.end());
  CaseSet set;
  set.folders.reserve(folders.size()); // Case keeps pointers into it
  for (const auto& folder : folders) {
    set.folders.push_back(read_folder(folder));
  }
  std::set<std::string> names;
  std::set<std::string> code_runs;
  for (const CaseFolder& f : set.folders) {
    for (const RunInfo& run : f.runs) {
      if (!names.insert(run.name).second) {
        throw folder_error(f.path / "case.yaml",
                           "run " + run.name + " is listed by another case folder too");
      }
      Case c{run.name, run.summary, &f, &run, {}};
      if (f.kind == "code") {
        const auto it = registry.find(run.name);
        if (it == registry.end()) {
          throw folder_error(f.path / "case.yaml",
                             "run " + run.name +
                                 " has no C++ function (PD_VERIFICATION_RUN) in this build");
        }
        c.run = it->second;
        code_runs.insert(run.name);
      } else if (f.kind == "structure") {
        c.run = structure_run(f, run);
      } else {
        c.run = scene_run(run);
      }
      set.cases.push_back(std::move(c));
    }
  }
  for (const auto& [name, function] : registry) {
    if (code_runs.count(name) == 0) {
      throw std::runtime_error(fmt::format(
          "verification run '{}' is registered (PD_VERIFICATION_RUN) but no case folder of kind "
          "code in {} lists it in its case.yaml",
          name, cases_dir.string()));
    }
  }
  return set;
}

Json cases_json(const CaseSet& set) {
  Json out = Json::array();
  for (const Case& c : set.cases) {
    Json row = Json::object();
    row["name"] = c.name;
    row["summary"] = c.summary;
    row["folder"] = c.folder->path.string();
    row["kind"] = c.folder->kind;
    row["label"] = c.info->label;
    row["cpu_seconds"] = c.info->cpu_seconds;
    row["threads"] = c.info->threads ? Json(*c.info->threads) : Json(nullptr);
    row["timeout"] = c.info->timeout;
    row["reference_kind"] = c.info->reference_kind;
    row["gate"] = c.info->gate;
    out.push_back(row);
  }
  return out;
}

} // namespace pd::verification
