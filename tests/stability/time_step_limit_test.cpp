// Time step at 0.98× and 1.05× the measured stability limit, through the CLI.
//
// The limit is measured with the library (`measure_stability`: bisection of the largest fixed
// Δt for which a bounded Verlet run from a small random perturbation does not grow). Then the
// scene is rewritten with a fixed `dt:` and `pd run` is executed:
//  * at 0.98× it must complete (exit code 0, status end_time) with finite output and an energy
//    within Verlet's shadow-energy bounds (no loads, fixed or no supports);
//  * at 1.05× it must be detected and stopped: exit code 3, the message of the foundation issue
//    on stderr (step, Δt and the eq. 31 limit), status `unstable` in summary.json, and no
//    non-finite value in any file written.
// The limit itself is compared with the sharp prediction 2/ω_max (Lanczos estimate of the
// largest frequency) and with eq. 31 (which must be below it).
#include "libpd/time/stability.hpp"
#include "stability_support.hpp"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <gtest/gtest.h>
#include <regex>
#include <sstream>
#include <sys/wait.h>

namespace fs = std::filesystem;

namespace {

std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

struct CliRun {
  int exit_code = -1;
  std::string stdout_text, stderr_text, summary;
  std::vector<std::string> nonfinite; ///< "file: token" for each nan/inf found
  std::size_t files = 0;
};

/// Write `scene_text` with the given Δt and end time, run `pd run` on it and collect its output.
CliRun run_cli(const std::string& scene_text, const std::string& tag, double dt,
               std::size_t steps) {
  const fs::path work = fs::path(PD_STABILITY_WORK_DIR) / tag;
  fs::remove_all(work);
  fs::create_directories(work);
  std::string text = std::regex_replace(scene_text, std::regex(R"(\n  dt: auto\n)"),
                                        fmt::format("\n  dt: {:.17g}\n", dt));
  text = std::regex_replace(text, std::regex(R"(\n  end_time: [^\n]*\n)"),
                            fmt::format("\n  end_time: {:.17g}\n", dt * (double(steps) - 0.5)));
  EXPECT_NE(text.find(fmt::format("dt: {:.17g}", dt)), std::string::npos);
  const fs::path scene = work / "scene.yaml";
  std::ofstream(scene) << text;
  const fs::path out = work / "out";
  const std::string cmd = fmt::format(
      "OMP_NUM_THREADS=1 '{}' run '{}' -o '{}' > '{}' 2> '{}'", PD_EXECUTABLE, scene.string(),
      out.string(), (work / "stdout.txt").string(), (work / "stderr.txt").string());
  const int status = std::system(cmd.c_str());
  CliRun r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.stdout_text = read_text(work / "stdout.txt");
  r.stderr_text = read_text(work / "stderr.txt");
  r.summary = read_text(out / "summary.json");
  // Every number the run wrote: no NaN or infinity in any spelling.
  const std::regex bad(R"((^|[^A-Za-z_])(nan|inf|infinity)([^A-Za-z_]|$))", std::regex::icase);
  if (fs::exists(out)) {
    for (const auto& entry : fs::directory_iterator(out)) {
      ++r.files;
      const std::string body = read_text(entry.path());
      std::smatch m;
      if (std::regex_search(body, m, bad)) {
        r.nonfinite.push_back(entry.path().filename().string() + ": " + m.str());
      }
    }
  }
  return r;
}

bool json_has(const std::string& json, const std::string& key, const std::string& prefix) {
  return std::regex_search(json, std::regex("\"" + key + "\"\\s*:\\s*\"" + prefix));
}

double json_number(const std::string& json, const std::string& key) {
  std::smatch m;
  if (std::regex_search(json, m, std::regex("\"" + key + R"(\"\s*:\s*([-+0-9.eE]+))"))) {
    return std::stod(m[1]);
  }
  return std::nan("");
}

void check_limit(const std::string& file, std::size_t steps) {
  const pd::Scene scene = stab::load(file);
  pd::StabilityOptions opt;
  opt.steps = 1000;
  opt.relative_tolerance = 0.005;
  const pd::StabilityResult st =
      pd::measure_stability(scene.model, scene.solver, pd::StabilityTarget{pd::IntegratorKind::verlet}, opt);
  ASSERT_GT(st.measured, 0.0);
  EXPECT_GE(st.measured, st.eq31) << "eq. 31 above the measured limit";
  // Central differences are stable up to ω_max Δt = 2; a bounded run cannot tell much beyond it.
  EXPECT_NEAR(st.measured / st.sharp, 1.0, 0.02) << "measured limit vs 2/ω_max";

  // Initial energy of the scene (strain energy of the released state), for the stable run.
  pd::Model model = pd::build_model(scene.model);
  const double e0 = pd::Simulation(model, scene.solver, scene.initial).strain_energy();

  const std::string text = read_text(fs::path(PD_STABILITY_SCENES_DIR) / file);
  const std::string stem = fs::path(file).stem().string();

  const CliRun ok = run_cli(text, stem + "-0.98", 0.98 * st.measured, steps);
  EXPECT_EQ(ok.exit_code, 0) << ok.stderr_text;
  EXPECT_TRUE(json_has(ok.summary, "status", "end_time")) << ok.summary;
  EXPECT_TRUE(ok.nonfinite.empty()) << ok.nonfinite.front();
  const double e_end =
      json_number(ok.summary, "kinetic_energy") + json_number(ok.summary, "strain_energy");
  // Started from rest without loads, Verlet's sampled energy lies in [E0 (1 − (ω_max Δt)²/4), E0]
  // (shadow energy, see stab::check_verlet_energy); ω_max Δt = 2 · 0.98 Δt_measured / sharp.
  const double w_dt = 2.0 * 0.98 * st.measured / st.sharp;
  EXPECT_LE(e_end / e0, 1.0 + 1e-5) << "energy grew at 0.98× the limit";
  EXPECT_GE(e_end / e0, 1.0 - 0.25 * w_dt * w_dt) << "energy lost beyond Verlet's bound";

  const CliRun bad = run_cli(text, stem + "-1.05", 1.05 * st.measured, steps);
  EXPECT_EQ(bad.exit_code, 3) << bad.stdout_text << bad.stderr_text;
  const std::regex message(
      R"(error: run became unstable at step (\d+) \(t = [^)]*\): .*Δt = ([0-9.e+-]+) s is [0-9.e+-]+× the stable limit ([0-9.e+-]+) s \(eq\. 31 × 1\))");
  std::smatch m;
  const bool matched = std::regex_search(bad.stderr_text, m, message);
  EXPECT_TRUE(matched) << "stderr: " << bad.stderr_text;
  std::size_t unstable_step = 0;
  if (matched) {
    unstable_step = std::stoul(m[1]);
    EXPECT_NEAR(std::stod(m[2]), 1.05 * st.measured, 1e-5 * st.measured);
    EXPECT_NEAR(std::stod(m[3]), st.eq31, 1e-5 * st.eq31);
    EXPECT_LT(unstable_step, steps);
  }
  EXPECT_TRUE(json_has(bad.summary, "status", "unstable")) << bad.summary;
  EXPECT_TRUE(json_has(bad.summary, "message", "run became unstable at step")) << bad.summary;
  EXPECT_TRUE(bad.nonfinite.empty()) << bad.nonfinite.front();
  EXPECT_GE(bad.files, 2u) << "summary.json and probes.csv are written even for unstable runs";

  fmt::print("limit {}: eq31 {:.5g} s, measured {:.5g} s = {:.4f} x eq31, sharp 2/w_max {:.5g} s "
             "(measured/sharp {:.4f}), bisection {} runs {:.2f} s; 0.98x: exit {}, E_end/E0 = "
             "{:.5f}; 1.05x: exit {}, stopped at step {} of {}\n",
             file, st.eq31, st.measured, st.measured / st.eq31, st.sharp, st.measured / st.sharp,
             st.runs, st.seconds, ok.exit_code, e_end / e0, bad.exit_code, unstable_step, steps);
}

TEST(StabilityTimeStepLimit, Bar) {
  check_limit("limit-bar.yaml", 5000);
}
TEST(StabilityTimeStepLimitFull, IrregularStiffBlock) {
  check_limit("limit-block.yaml", 3000);
}

} // namespace
