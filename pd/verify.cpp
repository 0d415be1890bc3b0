// pd verify [CASE...] [-o DIR] [--list [--json]] [--sweep [--quick]] [--scenes DIR] [--threads N]
// pd verify SCENE.yaml... [--fe-levels N] [--fe-coarse] [--gate FRACTION] [--junit FILE]
// Verification cases with their gates: CASE.json in DIR for each, exit code 2 if a gate fails.
// A scene file instead of a case name runs the scene beside its FE reference (pd-fem --scene).
// The cases are the folders of verification/cases (or $PD_CASES_DIR), read at run time.
#include "case_folders.hpp"
#include "commands.hpp"
#include "libpd/core/atomic_file.hpp"
#include "libpd/io/scene.hpp"
#include "scene_verification.hpp"
#include "verification.hpp"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fmt/format.h>
#include <memory>
#include <mutex>
#include <optional>
#include <unistd.h>
#include <vector>

namespace pd::cli {

namespace {

/// The finest FE mesh doubles the resolution this many times at most: a 3D scene's unknowns grow
/// eightfold per level, so more would not fit in memory for any scene worth verifying.
constexpr int max_fe_levels = 6;

struct VerifyArgs {
  std::vector<std::string> cases;
  std::string out_dir = "verification-out";
  bool list = false;
  bool json = false;
  bool sweep = false;
  bool quick = false;
  std::string scenes_dir;
  int threads = 0;
  verification::SceneVerifyOptions scene;
  int fe_levels = 0;
  double gate = 0;
  std::string junit;
};

std::string upper(std::string word) {
  std::transform(word.begin(), word.end(), word.begin(),
                 [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
  return word;
}

bool is_scene_file(const std::string& arg) {
  const auto ext = std::filesystem::path(arg).extension();
  return ext == ".yaml" || ext == ".yml";
}

std::string xml_escaped(const std::string& text) {
  std::string out;
  for (const char c : text) {
    switch (c) {
    case '&':
      out += "&amp;";
      break;
    case '<':
      out += "&lt;";
      break;
    case '>':
      out += "&gt;";
      break;
    case '"':
      out += "&quot;";
      break;
    default:
      out += c;
    }
  }
  return out;
}

std::string text_of(const Json& j, const std::string& key) {
  const Json* v = j.find(key);
  if (v == nullptr) {
    return {};
  }
  if (const auto t = v->text()) {
    return *t;
  }
  if (const auto x = v->number()) {
    return fmt::format("{:.9g}", *x);
  }
  if (const auto b = v->boolean()) {
    return *b ? "true" : "false";
  }
  return {};
}

double number_of(const Json& j, const std::string& key) {
  const Json* v = j.find(key);
  return v != nullptr ? v->number().value_or(std::nan("")) : std::nan("");
}

/// One <testcase> (the JUnit structure of Ant / Maven Surefire that Jenkins, GitLab and GitHub
/// read): a verdict `failed` is a <failure>, `measured` and `interrupted` are <skipped> (not
/// judged), `error` an <error>; the values go to <system-out>.
void junit_case(std::string& xml, const std::string& suite, const std::string& name, double seconds,
                const std::string& verdict, const std::string& message, const std::string& out) {
  xml += fmt::format("    <testcase classname=\"{}\" name=\"{}\" time=\"{:.3f}\">\n",
                     xml_escaped(suite), xml_escaped(name), seconds);
  if (verdict == "failed") {
    xml += fmt::format("      <failure message=\"{}\" type=\"verification\">{}</failure>\n",
                       xml_escaped(message), xml_escaped(out));
  } else if (verdict == "error") {
    xml += fmt::format("      <error message=\"{}\" type=\"error\"/>\n", xml_escaped(message));
  } else if (verdict != "passed") {
    xml += fmt::format("      <skipped message=\"{}\"/>\n", xml_escaped(message));
  }
  if (!out.empty()) {
    xml += fmt::format("      <system-out>{}</system-out>\n", xml_escaped(out));
  }
  xml += "    </testcase>\n";
}

/// What pd verify has done, in DIR/summary.json: each case's verdict, written at the end and, on
/// a stop request, at once (by the watchdog of app/interrupt.hpp while a case cannot stop): the
/// cases finished keep their verdicts, the one running and the rest are `interrupted`, none is
/// FAILED for it, and the command exits 5.
class Ledger {
public:
  Ledger(const std::string& out_dir, std::vector<std::string> names)
      : dir_(out_dir), names_(std::move(names)), verdicts_(names_.size()), results_(names_.size()) {
  }

  void finish(std::size_t k, bool passed, Json result) {
    record(k, passed ? "passed" : "failed", std::move(result));
  }
  /// A scene's verdict: passed, failed or measured (scene_verification.hpp), or "error" where it
  /// could not run; `result` is what its JSON file holds.
  void record(std::size_t k, const std::string& verdict, Json result) {
    const std::lock_guard lock(mutex_);
    verdicts_[k] = verdict;
    results_[k] = std::move(result);
  }
  /// How many cases have this verdict.
  std::size_t count(const std::string& verdict) const {
    const std::lock_guard lock(mutex_);
    return static_cast<std::size_t>(std::count(verdicts_.begin(), verdicts_.end(), verdict));
  }
  /// --junit FILE: the verdicts as JUnit XML too, written with summary.json.
  void junit_to(std::string file) { junit_ = std::move(file); }

  /// `sig`: the signal that stopped the command, 0 if it ran to its end.
  void write(int sig) const {
    const std::lock_guard lock(mutex_);
    Json j = Json::object();
    j["command"] = "verify";
    bool failed = false;
    bool measured = false;
    Json cases = Json::array();
    for (std::size_t k = 0; k < names_.size(); ++k) {
      Json c = Json::object();
      c["name"] = names_[k];
      c["status"] = verdicts_[k].empty() ? "interrupted" : verdicts_[k];
      failed = failed || verdicts_[k] == "failed" || verdicts_[k] == "error";
      measured = measured || verdicts_[k] == "measured";
      cases.push_back(std::move(c));
    }
    // A run with a scene measured but not judged did not pass: it has no verdict to give.
    j["status"] = sig != 0 ? "interrupted" : failed ? "failed" : measured ? "measured" : "passed";
    if (sig != 0) {
      j["stop_signal"] = sig;
    }
    j["cases"] = std::move(cases);
    std::filesystem::create_directories(dir_);
    write_file_atomically(dir_ / "summary.json", j.dump());
    if (!junit_.empty()) {
      write_file_atomically(junit_, junit());
    }
  }

private:
  /// One <testsuite> per case or scene: a scene has one <testcase> per probe (PD, FE, their
  /// difference, tolerance and FE error estimate) and one, `verdict`, for what judges the scene
  /// as a whole (same materials, a PD equilibrium); a case has one <testcase>, its gate.
  std::string junit() const {
    std::string suites;
    std::size_t all_tests = 0, all_failures = 0, all_errors = 0, all_skipped = 0;
    double all_seconds = 0;
    for (std::size_t k = 0; k < names_.size(); ++k) {
      const std::string verdict = verdicts_[k].empty() ? "interrupted" : verdicts_[k];
      const Json& r = results_[k];
      const double seconds =
          r.find("wall_seconds") != nullptr ? r.find("wall_seconds")->number().value_or(0.0) : 0.0;
      std::string cases;
      std::size_t tests = 0, failures = 0, errors = 0, skipped = 0;
      const auto add = [&](const std::string& name, const std::string& v, const std::string& why,
                           const std::string& out) {
        ++tests;
        failures += v == "failed" ? 1 : 0;
        errors += v == "error" ? 1 : 0;
        skipped += v != "passed" && v != "failed" && v != "error" ? 1 : 0;
        junit_case(cases, names_[k], name, tests == 1 ? seconds : 0.0, v, why, out);
      };
      const std::string not_judged = verdict == "interrupted" ? "interrupted before it finished"
                                     : verdict == "measured"
                                         ? "measured, not judged: " + text_of(r, "not_judged")
                                         : std::string();
      std::string reasons;
      if (const Json* list = r.find("reasons")) {
        reasons = list->dump(0);
        while (!reasons.empty() && reasons.back() == '\n') {
          reasons.pop_back();
        }
      }
      const Json* probes = r.find("probes");
      if (probes != nullptr && probes->items() != nullptr) {
        // Probes: each judged on its own tolerance.
        // The scene's own conditions: failed where a reason (other than a probe beyond the
        // gate, which its probe's testcase reports) says PD and FE are not comparable.
        const Json::Array* why =
            r.find("reasons") != nullptr ? r.find("reasons")->items() : nullptr;
        const bool comparable = why == nullptr || why->empty() ||
                                (why->size() == 1 && reasons.find("the gate") != std::string::npos);
        add("verdict",
            verdict == "measured" || verdict == "interrupted" ? verdict
            : comparable                                      ? "passed"
                                                              : "failed",
            comparable ? not_judged : reasons,
            fmt::format("PD status {}, PD {} s, FE {} s, reasons {}", text_of(r, "pd_status"),
                        text_of(r, "pd_seconds"), text_of(r, "fe_seconds"), reasons));
        for (const Json& p : *probes->items()) {
          const std::string within = text_of(p, "within_tolerance");
          const std::string v = verdict == "interrupted"   ? "interrupted"
                                : text_of(p, "pd").empty() ? "failed"
                                : within.empty()           ? "measured"
                                : within == "true"         ? "passed"
                                                           : "failed";
          add(text_of(p, "name"), v,
              v == "failed"     ? fmt::format("|PD - FE| = {:.6g} exceeds the tolerance {}",
                                              std::abs(number_of(p, "pd") - number_of(p, "fe")),
                                              text_of(p, "tolerance"))
              : v == "measured" ? not_judged
                                : std::string(v == "interrupted" ? not_judged : ""),
              fmt::format("quantity {}, PD {}, FE {}, relative difference {}, judged difference "
                          "{}, tolerance {}, FE error estimate {}{}",
                          text_of(p, "quantity"), text_of(p, "pd"), text_of(p, "fe"),
                          text_of(p, "relative_difference"), text_of(p, "judged_difference"),
                          text_of(p, "tolerance").empty() ? "none" : text_of(p, "tolerance"),
                          text_of(p, "fe_error_estimate"),
                          text_of(p, "note").empty() ? "" : ", " + text_of(p, "note")));
        }
      } else {
        add(names_[k], verdict,
            verdict == "failed"  ? "the gate failed"
            : verdict == "error" ? text_of(r, "error")
                                 : not_judged,
            text_of(r, "gate"));
      }
      all_tests += tests;
      all_failures += failures;
      all_errors += errors;
      all_skipped += skipped;
      all_seconds += seconds;
      suites += fmt::format("  <testsuite name=\"{}\" tests=\"{}\" failures=\"{}\" errors=\"{}\" "
                            "skipped=\"{}\" time=\"{:.3f}\">\n",
                            xml_escaped(names_[k]), tests, failures, errors, skipped, seconds);
      suites += cases;
      suites += "  </testsuite>\n";
    }
    return fmt::format("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<testsuites name=\"pd verify\" "
                       "tests=\"{}\" failures=\"{}\" errors=\"{}\" skipped=\"{}\" "
                       "time=\"{:.3f}\">\n{}</testsuites>\n",
                       all_tests, all_failures, all_errors, all_skipped, all_seconds, suites);
  }

  mutable std::mutex mutex_;
  std::filesystem::path dir_;
  std::vector<std::string> names_;
  std::vector<std::string> verdicts_; ///< "passed", "failed", "measured", or empty while running
  std::vector<Json> results_;         ///< each case's JSON, once finished
  std::string junit_;
};

/// The end of pd verify: the summary, the count and the exit status (2 if a gate failed, 5 if
/// interrupted). A scene measured without a tolerance is counted as measured, not as passed.
int conclude(const Ledger& ledger, const InterruptGuard& interrupt, int failed) {
  ledger.write(interrupt.signal());
  if (interrupt.requested()) {
    fmt::print(stderr, "interrupted by signal {}: the cases not finished are not judged\n",
               interrupt.signal());
    return exit_interrupted;
  }
  const std::size_t measured = ledger.count("measured");
  fmt::print("{} passed, {}{} failed\n", ledger.count("passed"),
             measured > 0 ? fmt::format("{} measured (not judged), ", measured) : std::string(),
             failed);
  return failed > 0 ? 2 : 0;
}

/// pd verify SCENE.yaml: the scene against its FE reference; exit 1 if it cannot run, 2 if the
/// gate fails.
int verify_scenes(const VerifyArgs& a, const verification::Context& ctx) {
  const InterruptGuard interrupt(true);
  std::vector<std::string> names;
  for (const std::string& file : a.cases) {
    names.push_back(std::filesystem::path(file).stem().string());
  }
  Ledger ledger(a.out_dir, names);
  ledger.junit_to(a.junit);
  const AbandonOnInterrupt abandon([&ledger](int sig) { ledger.write(sig); });
  int failed = 0;
  // A scene that cannot run ends the command (exit 1), its error recorded.
  const auto error = [&](std::size_t k, const std::string& what) {
    fmt::print(stderr, "{}\n", what);
    Json e = Json::object();
    e["error"] = what;
    ledger.record(k, "error", std::move(e));
    ledger.write(interrupt.signal());
    return 1;
  };
  for (std::size_t k = 0; k < a.cases.size() && !interrupt.requested(); ++k) {
    const std::string& file = a.cases[k];
    fmt::print("== {} — PD vs deal.II on the same continuum problem\n", file);
    std::fflush(stdout);
    const auto t0 = std::chrono::steady_clock::now();
    Json result;
    try {
      result = verification::verify_scene(file, ctx, a.scene);
    } catch (const SceneError& e) {
      return error(k, e.what());
    } catch (const std::exception& e) {
      return error(k, fmt::format("error: {}", e.what()));
    }
    if (interrupt.requested()) {
      break; // its run stopped early: no verdict
    }
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    result["wall_seconds"] = wall;
    const std::string& name = names[k];
    write_file_atomically(std::filesystem::path(a.out_dir) / (name + ".json"), result.dump());
    const std::string verdict = result.find("verdict")->text().value_or("failed");
    fmt::print("   {} in {:.1f} s -> {}/{}.json\n", upper(verdict), wall, a.out_dir, name);
    if (verdict == "measured") {
      fmt::print("   (measured, not judged: {})\n",
                 result.find("not_judged")->text().value_or("no --gate"));
    }
    ledger.record(k, verdict, std::move(result));
    failed += verdict == "failed" ? 1 : 0;
  }
  return conclude(ledger, interrupt, failed);
}

/// Run one case, write its JSON and say whether its gate passed; nothing if a stop request
/// came while it ran (its runs ended early, so its numbers are not its result).
std::optional<std::pair<bool, Json>> run_case(const verification::Case& c,
                                              verification::Context ctx, const std::string& out_dir,
                                              const InterruptGuard& interrupt) {
  fmt::print("== {} — {}\n", c.name, c.summary);
  std::fflush(stdout);
  ctx.folder = c.folder->path;
  ctx.case_folder = c.folder;
  ctx.run = c.info;
  const auto t0 = std::chrono::steady_clock::now();
  Json result = c.run(ctx);
  if (interrupt.requested()) {
    fmt::print("   interrupted\n");
    return std::nullopt;
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  result["wall_seconds"] = wall;
  write_file_atomically(std::filesystem::path(out_dir) / (c.name + ".json"), result.dump());
  const Json* verdict = result.find("passed");
  const bool passed = verdict != nullptr && verdict->boolean().value_or(false);
  fmt::print("   {} in {:.1f} s -> {}/{}.json\n", passed ? "PASSED" : "FAILED", wall, out_dir,
             c.name);
  return std::pair{passed, std::move(result)};
}

int verify(const VerifyArgs& a) {
  set_threads(a.threads);
  verification::Context ctx;
  ctx.scenes_dir = a.scenes_dir.empty() ? verification::default_scenes_dir()
                                        : std::filesystem::path(a.scenes_dir);
  ctx.output_dir = a.out_dir;
  ctx.quick = a.quick;
  ctx.progress = ::isatty(STDERR_FILENO) != 0;
  if (!a.list && !a.cases.empty() && std::all_of(a.cases.begin(), a.cases.end(), is_scene_file)) {
    VerifyArgs scene_args = a;
    if (a.fe_levels > 0) {
      scene_args.scene.fe_levels = a.fe_levels;
    }
    if (a.gate > 0) { // the option's check admits only (0, 1]; 0 is "not given"
      scene_args.scene.gate = a.gate;
    }
    return verify_scenes(scene_args, ctx);
  }
  const verification::CaseSet set = verification::discover_cases(verification::default_cases_dir());
  const auto& cases = set.cases;
  if (a.list && a.json) {
    fmt::print("{}\n", verification::cases_json(set).dump());
    return 0;
  }
  if (a.list) {
    for (const auto& c : cases) {
      fmt::print("{:<20} {}\n", c.name, c.summary);
    }
    return 0;
  }
  const InterruptGuard interrupt(true);
  std::vector<const verification::Case*> selected;
  for (const auto& case_name : a.cases) {
    // --sweep runs each named case's accuracy-vs-time sweep, the case CASE-sweep.
    const std::string name = a.sweep ? case_name + "-sweep" : case_name;
    auto it =
        std::find_if(cases.begin(), cases.end(), [&](const auto& c) { return c.name == name; });
    if (it == cases.end()) {
      fmt::print(stderr, "error: unknown verification case '{}' (see pd verify --list)\n", name);
      return 1;
    }
    selected.push_back(&*it);
  }
  if (selected.empty()) {
    for (const auto& c : cases) {
      selected.push_back(&c);
    }
  }
  std::vector<std::string> names;
  for (const auto* c : selected) {
    names.push_back(c->name);
  }
  Ledger ledger(a.out_dir, names);
  ledger.junit_to(a.junit);
  const AbandonOnInterrupt abandon([&ledger](int sig) { ledger.write(sig); });
  int failed = 0;
  for (std::size_t k = 0; k < selected.size() && !interrupt.requested(); ++k) {
    auto outcome = run_case(*selected[k], ctx, a.out_dir, interrupt);
    if (outcome) {
      ledger.finish(k, outcome->first, std::move(outcome->second));
      failed += outcome->first ? 0 : 1;
    }
  }
  return conclude(ledger, interrupt, failed);
}

} // namespace

Command add_verify_command(CLI::App& app) {
  auto a = std::make_shared<VerifyArgs>();
  auto* cmd = app.add_subcommand("verify", "Run verification cases; exit code 2 if a gate fails");
  cmd->add_option("cases", a->cases,
                  "case names (default: all), or scene files (.yaml) to verify against FE");
  cmd->add_option("-o,--output", a->out_dir, "output folder")->capture_default_str();
  cmd->add_flag("--list", a->list, "list the cases");
  cmd->add_flag("--json", a->json,
                "with --list: a JSON array, one object per case with its folder and metadata");
  cmd->add_flag("--quick", a->quick,
                "the default report's extent: with --sweep the case file's quick_sweep lists "
                "where it has them; rc-beam without its s0 sensitivity runs");
  cmd->add_flag("--sweep", a->sweep,
                "run the accuracy-vs-time sweep of each named case (the case CASE-sweep): one "
                "JSON row per run in DIR/CASE-sweep.jsonl");
  cmd->add_option("--scenes", a->scenes_dir, "folder with the shipped scenes");
  cmd->add_option("--fe-levels", a->fe_levels,
                  "scene files: number of FE meshes (pd-fem --levels; default its own)")
      ->check(CLI::Range(1, max_fe_levels));
  cmd->add_flag("--fe-coarse", a->scene.fe_coarse, "scene files: pd-fem --coarse (quick check)");
  cmd->add_option("--gate", a->gate,
                  "scene files: fail (exit 2) if a probe's |PD − FE| exceeds this fraction of "
                  "max(|FE|, a tenth of the largest |FE| of its quantity); without it the "
                  "result is measured, not passed")
      ->check(CLI::Validator(
          [](std::string& text) -> std::string {
            const double v = std::strtod(text.c_str(), nullptr);
            return std::isfinite(v) && v > 0 && v <= 1 ? "" : "must be a fraction in (0, 1]";
          },
          "FRACTION in (0, 1]"));
  cmd->add_option("--junit", a->junit,
                  "also write the verdicts as JUnit XML to FILE (one testsuite per case or scene, "
                  "one testcase per probe; failed is a failure, measured and interrupted are "
                  "skipped) for CI systems");
  add_threads_option(*cmd, a->threads);
  return {cmd, [a] { return verify(*a); }, true};
}

} // namespace pd::cli
