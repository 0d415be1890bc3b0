// Linear-elastic structures of Miranda et al. 2019 §5.1 (clamped beam, cantilever, plate with three
// edges clamped) against the deal.II reference of the same continuum and against beam/plate theory.
//
// Each case is data: the case.yaml of a case folder of kind `structure` names the scene, the FE
// reference, the quantities (points) and deflection lines, the gates and a coarse CI variant. This
// file turns such a description into runs and a case JSON.
//
// Where PD is evaluated: particles sit at cell centres, so a point such as the beam's centre line
// (y = b/2, z = h/2) or the plate's free edge (y = 3 m) generally lies between particle layers or
// half a spacing outside the outer layer. The PD value there is the trilinear (2D scenes:
// bilinear, points of two coordinates) interpolation between the two nearest layers in each
// direction (linear extrapolation for points on the surface), so PD and FE are compared at the
// same physical point. The deflection is −u_z, in 2D −u_y.
//
// Steady state, not step counts: the run stops at the scene's steady-state tolerance. The
// paper-resolution case of a dynamic-relaxation scene also reruns with a 10× tighter tolerance and
// reports the difference as the relaxation error, separately from the discretisation error (PD at
// the tight tolerance vs FE); a static-solver scene reports its solve's residual instead (the
// rerun would be the same solve).
#include "structures.hpp"

#include "libpd/app/run.hpp"
#include "libpd/discretisation/corrections.hpp"
#include "libpd/io/scene.hpp"
#include "observed_order.hpp"
#include "section_stiffness.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <yaml-cpp/yaml.h>

#ifndef PD_FEM_REFERENCE_DIR
#define PD_FEM_REFERENCE_DIR "fem_reference/reference"
#endif

namespace pd::verification {

namespace {

struct PointQuantity {
  std::string name;
  std::string fe_key;
  Vec3 point{};
};

struct LineQuantity {
  std::string name;
  std::string fe_csv;
  int along = 0;
  Vec3 through{};
};

struct CorrectionPair {
  std::string label; ///< as the case file writes it: "surface+volume", e.g. "energy+linear"
  SurfaceCorrection surface = SurfaceCorrection::none;
  VolumeCorrection volume = VolumeCorrection::none;
};

struct StructureCase {
  std::string name;
  std::string scene;
  std::string fe_reference;
  std::string theory;
  std::vector<PointQuantity> quantities;
  std::vector<LineQuantity> lines;
  std::map<std::string, double> gate;
  double fast_spacing = 0;
  std::map<std::string, double> fast_stored;
  double fast_regression_tolerance = 0;
  std::map<std::string, double> fast_gate;
  /// Accuracy-vs-time sweep: each knob is varied on its own around the scene's settings.
  std::vector<double> sweep_spacing;
  std::vector<double> sweep_horizon_factor;
  std::vector<std::string> sweep_stretch;
  std::vector<double> sweep_force_tolerance;
  /// Surface + volume correction pairs the structural scenes ran with before the library's
  /// defaults (ghost + gradient), so the sweep shows what the defaults bought.
  std::vector<CorrectionPair> sweep_corrections;
  /// Section-stiffness error budget (section_stiffness.hpp): axes of the main body; only for a
  /// case file with a `section:` block.
  bool has_section = false;
  int section_span = 0;
  int section_depth = 2;
  bool section_plate = false;
};

Vec3 read_vec3(const YAML::Node& n) {
  Vec3 v{0, 0, 0};
  for (std::size_t k = 0; k < n.size() && k < 3; ++k) {
    v[k] = n[k].as<double>();
  }
  return v;
}

std::map<std::string, double> read_map(const YAML::Node& n) {
  std::map<std::string, double> m;
  if (n) {
    for (const auto& kv : n) {
      m[kv.first.as<std::string>()] = kv.second.as<double>();
    }
  }
  return m;
}

/// "surface+volume" of a case file's sweep, checked against the scene format's words before any
/// run starts.
CorrectionPair correction_pair(const std::string& text, const std::filesystem::path& file) {
  const auto plus = text.find('+');
  const auto surface = from_name<SurfaceCorrection>(text.substr(0, plus));
  const auto volume =
      plus == std::string::npos ? std::nullopt : from_name<VolumeCorrection>(text.substr(plus + 1));
  if (!surface || !volume) {
    throw std::runtime_error(fmt::format(
        "{}: sweep corrections '{}': expected SURFACE+VOLUME, SURFACE one of {}, VOLUME one of {}",
        file.string(), text, fmt::join(enum_words<SurfaceCorrection>, ", "),
        fmt::join(enum_words<VolumeCorrection>, ", ")));
  }
  return {text, *surface, *volume};
}

/// `quick`: the sweep is the file's `quick_sweep:` block if it has one (what the default report
/// runs), else its `sweep:`.
StructureCase load_case(const std::filesystem::path& file, bool quick = false) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(file.string());
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(
        fmt::format("{}:{}:{}: {}", file.string(), e.mark.line + 1, e.mark.column + 1, e.msg));
  }
  StructureCase c;
  try {
    c.name = root["case"].as<std::string>();
    c.scene = root["scene"].as<std::string>();
    c.fe_reference = root["fe_reference"].as<std::string>();
    c.theory = root["theory"].as<std::string>();
    for (const auto& q : root["quantities"]) {
      c.quantities.push_back(
          {q["name"].as<std::string>(), q["fe"].as<std::string>(), read_vec3(q["point"])});
    }
    for (const auto& l : root["lines"]) {
      c.lines.push_back({l["name"].as<std::string>(), l["fe_csv"].as<std::string>(),
                         axis_of(l["along"].as<std::string>()), read_vec3(l["through"])});
    }
    c.gate = read_map(root["gate"]);
    if (const auto sec = root["section"]) {
      c.has_section = true;
      c.section_span = axis_of(sec["span"].as<std::string>());
      c.section_depth = axis_of(sec["depth"].as<std::string>());
      c.section_plate = sec["plate"].as<bool>(false);
    }
    if (const auto fast = root["fast"]) {
      c.fast_spacing = fast["spacing"].as<double>();
      c.fast_stored = read_map(fast["stored"]);
      c.fast_regression_tolerance = fast["regression_tolerance"].as<double>(0.0);
      c.fast_gate = read_map(fast["gate"]);
    }
    if (const auto sw = quick && root["quick_sweep"] ? root["quick_sweep"] : root["sweep"]) {
      c.sweep_spacing = sw["spacing"].as<std::vector<double>>(std::vector<double>{});
      c.sweep_horizon_factor = sw["horizon_factor"].as<std::vector<double>>(std::vector<double>{});
      c.sweep_stretch = sw["stretch"].as<std::vector<std::string>>(std::vector<std::string>{});
      c.sweep_force_tolerance =
          sw["force_tolerance"].as<std::vector<double>>(std::vector<double>{});
      for (const auto& pair :
           sw["corrections"].as<std::vector<std::string>>(std::vector<std::string>{})) {
        c.sweep_corrections.push_back(correction_pair(pair, file));
      }
    }
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(fmt::format("{}:{}:{}: bad case description: {}", file.string(),
                                         e.mark.line + 1, e.mark.column + 1, e.msg));
  }
  return c;
}

/// Deflection sampled along a line of the FE solution: (position along the line's axis, value).
std::vector<std::pair<double, double>> load_fe_line(const std::filesystem::path& csv, int along) {
  std::ifstream in(csv);
  if (!in) {
    throw std::runtime_error("cannot read FE line " + csv.string() +
                             " (run pd-fem to regenerate fem_reference/reference)");
  }
  std::string header;
  std::getline(in, header);
  std::vector<std::string> names;
  {
    std::stringstream hs(header);
    std::string col;
    while (std::getline(hs, col, ',')) {
      names.push_back(col);
    }
  }
  const auto find = [&](const std::string& n) {
    const auto it = std::find(names.begin(), names.end(), n);
    if (it == names.end()) {
      throw std::runtime_error(csv.string() + ": no column '" + n + "'");
    }
    return static_cast<std::size_t>(it - names.begin());
  };
  const std::size_t col_pos = find(std::string(1, "xyz"[along]));
  const std::size_t col_val = find("deflection");
  std::vector<std::pair<double, double>> out;
  std::string line;
  while (std::getline(in, line)) {
    std::vector<double> v;
    std::stringstream ls(line);
    std::string cell;
    while (std::getline(ls, cell, ',')) {
      v.push_back(std::stod(cell));
    }
    if (v.size() > std::max(col_pos, col_val)) {
      out.emplace_back(v[col_pos], v[col_val]);
    }
  }
  return out;
}

double interpolate(const std::vector<std::pair<double, double>>& f, double x) {
  if (f.empty()) {
    return std::nan("");
  }
  if (x <= f.front().first) {
    return f.front().second;
  }
  for (std::size_t k = 1; k < f.size(); ++k) {
    if (x <= f[k].first) {
      const double w = (x - f[k - 1].first) / (f[k].first - f[k - 1].first);
      return (1 - w) * f[k - 1].second + w * f[k].second;
    }
  }
  return f.back().second;
}

/// Downward deflection of the final PD field (−u_z; 2D: −u_y), interpolated from lattice layers.
class DeflectionField {
public:
  DeflectionField(const RunOutcome& run, const LatticeSpec& lattice, const Region& body, int dim)
      : run_(run), lattice_(lattice), dim_(dim) {
    const double tol = 1e-6 * lattice.spacing;
    for (std::size_t i = 0; i < run.positions.size(); ++i) {
      if (!body.contains(run.positions[i], dim_, tol)) {
        continue; // supports are not part of the measured body
      }
      std::array<long long, 3> key{};
      for (int a = 0; a < dim_; ++a) {
        key[a] = index(a, run.positions[i][a]);
        layers_[a].insert(key[a]);
      }
      particle_[key] = i;
    }
  }

  /// Interpolated deflection at p: bilinear (2D) or trilinear (3D) between the particle layers
  /// around it; coordinates beyond the dimension are ignored.
  double at(const Vec3& p) const {
    using Weights = std::array<std::pair<long long, double>, 2>;
    std::array<Weights, 3> w{};
    for (int a = 0; a < 3; ++a) {
      // An axis beyond the dimension has the one layer 0: a weight of 1 and one of 0 on itself.
      w[a] = a < dim_ ? weights(a, p[a]) : Weights{{{0, 1.0}, {0, 0.0}}};
    }
    const auto vertical = static_cast<std::size_t>(dim_ - 1);
    double sum = 0;
    for (const auto& [i, wi] : w[0]) {
      for (const auto& [j, wj] : w[1]) {
        for (const auto& [k, wk] : w[2]) {
          const auto it = particle_.find({i, j, k});
          if (it == particle_.end()) {
            return std::nan("");
          }
          sum += wi * wj * wk * -run_.displacement[3 * it->second + vertical];
        }
      }
    }
    return sum;
  }

  /// Positions of the particle layers along an axis.
  std::vector<double> layer_positions(int axis) const {
    std::vector<double> out;
    for (long long n : layers_[axis]) {
      out.push_back(coordinate(axis, n));
    }
    return out;
  }

private:
  double shift() const {
    return lattice_.convention == LatticeConvention::cell_centered ? 0.5 : 0.0;
  }
  long long index(int a, double x) const {
    return std::llround((x - lattice_.origin[a]) / lattice_.spacing - shift());
  }
  double coordinate(int a, long long n) const {
    return lattice_.origin[a] + (static_cast<double>(n) + shift()) * lattice_.spacing;
  }
  /// The two layers bracketing x (or the two outermost for x beyond the outer layer) and their
  /// linear weights.
  std::array<std::pair<long long, double>, 2> weights(int a, double x) const {
    const auto& l = layers_[a];
    if (l.size() < 2) {
      throw std::runtime_error("deflection field: fewer than two particle layers");
    }
    const double t = (x - lattice_.origin[a]) / lattice_.spacing - shift();
    long long lo = static_cast<long long>(std::floor(t));
    lo = std::clamp(lo, *l.begin(), *std::prev(l.end(), 2));
    const double w = t - static_cast<double>(lo);
    if (std::abs(w) < 1e-9) {
      return {{{lo, 1.0}, {lo + 1, 0.0}}};
    }
    return {{{lo, 1.0 - w}, {lo + 1, w}}};
  }

  const RunOutcome& run_;
  LatticeSpec lattice_;
  int dim_ = 3;
  std::array<std::set<long long>, 3> layers_;
  std::map<std::array<long long, 3>, std::size_t> particle_;
};

Json run_once(const Scene& scene, const StructureCase& c, const Context& ctx,
              const std::string& tag, std::map<std::string, double>& values,
              std::map<std::string, double>& line_error, RunOutcome& outcome,
              bool write_vtu = true) {
  RunOptions opt = case_run_options(ctx, c.name + tag);
  opt.write_vtu = write_vtu;
  opt.keep_final_field = true;
  outcome = run_scene(scene, opt);
  if (outcome.result.status == RunStatus::unstable) {
    throw std::runtime_error(c.name + ": " + outcome.result.message);
  }
  const DeflectionField field(outcome, scene.model.lattice, scene.model.bodies.front().region,
                              scene.model.dimension.dim);
  for (const auto& q : c.quantities) {
    values[q.name] = field.at(q.point);
  }
  Json lines = Json::object();
  for (const auto& l : c.lines) {
    const auto fe = load_fe_line(std::filesystem::path(PD_FEM_REFERENCE_DIR) / l.fe_csv, l.along);
    double fe_max = 0;
    for (const auto& [x, v] : fe) {
      fe_max = std::max(fe_max, std::abs(v));
    }
    Json rows = Json::array();
    double worst = 0;
    for (double x : field.layer_positions(l.along)) {
      Vec3 p = l.through;
      p[l.along] = x;
      const double pd_value = field.at(p);
      const double fe_value = interpolate(fe, x);
      worst = std::max(worst, std::abs(pd_value - fe_value) / fe_max);
      rows.push_back(Json(Json::Array{x, pd_value, fe_value}));
    }
    line_error[l.name] = worst;
    Json& lj = lines[l.name];
    lj["columns"] = Json::array_of(std::vector<std::string>{"position", "pd", "fe"});
    lj["rows"] = rows;
    lj["max_difference_over_max_fe"] = worst;
  }
  return lines;
}

/// The section-stiffness error budget of a scene's main body.
SectionStiffness section_of(const Scene& scene, const StructureCase& c) {
  return section_stiffness(scene.model, scene.model.bodies.front(), c.section_span, c.section_depth,
                           c.section_plate);
}

Json section_json(const SectionStiffness& s) {
  Json j;
  j["bending"] = s.bending;
  j["shear"] = s.shear;
  j["membrane"] = s.membrane;
  j["section_particles"] = s.section_particles;
  j["meaning"] = "PD / continuum stiffness of the infinitely long section under uniform "
                 "curvature, shear and axial strain, transverse displacements relaxed "
                 "(verification/cases/section_stiffness.hpp); supports, load and ends excluded";
  return j;
}

YAML::Node load_fe_summary(const std::string& name) {
  const auto path = std::filesystem::path(PD_FEM_REFERENCE_DIR) / (name + ".json");
  try {
    return YAML::LoadFile(path.string());
  } catch (const YAML::Exception& e) {
    throw std::runtime_error("cannot read FE reference " + path.string() + ": " + e.msg);
  }
}

/// The section-stiffness error budget of a case with a `section:` block, into out; returns the
/// lines to print.
std::string error_budget(const Scene& scene, const StructureCase& c, const YAML::Node& fe,
                         const std::map<std::string, double>& values, Json& out) {
  const SectionStiffness section = section_of(scene, c);
  out["section_stiffness"] = section_json(section);
  // Error budget: the deflection factor the section's stiffness alone predicts, its bending and
  // shear parts weighted as theory splits the deflection (Euler–Bernoulli + Timoshenko's shear term
  // for a beam; Kirchhoff + the rest of the FE value for the plate), and what the measurement
  // leaves beyond it: the supports, the load and the ends.
  const YAML::Node theory = fe["theory"];
  std::map<std::string, double> section_factor, measured_factor;
  for (const auto& q : c.quantities) {
    const double fe_value = fe["quantities"][q.fe_key]["extrapolated"].as<double>();
    double total = fe_value;
    double bending = fe_value;
    if (theory["euler_bernoulli"]) {
      total = theory["timoshenko"].as<double>();
      bending = theory["euler_bernoulli"].as<double>();
    } else if (theory["quantities"] && theory["quantities"][q.fe_key]) {
      bending = theory["quantities"][q.fe_key]["kirchhoff"].as<double>();
    }
    section_factor[q.name] =
        (bending / section.bending + (total - bending) / section.shear) / total;
    measured_factor[q.name] = values.at(q.name) / fe_value;
    Json& b = out["error_budget"][q.name];
    b["measured_factor"] = measured_factor[q.name];
    b["section_factor"] = section_factor[q.name];
    b["remaining_factor"] = measured_factor[q.name] / section_factor[q.name];
  }
  out["error_budget"]["meaning"] =
      "deflection PD/FE = section_factor × remaining_factor; section_factor from "
      "section_stiffness with the bending and shear parts of the deflection weighted as theory "
      "splits it; remaining_factor: supports (fixed particle blocks), load and ends";
  std::string text = fmt::format(
      "   section stiffness PD/continuum: bending {:.4f}, shear {:.4f}, membrane {:.4f}\n",
      section.bending, section.shear, section.membrane);
  for (const auto& q : c.quantities) {
    text += fmt::format(
        "   error budget of {}: the section predicts x{:.4f}, measured x{:.4f}: x{:.4f} from "
        "supports, load and ends\n",
        q.name, section_factor[q.name], measured_factor[q.name],
        measured_factor[q.name] / section_factor[q.name]);
  }
  return text;
}

/// The relaxation error of the paper resolution's run: a rerun with tighter tolerances.
void add_tight_rerun(const Scene& scene, const StructureCase& c, const Context& ctx,
                     const YAML::Node& fe, const std::map<std::string, double>& values,
                     Json& relax) {
  // Relaxation error: the same model relaxed 10× further in force (100× in kinetic energy,
  // which goes with the square of the amplitude). Not further: the residual has a round-off
  // floor near 1e-8 of the applied load (the stretch s = r/L − 1 of a bond at s ~ 1e-5 carries
  // a relative error ~1e-11), so a 1e-8 tolerance is never reached.
  Scene tight = scene;
  tight.solver.steady.force_tolerance *= 0.1;
  tight.solver.steady.kinetic_tolerance *= 0.01;
  // A scene without end_time (the static solver needs none) keeps none: 0 would stop the run
  // before its solve.
  if (scene.solver.end_time) {
    tight.solver.end_time = *scene.solver.end_time * 10;
  }
  std::map<std::string, double> tight_values, tight_lines;
  RunOutcome tight_run;
  run_once(tight, c, ctx, "-tight", tight_values, tight_lines, tight_run);
  for (const auto& q : c.quantities) {
    relax[q.name]["tight_tolerance_value"] = tight_values[q.name];
    relax[q.name]["relaxation_error"] = relative_error(values.at(q.name), tight_values[q.name]);
    relax[q.name]["discretisation_error_vs_fe"] = relative_error(
        tight_values[q.name], fe["quantities"][q.fe_key]["extrapolated"].as<double>());
  }
  relax["tight_steps"] = tight_run.result.steps;
  relax["tight_wall_seconds"] = tight_run.result.wall_seconds;
}

Json run_structure(const Context& ctx, bool fast) {
  const StructureCase c = load_case(ctx.folder / "case.yaml");
  Scene scene = load_scene((ctx.folder / c.scene).string());
  if (fast) {
    set_spacing(scene, c.fast_spacing);
  }
  const YAML::Node fe = load_fe_summary(c.fe_reference);

  std::map<std::string, double> values, line_error;
  RunOutcome run;
  Json lines = run_once(scene, c, ctx, fast ? "-fast" : "", values, line_error, run);

  Json out;
  out["case"] = c.name + (fast ? "-fast" : "");
  std::vector<std::string> names;
  for (const auto& q : c.quantities) {
    names.push_back(q.name);
  }
  out["quantity"] = fmt::format("downward deflection at {} (m)", fmt::join(names, ", "));
  bool passed = run.result.status == RunStatus::converged;
  for (const auto& q : c.quantities) {
    const double fe_value = fe["quantities"][q.fe_key]["extrapolated"].as<double>();
    out["pd"][q.name] = values[q.name];
    out["reference"][q.name]["fe"] = fe_value;
    out["reference"][q.name]["fe_relative_error_estimate"] =
        fe["quantities"][q.fe_key]["relative_error_estimate"].as<double>();
    const double err = relative_error(values[q.name], fe_value);
    out["error"][q.name + "_vs_fe"] = err;
    // Theory values as the FE program computed them (one formula, one place).
    const YAML::Node th = fe["theory"];
    if (th["euler_bernoulli"]) {
      out["reference"][q.name]["euler_bernoulli"] = th["euler_bernoulli"].as<double>();
      out["reference"][q.name]["timoshenko"] = th["timoshenko"].as<double>();
      out["error"][q.name + "_vs_euler_bernoulli"] =
          relative_error(values[q.name], th["euler_bernoulli"].as<double>());
      out["error"][q.name + "_vs_timoshenko"] =
          relative_error(values[q.name], th["timoshenko"].as<double>());
    } else if (th["quantities"] && th["quantities"][q.fe_key]) {
      const double k = th["quantities"][q.fe_key]["kirchhoff"].as<double>();
      out["reference"][q.name]["kirchhoff"] = k;
      out["error"][q.name + "_vs_kirchhoff"] = relative_error(values[q.name], k);
    }
    const auto& gates = fast ? c.fast_gate : c.gate;
    if (const auto g = gates.find(q.name); g != gates.end()) {
      out["gate"][q.name + "_vs_fe"] = g->second;
      passed = passed && err <= g->second;
    }
    if (fast) {
      if (const auto s = c.fast_stored.find(q.name); s != c.fast_stored.end()) {
        const double drift = relative_error(values[q.name], s->second);
        out["regression"][q.name]["stored"] = s->second;
        out["regression"][q.name]["relative_change"] = drift;
        out["regression"][q.name]["tolerance"] = c.fast_regression_tolerance;
        passed = passed && drift <= c.fast_regression_tolerance;
      }
    }
  }
  for (const auto& [name, e] : line_error) {
    out["error"]["line_" + name + "_max_over_max_fe"] = e;
  }
  out["lines"] = lines;
  // Printed after the quantities.
  const std::string budget_text = c.has_section ? error_budget(scene, c, fe, values, out) : "";
  out["wall_seconds_run"] = run.result.wall_seconds;
  out["steps"] = run.result.steps;
  out["bond_updates"] =
      static_cast<double>(run.bonds) * static_cast<double>(run.result.force_evaluations);
  out["particles"] = run.particles;
  out["bonds"] = run.bonds;
  Json& settings = out["settings"];
  settings["spacing"] = scene.model.lattice.spacing;
  settings["horizon_factor"] = scene.model.lattice.horizon_factor;
  settings["stretch"] = to_string(scene.model.effects.stretch);
  settings["surface_correction"] = to_string(scene.model.surface_correction);
  settings["volume_correction"] = to_string(scene.model.volume_correction);
  settings["mirror_coupling"] = std::string(name_of(scene.model.mirror_coupling));
  settings["integrator"] = to_string(scene.solver.integrator);
  settings["force_tolerance"] = scene.solver.steady.force_tolerance;
  settings["kinetic_tolerance"] = scene.solver.steady.kinetic_tolerance;
  settings["run"] = run.summary;

  if (!fast && scene.solver.integrator == IntegratorKind::static_solve) {
    // The static solver does not read the steady-state tolerances: it solves K u = f and runs
    // Newton to its own 1e-10 of the load or the residual's round-off floor (static_solver.cpp),
    // so a rerun "10× tighter" is the identical solve and its difference is 0 by construction.
    // What bounds the unfinished part is the residual the solve reached, reported here.
    Json& relax = out["relaxation"];
    relax["rerun"] = false;
    relax["why_not"] = "static solver: its solution does not depend on the steady-state "
                       "tolerances, so a tighter rerun repeats the same solve";
    relax["residual"] = run.result.residual;
    relax["residual_floor"] = run.result.residual_floor;
  } else if (!fast) {
    add_tight_rerun(scene, c, ctx, fe, values, out["relaxation"]);
  }
  out["passed"] = passed;

  for (const auto& q : c.quantities) {
    const double fe_value = fe["quantities"][q.fe_key]["extrapolated"].as<double>();
    fmt::print("   {} = {:.6e} m vs FE {:.6e} m: error {:.2f} % (gate {})\n", q.name,
               values[q.name], fe_value, 100 * relative_error(values[q.name], fe_value),
               (fast ? c.fast_gate : c.gate).count(q.name)
                   ? fmt::format("{:.1f} %", 100 * (fast ? c.fast_gate : c.gate).at(q.name))
                   : std::string("none"));
  }
  fmt::print("{}", budget_text);
  fmt::print("   {} particles, {} bonds, {} steps, {:.1f} s, status {}\n", run.particles, run.bonds,
             run.result.steps, run.result.wall_seconds, to_string(run.result.status));
  return out;
}

StretchKind stretch_from(const std::string& s) {
  if (s == "exact") {
    return StretchKind::exact;
  }
  if (s == "modified") {
    return StretchKind::modified;
  }
  if (s == "fast") {
    return StretchKind::fast;
  }
  throw std::runtime_error("unknown stretch measure '" + s + "' in a sweep");
}

struct SweepVariant {
  std::string knob;
  std::string value;
  Scene scene;
};

/// The sweep's runs: the scene itself (the baseline), then each knob varied on its own.
std::vector<SweepVariant> sweep_variants(const Scene& base, const StructureCase& c) {
  std::vector<SweepVariant> variants{{"baseline", "scene", base}};
  for (double h : c.sweep_spacing) {
    Scene s = base;
    set_spacing(s, h);
    variants.push_back({"spacing", fmt::format("{:.6g}", h), s});
  }
  for (double m : c.sweep_horizon_factor) {
    Scene s = base;
    s.model.lattice.horizon_factor = m;
    variants.push_back({"horizon_factor", fmt::format("{:.6g}", m), s});
  }
  for (const auto& name : c.sweep_stretch) {
    Scene s = base;
    s.model.effects.stretch = stretch_from(name);
    variants.push_back({"stretch", name, s});
  }
  if (base.model.surface_correction != SurfaceCorrection::none) {
    Scene s = base;
    s.model.surface_correction = SurfaceCorrection::none;
    variants.push_back({"surface_correction", "none", s});
  }
  if (base.model.volume_correction != VolumeCorrection::none) {
    Scene s = base;
    s.model.volume_correction = VolumeCorrection::none;
    variants.push_back({"volume_correction", "none", s});
  }
  for (double t : c.sweep_force_tolerance) {
    Scene s = base;
    s.solver.steady.force_tolerance = t;
    s.solver.steady.kinetic_tolerance = base.solver.steady.kinetic_tolerance *
                                        (t / base.solver.steady.force_tolerance) *
                                        (t / base.solver.steady.force_tolerance);
    variants.push_back({"force_tolerance", fmt::format("{:.3g}", t), s});
  }
  // The old pairs run with everything else as the scene has it (clamps, solver), so the rows
  // differ from the baseline in the corrections alone.
  for (const CorrectionPair& pair : c.sweep_corrections) {
    Scene s = base;
    s.model.surface_correction = pair.surface;
    s.model.volume_correction = pair.volume;
    variants.push_back({"corrections", pair.label, s});
  }
  return variants;
}

/// One row per run: each knob varied on its own around the scene's settings (the baseline).
Json run_structure_sweep(const Context& ctx) {
  const StructureCase c = load_case(ctx.folder / "case.yaml", ctx.quick);
  const Scene base = load_scene((ctx.folder / c.scene).string());
  const YAML::Node fe = load_fe_summary(c.fe_reference);
  const std::vector<SweepVariant> variants = sweep_variants(base, c);

  std::string rows_text;
  Json rows = Json::array();
  std::vector<std::pair<double, double>> spacing_error;
  const std::string first_quantity = c.quantities.front().name;
  const double first_fe =
      fe["quantities"][c.quantities.front().fe_key]["extrapolated"].as<double>();
  std::size_t k = 0;
  for (const SweepVariant& v : variants) {
    ++k;
    fmt::print("   [{}/{}] {} = {} ...\n", k, variants.size(), v.knob, v.value);
    std::fflush(stdout);
    std::map<std::string, double> values, line_error;
    RunOutcome run;
    run_once(v.scene, c, ctx, "-sweep-" + v.knob + "-" + v.value, values, line_error, run, false);
    Json row;
    row["case"] = c.name;
    row["knob"] = v.knob;
    row["knob_value"] = v.value;
    row["spacing"] = v.scene.model.lattice.spacing;
    row["horizon_factor"] = v.scene.model.lattice.horizon_factor;
    row["stretch"] = to_string(v.scene.model.effects.stretch);
    row["surface_correction"] = to_string(v.scene.model.surface_correction);
    row["volume_correction"] = to_string(v.scene.model.volume_correction);
    row["force_tolerance"] = v.scene.solver.steady.force_tolerance;
    row["status"] = to_string(run.result.status);
    for (const auto& q : c.quantities) {
      const double fe_value = fe["quantities"][q.fe_key]["extrapolated"].as<double>();
      row["pd"][q.name] = values[q.name];
      row["error_vs_fe"][q.name] = relative_error(values[q.name], fe_value);
      // + means too soft; a sign change between levels ends a convergence fit.
      row["signed_error_vs_fe"][q.name] = values[q.name] / fe_value - 1.0;
    }
    row["wall_seconds"] = run.result.wall_seconds;
    row["setup_seconds"] = run.setup_seconds;
    row["steps"] = run.result.steps;
    row["bond_updates"] =
        static_cast<double>(run.bonds) * static_cast<double>(run.result.force_evaluations);
    row["particles"] = run.particles;
    row["bonds"] = run.bonds;
    if (c.has_section) {
      row["section_stiffness"] = section_json(section_of(v.scene, c));
    }
    if (v.knob == "spacing" || v.knob == "baseline") {
      spacing_error.emplace_back(v.scene.model.lattice.spacing,
                                 relative_error(values[first_quantity], first_fe));
    }
    fmt::print("         error {:.3f} % in {:.1f} s ({} particles)\n",
               100 * relative_error(values[first_quantity], first_fe), run.result.wall_seconds,
               run.particles);
    rows_text += row.dump(0);
    rows.push_back(std::move(row));
    // Rows are appended to the JSON-lines file as they come, so an interrupted sweep keeps them.
    write_file_atomically(ctx.output_dir / (c.name + "-sweep.jsonl"), rows_text);
  }
  Json out;
  out["case"] = c.name + "-sweep";
  out["quantity"] = "error vs FE and wall time for each knob (rows in " + c.name + "-sweep.jsonl)";
  out["rows"] = rows;
  out["extent"] = ctx.quick ? "quick_sweep (pd verify --sweep --quick)" : "sweep";
  if (spacing_error.size() >= 2) {
    const ObservedOrder order = observed_order(spacing_error);
    out["observed_order_in_spacing"] = order.order ? Json(*order.order) : Json(nullptr);
    out["observed_order"] = to_json(order);
    fmt::print("   observed order in λ of the {} error: {}\n", first_quantity, order.text());
  }
  out["gate"] = "none: a measurement";
  out["passed"] = true;
  return out;
}

} // namespace

void set_spacing(Scene& scene, double spacing) {
  const double old = scene.model.lattice.spacing;
  const int vertical = scene.model.dimension.dim - 1;
  scene.model.lattice.spacing = spacing;
  for (LoadSpec& l : scene.model.loads) {
    for (Box& b : l.load.region.boxes) {
      if (b.hi[vertical] - b.lo[vertical] <= old * (1 + 1e-9)) { // one top layer: keep it one
        b.lo[vertical] = b.hi[vertical] - 0.5 * spacing;
      }
    }
  }
}

Json run_structure_case(const Context& ctx, bool fast) {
  return run_structure(ctx, fast);
}
Json run_structure_sweep_case(const Context& ctx) {
  return run_structure_sweep(ctx);
}
std::string structure_case_name(const std::filesystem::path& case_yaml) {
  return load_case(case_yaml).name;
}

} // namespace pd::verification
