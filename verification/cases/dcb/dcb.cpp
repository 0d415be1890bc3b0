// dcb (issue 36): a double cantilever beam opened quasi-statically by displacement, the scene as a
// new user writes it (library defaults), against LEFM of the same body (its deal.II compliance at
// every crack length, fe_compliance.hpp): the initiation load, the load while the crack grows, and
// the energy the specimen dissipated against G0 × the crack area it opened. Beam theory with the
// root-rotation correction is reported beside. dcb-fine is the same scene at half the spacing (the
// horizon follows at fixed m).
#include "fe_compliance.hpp"
#include "libpd/app/run.hpp"
#include "libpd/discretisation/model.hpp"
#include "libpd/io/scene.hpp"
#include "verification.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fmt/format.h>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <yaml-cpp/yaml.h>

namespace pd::verification {

namespace {

/// Beam theory of a DCB whose arms (depth h, width b) are cantilevers built in at the crack tip:
/// each arm deflects P a³ / (3 E I), I = b h³ / 12. Root rotation and shear at the built-in end
/// make the arm behave as if it were longer by χ h, with Williams' correction for an orthotropic
/// arm (J. G. Williams, End corrections for orthotropic DCB specimens, Compos. Sci. Technol. 35
/// (1989) 367–376): χ = √(E11 / (11 G13)) (3 − 2 (Γ / (1 + Γ))²), Γ = 1.18 √(E11 E22) / G13,
/// here isotropic in plane stress with the bond-based ν = 1/3 (E11 = E22 = E, G13 = E / (2 (1 +
/// ν))).
struct BeamTheory {
  double e = 0, g0 = 0, b = 0, h = 0;
  double chi = 0;
  double ei() const { return e * b * h * h * h / 12; }
  /// Opening Δ (both arms) per unit load at crack length a: 2 (a + χh)³ / (3 E I).
  double compliance(double a) const { return 2 * std::pow(a + chi * h, 3) / (3 * ei()); }
  /// G = P² (a + χh)² / (b E I) = G0 (Irwin–Kies, dC/da of the compliance above): the load at
  /// which a crack of length a grows.
  double critical_load(double a) const { return std::sqrt(b * ei() * g0) / (a + chi * h); }
  /// The growth branch: a grows so that G = G0 at every Δ, so a + χh = √(3 E I Δ / (2 √(b E I G0)))
  /// and P = √(b E I G0) / (a + χh) falls as Δ^(-1/2).
  double growth_length(double opening) const {
    return std::sqrt(3 * ei() * opening / (2 * std::sqrt(b * ei() * g0))) - chi * h;
  }
};

BeamTheory beam_theory(const Material& m, double b, double h) {
  BeamTheory t;
  t.e = m.youngs_modulus;
  t.g0 = m.fracture_energy.value_or(0);
  t.b = b;
  t.h = h;
  const double nu = 1.0 / 3.0; // what bond-based PD represents in plane stress
  const double shear = t.e / (2 * (1 + nu));
  const double gamma = 1.18 * t.e / shear;
  t.chi = std::sqrt(t.e / (11 * shear)) * (3 - 2 * std::pow(gamma / (1 + gamma), 2));
  return t;
}

/// One recorded equilibrium of load_curve.csv: the opening Δ between the grips and the grips'
/// force P (the mean of the two reactions' magnitudes).
struct CurvePoint {
  bool critical = false;
  std::size_t bonds_broken = 0;
  double opening = 0, load = 0, dissipated = 0;
};

double summary_number(const Json& j, const std::string& key) {
  const Json* v = j.find(key);
  return v && v->number() ? *v->number() : 0.0;
}

std::vector<CurvePoint> read_load_curve(const std::filesystem::path& file, double full_opening) {
  std::ifstream in(file);
  if (!in) {
    throw std::runtime_error("dcb: cannot read " + file.string());
  }
  std::string line;
  std::getline(
      in,
      line); // level,load_factor,critical,bonds_broken,breaking,dissipated_energy,force,force-bottom
  std::vector<CurvePoint> out;
  while (std::getline(in, line)) {
    std::vector<double> v;
    std::stringstream ss(line);
    for (std::string cell; std::getline(ss, cell, ',');) {
      v.push_back(std::stod(cell));
    }
    if (v.size() < 8) {
      throw std::runtime_error("dcb: short row in " + file.string());
    }
    out.push_back({v[2] > 0.5, static_cast<std::size_t>(v[3]), v[1] * full_opening,
                   0.5 * (std::abs(v[6]) + std::abs(v[7])), v[5]});
  }
  return out;
}

/// The load line: the mean x of the body particles in the grip's box (its end column).
double load_line_of(const Model& model, const Box& grip) {
  double sum = 0;
  std::size_t count = 0;
  for (std::size_t i = 0; i < model.body_particle_count(); ++i) {
    const Vec3& x = model.particles.position[i];
    if (x[0] >= grip.lo[0] && x[0] <= grip.hi[0] && x[1] >= grip.lo[1] && x[1] <= grip.hi[1]) {
      sum += x[0];
      ++count;
    }
  }
  return count > 0 ? sum / static_cast<double>(count) : 0.0;
}

struct Growth {
  double ratio = 0;     ///< mean P / P_LEFM over the growth branch (gated)
  double worst = 0;     ///< largest |P / P_LEFM − 1| there
  double all_ratio = 0; ///< mean over every critical state past the threshold
  double exponent = 0;  ///< n of a fit P ∝ Δ^n over the growth branch
  std::size_t points = 0;
};

// Growth: the loads at which bonds break once the opening is 25 % past LEFM's initiation (where
// LEFM's crack has grown by about 12 % of a0 + χh), against P(Δ) of LEFM's growth branch. Breaking
// bonds one at a time, the driver may find the next bond critical at an opening below one
// already reached (the lattice snaps back); under an opening that only grows those states are
// passed dynamically, so the growth branch is the states at an opening no smaller than any
// before them.
Growth measure_growth(const std::vector<CurvePoint>& curve, const ComplianceGrowth& lefm,
                      double initiation_opening) {
  Growth out;
  double ratio_sum = 0, all_sum = 0, reached = 0;
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  std::size_t all_points = 0;
  for (const CurvePoint& p : curve) {
    const bool monotone = p.opening >= reached;
    reached = std::max(reached, p.opening);
    const double reference = lefm.load_at(p.opening);
    if (!p.critical || p.opening < 1.25 * initiation_opening || !std::isfinite(reference)) {
      continue;
    }
    const double ratio = p.load / reference;
    all_sum += ratio;
    ++all_points;
    if (!monotone) {
      continue;
    }
    ratio_sum += ratio;
    out.worst = std::max(out.worst, std::abs(ratio - 1));
    const double x = std::log(p.opening), y = std::log(p.load);
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
    ++out.points;
  }
  const double n = static_cast<double>(out.points);
  out.ratio = out.points > 0 ? ratio_sum / n : std::nan("");
  out.all_ratio = all_points > 0 ? all_sum / static_cast<double>(all_points) : std::nan("");
  out.exponent = out.points > 1 ? (n * sxy - sx * sy) / (n * sxx - sx * sx) : std::nan("");
  return out;
}

// Crack extension: along the crack plane (y = mid), each column of the two face rows (the
// particles λ/2 above and below it) ahead of the pre-crack's tip counts the fraction of the
// damage it would have with every bond across the plane broken; Σ fraction × λ is the length the
// broken bonds opened. The full-crack damage of a face particle is counted from the model's own
// bonds (those into ghosts included, as the damage index counts them).
double crack_extension(const Model& model, const std::vector<double>& damage, double mid,
                       double tip0, double spacing) {
  const auto crosses = [&](std::size_t i, std::uint32_t j) {
    return (model.particles.position[i][1] - mid) * (model.particles.position[j][1] - mid) < 0;
  };
  std::map<long, std::pair<double, double>> columns; // column → (Σ damage, Σ full damage)
  for (std::size_t i = 0; i < model.body_particle_count(); ++i) {
    const Vec3& x = model.particles.position[i];
    if (std::abs(std::abs(x[1] - mid) - 0.5 * spacing) > 1e-3 * spacing || x[0] < tip0) {
      continue;
    }
    const std::size_t b = model.family.offsets[i], e = model.family.offsets[i + 1];
    std::size_t across = 0;
    for (std::size_t k = b; k < e; ++k) {
      across += crosses(i, model.family.neighbour[k]) ? 1 : 0;
    }
    auto& c = columns[std::lround(x[0] / spacing)];
    c.first += damage.empty() ? 0.0 : damage[i];
    c.second += e > b ? static_cast<double>(across) / static_cast<double>(e - b) : 0.0;
  }
  double extension = 0;
  for (const auto& [column, c] : columns) {
    extension += spacing * std::min(1.0, c.second > 0 ? c.first / c.second : 0.0);
  }
  return extension;
}

/// Body particles that lost a bond more than a horizon away from the crack plane: damage that is
/// not the crack's (at the grips, say), whose bonds' energy summary.json counts all the same.
std::size_t damaged_off_plane(const Model& model, const std::vector<double>& damage, double mid) {
  std::size_t n = 0;
  for (std::size_t i = 0; i < model.body_particle_count() && i < damage.size(); ++i) {
    n += damage[i] > 0 && std::abs(model.particles.position[i][1] - mid) > model.horizon() ? 1 : 0;
  }
  return n;
}

// The energy the specimen lost, by a global balance: the grips' work minus the energy stored at
// the end. Between two recorded states the bonds are those of the later one and the force is
// linear in the opening through the origin, so each piece of work is exact.
double released_energy(const std::vector<CurvePoint>& curve) {
  double work = 0;
  for (std::size_t k = 0; k < curve.size(); ++k) {
    const double d0 = k > 0 ? curve[k - 1].opening : 0.0;
    const CurvePoint& p = curve[k];
    if (p.opening > 0) {
      work += 0.5 * p.load / p.opening * (p.opening * p.opening - d0 * d0);
    }
  }
  return curve.empty() ? 0.0 : work - 0.5 * curve.back().load * curve.back().opening;
}

struct Start {
  double compliance = 0; ///< Δ / P at the first level, before any bond broke
  CurvePoint peak, first_break;
  bool any_break = false;
};

Start measure_start(const std::vector<CurvePoint>& curve) {
  Start out;
  // Elastic: the first level, before any bond broke, against the compliance at a0.
  const auto first_level = std::find_if(curve.begin(), curve.end(), [](const CurvePoint& p) {
    return !p.critical && p.bonds_broken == 0;
  });
  out.compliance = first_level != curve.end() && first_level->load > 0
                       ? first_level->opening / first_level->load
                       : std::nan("");
  // Initiation: the largest load (the load of a DCB peaks where its crack starts: under
  // displacement control the load falls as soon as the crack grows); the first bond's break is
  // reported beside it.
  for (const CurvePoint& p : curve) {
    if (p.load > out.peak.load) {
      out.peak = p;
    }
    if (p.critical && !out.any_break) {
      out.first_break = p;
      out.any_break = true;
    }
  }
  return out;
}

/// The case's numbers on the console, from its JSON.
void print_dcb(const Json& out) {
  const auto v = [&](const char* group, const char* key) {
    const Json* g = out.find(group);
    const Json* x = g ? g->find(key) : nullptr;
    return x && x->number() ? *x->number() : std::nan("");
  };
  fmt::print("   λ = {:.3g} mm, {:.0f} particles, {:.0f} break events, {:.1f} s\n"
             "   compliance {:.4g} vs FE {:.4g} m/N ({:+.2f} %; beam theory {:.4g})\n"
             "   initiation (peak) load {:.5g} N at Δ = {:.4g} mm vs LEFM {:.5g} N at {:.4g} mm "
             "({:+.2f} %; beam theory {:.5g} N); first break at {:.5g} N, Δ = {:.4g} mm\n"
             "   growth: P / P_LEFM(Δ) mean {:.4f} ({:+.2f} %; over every critical state {:.4f}), "
             "worst {:.2f} %, {:.0f} states, exponent {:.3f}\n"
             "   crack extension {:.4g} mm (final a {:.4g} mm; LEFM at the final Δ {:.4g} mm; "
             "from the compliance {:.4g} mm)\n"
             "   dissipated by energy balance {:.5g} J, G0 × area {:.5g} J: {:+.2f} % (stored in "
             "the broken bonds as they broke {:.5g} J, {:+.2f} %)\n",
             1e3 * v("pd", "spacing"), v("pd", "particles"), v("pd", "break_events"),
             v("pd", "solve_seconds"), v("pd", "compliance"), v("reference", "compliance"),
             100 * v("signed_error", "compliance"), v("reference", "compliance_beam_theory"),
             v("pd", "initiation_load"), 1e3 * v("pd", "initiation_opening"),
             v("reference", "initiation_load"), 1e3 * v("reference", "initiation_opening"),
             100 * v("signed_error", "initiation_load"),
             v("reference", "initiation_load_beam_theory"), v("pd", "first_break_load"),
             1e3 * v("pd", "first_break_opening"), v("pd", "growth_load_ratio_mean"),
             100 * v("signed_error", "growth_load_ratio_mean"),
             v("pd", "growth_load_ratio_mean_all_critical_states"),
             100 * v("pd", "growth_load_ratio_worst_deviation"), v("pd", "growth_points"),
             v("pd", "growth_exponent"), 1e3 * v("pd", "crack_extension"),
             1e3 * v("pd", "crack_length_final"), 1e3 * v("reference", "crack_length_final_lefm"),
             1e3 * v("pd", "crack_length_from_compliance"), v("pd", "dissipated_energy"),
             v("reference", "dissipated_energy"), 100 * v("signed_error", "dissipated_energy"),
             v("pd", "bond_energy_at_break"), 100 * v("signed_error", "bond_energy_at_break"));
  if (v("reference", "largest_opening_judged") < v("pd", "final_opening")) {
    fmt::print("   note: LEFM's growth curve reaches Δ = {:.4g} mm only; the states beyond it are "
               "not judged\n",
               1e3 * v("reference", "largest_opening_judged"));
  }
}

/// The scene at the run's spacing, written where the FE runs can read it.
std::filesystem::path scene_at_spacing(const std::filesystem::path& scene_file, double spacing,
                                       const std::filesystem::path& file) {
  YAML::Node s = YAML::LoadFile(scene_file.string());
  s["lattice"]["spacing"] = spacing;
  std::filesystem::create_directories(file.parent_path());
  std::ofstream(file) << s << "\n";
  return file;
}

Json run_dcb(const Context& ctx, const std::string& name, double refine) {
  const auto start = std::chrono::steady_clock::now();
  Json out;
  out["case"] = name;
  out["quantity"] = "load–opening curve and dissipated energy of a DCB opened by displacement";
  Scene s = load_scene((ctx.folder / "dcb.yaml").string());
  s.model.lattice.spacing /= refine;
  const double spacing = s.model.lattice.spacing;

  const Material& material = s.model.materials.at(0);
  const Box& beam = s.model.bodies.at(0).region.boxes.at(0);
  const double h = 0.5 * (beam.hi[1] - beam.lo[1]);
  const double mid = beam.lo[1] + h;
  const Crack& crack = s.model.cracks.at(0);
  const double tip0 = std::max(crack.vertices[0][0], crack.vertices[1][0]);
  const SupportSpec& top = s.model.supports.at(0);
  const SupportSpec& bottom = s.model.supports.at(1);
  const Model model = build_model(s.model);
  const double load_line = load_line_of(model, top.region.boxes.at(0));
  const double a0 = tip0 - load_line;
  const double full_opening = top.displacement[1] - bottom.displacement[1];
  const double b = s.model.dimension.thickness;
  const double g0 = material.fracture_energy.value_or(0);
  const BeamTheory beam_lefm = beam_theory(material, b, h);

  RunOptions options = case_run_options(ctx, name);
  options.write_vtu = false;
  options.keep_final_field = true;
  const RunOutcome r = run_scene(s, options);
  const std::vector<CurvePoint> curve =
      read_load_curve(options.output_dir / "load_curve.csv", full_opening);
  const double final_opening = curve.empty() ? 0.0 : curve.back().opening;

  // LEFM of this body, from its FE compliance, up to the crack LEFM reaches at the final opening
  // (beam theory's estimate of it, with a margin).
  const std::filesystem::path fe_dir = ctx.output_dir / (name + "-fe-compliance");
  const ComplianceGrowth lefm = lefm_growth_from_fe_compliance(
      scene_at_spacing(ctx.folder / "dcb.yaml", spacing, fe_dir / "scene.yaml"), s, "force",
      full_opening, 0.25 * h,
      1.2 * (beam_lefm.growth_length(std::max(final_opening, full_opening)) - a0), fe_dir);

  const Start st = measure_start(curve);
  const CurvePoint &peak = st.peak, &first_break = st.first_break;
  const bool any_break = st.any_break;
  const double compliance = st.compliance;
  const double initiation_load = lefm.load.front();
  const double initiation_opening = lefm.opening.front();
  const double compliance_fe = initiation_opening / initiation_load;

  const Growth growth = measure_growth(curve, lefm, initiation_opening);
  const double extension = crack_extension(model, r.damage, mid, tip0, spacing);
  const double crack_area = extension * b;
  const double bond_energy = summary_number(r.quasi_static, "dissipated_energy");
  const double released = released_energy(curve);
  const double final_compliance = curve.empty() ? std::nan("") : final_opening / curve.back().load;

  out["status"] = to_string(r.result.status);
  out["message"] = r.result.message;
  Json& pd = out["pd"];
  pd["initiation_load"] = peak.load;
  pd["initiation_opening"] = peak.opening;
  pd["first_break_load"] = any_break ? Json(first_break.load) : Json();
  pd["first_break_opening"] = any_break ? Json(first_break.opening) : Json();
  pd["compliance"] = compliance;
  pd["growth_load_ratio_mean"] = growth.ratio;
  pd["growth_load_ratio_worst_deviation"] = growth.worst;
  pd["growth_points"] = growth.points;
  pd["growth_load_ratio_mean_all_critical_states"] = growth.all_ratio;
  pd["load_line"] = load_line;
  pd["damaged_particles_off_plane"] = damaged_off_plane(model, r.damage, mid);
  pd["growth_exponent"] = growth.exponent;
  pd["dissipated_energy"] = released;
  pd["bond_energy_at_break"] = bond_energy;
  pd["crack_extension"] = extension;
  pd["crack_length_final"] = a0 + extension;
  pd["crack_length_from_compliance"] = a0 + lefm.extension_at_compliance(final_compliance);
  pd["final_opening"] = final_opening;
  pd["final_load"] = curve.empty() ? 0.0 : curve.back().load;
  pd["bonds_broken"] = summary_number(r.quasi_static, "bonds_broken");
  pd["break_events"] = summary_number(r.quasi_static, "break_events");
  pd["spacing"] = spacing;
  pd["particles"] = r.particles;
  pd["solve_seconds"] = r.result.wall_seconds;
  Json& ref = out["reference"];
  ref["initiation_load"] = initiation_load;
  ref["initiation_opening"] = initiation_opening;
  ref["compliance"] = compliance_fe;
  ref["growth_load_ratio_mean"] = 1.0;
  ref["growth_exponent_lefm"] = lefm.load.size() > 1
                                    ? std::log(lefm.load.back() / lefm.load.front()) /
                                          std::log(lefm.opening.back() / lefm.opening.front())
                                    : std::nan("");
  ref["dissipated_energy"] = g0 * crack_area;
  ref["crack_length_final_lefm"] = a0 + lefm.extension_at(final_opening);
  ref["crack_step"] = lefm.extension.size() > 1 ? lefm.extension[1] : 0.0;
  ref["largest_opening_judged"] = lefm.opening.back(); // LEFM's growth curve ends there
  ref["initiation_load_beam_theory"] = beam_lefm.critical_load(a0);
  ref["compliance_beam_theory"] = beam_lefm.compliance(a0);
  ref["chi"] = beam_lefm.chi;
  ref["a0"] = a0;
  const double e_init = peak.load / initiation_load - 1;
  const double e_growth = growth.ratio - 1;
  const double e_energy = released / (g0 * crack_area) - 1;
  out["error"]["initiation_load"] = std::abs(e_init);
  out["error"]["growth_load_ratio_mean"] = std::abs(e_growth);
  out["error"]["dissipated_energy"] = std::abs(e_energy);
  out["error"]["compliance"] = std::abs(compliance / compliance_fe - 1);
  out["signed_error"]["initiation_load"] = e_init;
  out["signed_error"]["growth_load_ratio_mean"] = e_growth;
  out["signed_error"]["dissipated_energy"] = e_energy;
  out["signed_error"]["compliance"] = compliance / compliance_fe - 1;
  out["signed_error"]["bond_energy_at_break"] = bond_energy / (g0 * crack_area) - 1;
  out["run"] = r.summary;
  print_dcb(out);
  finish_case(
      out,
      {{"initiation_load", 0.05}, {"growth_load_ratio_mean", 0.05}, {"dissipated_energy", 0.03}},
      r.result.status == RunStatus::converged && growth.points > 0, start);
  return out;
}

Json run_dcb_default(const Context& ctx) {
  return run_dcb(ctx, "dcb", 1);
}
Json run_dcb_fine(const Context& ctx) {
  return run_dcb(ctx, "dcb-fine", 2);
}

} // namespace

PD_VERIFICATION_RUN("dcb", run_dcb_default);
PD_VERIFICATION_RUN("dcb-fine", run_dcb_fine);

} // namespace pd::verification
