// griffith (issue 17; Olsson, Ander & Williams 2021, §8–10, eqs. 103, 111, 116–119, Fig. 14):
// the failure stress of the virtual-fibre model against Griffith's theory.
//
// The body is the paper's elliptical disk (eq. 114) with a crack between its focal points x = ±c,
// as runner/elliptic_disk.hpp builds it: graded particles (finest at the tips), plane strain, steel
// of Table 1 with elastic–perfectly plastic arms (eq. 111, ε_y = 1/500) that fail once their
// plastic elongation exceeds δ_e (eq. 118). The load is the paper's (§10.3): the particles of a
// boundary zone, the fewest outer rings of zones that complete every free particle's horizon, are
// held at eq. 116's displacement field for a remote equibiaxial stress S, scaled up in increments
// of S/σ_y; each increment is relaxed to equilibrium by the quasi-static driver
// (time/quasi_static.hpp, ADR with a linear predictor; the fibre model has no static solver).
// After each increment the boundary stress is the summed reaction of the boundary zone, its
// component along the outward normal of the confocal ellipse through each particle, over the
// outer perimeter (thickness 1): σ_b = Σ R_i·n_i / P. The failure stress σ_f is the peak of that
// load–displacement history, once σ_b has fallen `failure_drop` below it (the crack has run).
// The disk's outer boundary is ξ_max = 2 (semi-major axis 3.76 c; CI) or 2.7 (7.47 c; full), not
// the builder's π/2 (2.51 c): Griffith's law is for a crack in a large plate, and the plastic
// zone at failure reaches 1.7 c from a tip at the largest δ_e (`plastic_reach_over_c_at_peak`).
//
// Griffith (eqs. 106–109): σ_f/σ_y ≈ ζ with ζ ∝ √(δ/c), so σ_f/σ_y against √(δ_e/c) is a
// straight line (eq. 117) whose slope only a numerical experiment gives (§10.5). Gates: R² of
// the least-squares line ≥ 0.98 over the δ_e sweep, and the c^(−1/2) law directly: a crack of
// half the length, c/2, in a disk with the same outer boundary must fail at √2 times the stress
// at the same δ_e, within 5 %.
// - Which δ_e: Griffith's energy balance holds under small-scale yielding, when the failure
//   stress is well below yield, so the ratio is gated at the sweep's smallest δ_e (the short
//   crack then at twice its δ_e/c). The pair at half that δ_e (the short crack at the sweep's
//   smallest δ_e/c) is reported beside it (`crack_length_scaling_half_delta`). The CI disk is
//   held to the same gate, though without the path band below its ratio moved from +0.9 % to
//   −12.3 % between two resolutions (docs/theory/griffith.md): a disk too coarse for the law
//   fails, it is not excused.
// - Why c/2 in the same disk, not the disk scaled with its crack: a scaled disk with fixed δ_e
//   is, by dimensional analysis, exactly the first disk at δ_e/2 (every length scales, ε^p·L > δ_e
//   becomes ε^p·L > δ_e/2), so it would repeat a point of the sweep and test nothing new. Keeping
//   the outer boundary and the zone sizes (ξ_max' from c' cosh ξ_max' = c cosh ξ_max, the same Δξ
//   and n_η) puts the boundary zone twice as far from the shorter crack (in crack lengths).
// - The crack's path (full disks): eq. 114's grading refines the initial tips only, and the
//   crack grows stably before the peak, so on the graded set the peak is set by where the
//   coarsening zones arrest it. `griffith-full` fills |x| ≤ 2c, |y| ≤ c/2 with one lattice of
//   spacing c/32 (elliptic_disk.hpp's PathBand), the same in metres around both cracks: at a
//   fixed δ_e the process zone has one size in metres (a strip-yield zone ≈ (π/8) E′ δ_e/σ_y, no
//   c in it), so both cracks resolve it alike. `griffith-boundary` (ξ_max 3.2) and
//   `griffith-resolution` (c/64) measure what the disk and the spacing still move.
// - σ_b and S: eq. 116 is the exact elastic field of either disk, so linear elastic fracture
//   mechanics gives exactly √2 in S, while σ_b = κ S in the elastic range with κ set by the disk's
//   size over its crack (0.893 for ξ_max = 2, 0.927 for its c/2 disk; 0.951 and 0.958 at 2.7 since
//   the graded particles carry their Voronoi areas, 0.903 and 0.909 before). The
//   issue reads σ_f from the reactions, so σ_b is gated; the ratio in S (`remote_ratio`), which
//   has no κ in it, is gated beside it at the same 5 %.
//
// Resolution and cost (the "decide honestly"): the paper uses Table 1 (20,000 particles,
// ~226,000 arms) and a fine load step. `griffith` (CI) runs 16 × 16 zones of 3 × 3 (2,304
// particles) at ΔS = 0.01 σ_y over 5 elongation limits; `griffith-full` 27 × 20 zones of 4 × 4
// and the path band (10,180 particles) at ΔS = 0.005 σ_y over the paper's 11 (c/750 … c/3250).
// Each increment's plastic flow is recomputed from its start (time/quasi_static.cpp), so ADR's
// path to equilibrium leaves none of its own; before that, σ_f at c/3250 rose 25 % from path
// spacing c/32 to c/64 and the ratio failed the gate there (−11.4 %). With the relaxed moduli of
// the noisy particles (discretisation/fibre_relaxation.cpp) the ratio is −3.3 % at
// c/32 and +1.4 % at c/64 (+1.9 % on the larger disk of griffith-boundary). σ_f itself settles
// once the horizon is below about 0.6 of the process zone (≈ 216 δ_e; measured before the
// relaxed moduli: at δ_e = c/1500 it moved 10 % from c/32 to c/64 and 1.5 % to c/96); at c/3250
// (zone ≈ 0.07 c, horizon 0.16 c … 0.05 c) it still rises with refinement. Numbers and commands:
// docs/theory/griffith.md.
#include "curve_recorder.hpp"
#include "elliptic_disk.hpp"
#include "libpd/io/scene.hpp"
#include "libpd/time/quasi_static.hpp"
#include "line_fit.hpp"
#include "verification.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <complex>
#include <fmt/format.h>
#include <numbers>
#include <string>
#include <vector>

namespace pd::verification {

namespace {

constexpr double r_squared_gate = 0.98; // issue 17: "expect R² ≥ 0.98"
constexpr double scaling_gate = 0.05;   // issue 17: c^(−1/2) "within 5 %"
/// The run has failed once σ_b is this fraction below its peak: the crack has run and unloaded
/// the disk (a crack across an equibiaxially loaded disk releases most of σ_yy).
constexpr double failure_drop = 0.1;
/// Each increment is relaxed until ‖free-dof force‖ ≤ this × ‖reactions‖ (quasi_static.hpp).
constexpr double increment_tolerance = 1e-4;

/// The disk of a run: elliptic_disk.hpp's disk with this case's crack, outer boundary and zones.
struct Disk {
  double c = EllipticDiskTable1{}.focal_half_distance;
  double xi_max = 2.0;
  int zones_xi = 16;  ///< along ξ ∈ (0, ξ_max]
  int zones_eta = 16; ///< around, η ∈ [0, 2π) (even)
  int pattern = 3;
  /// The crack's path at one spacing (elliptic_disk.hpp), in metres, so the same for a shorter
  /// crack; none on the CI disk.
  PathBand band;
  /// The same outer boundary and zone sizes around a crack of length 2c·factor (factor < 1).
  Disk shorter_crack(double factor) const {
    Disk d = *this;
    d.c = c * factor;
    d.xi_max = std::acosh(std::cosh(xi_max) / factor);
    d.zones_xi = static_cast<int>(std::lround(zones_xi * d.xi_max / xi_max));
    return d;
  }
  /// The builder's spec: plasticity and the elongation limit on, S = σ_y (the driver's levels
  /// are then S/σ_y), the boundary zone `rings` rings of zones deep. The builder counts Table 1's
  /// zones as the paper does, n_ξ over ξ ∈ (−ξ_max, ξ_max) and n_η over η ∈ (0, π).
  EllipticDiskSpec spec(int rings) const {
    EllipticDiskSpec s;
    s.table.focal_half_distance = c;
    s.table.zones_xi = 2 * zones_xi;
    s.table.zones_eta = zones_eta / 2;
    s.pattern = pattern;
    s.xi_max = xi_max;
    s.remote_stress = s.table.yield_stress;
    s.boundary_rings = rings;
    s.path_band = band;
    s.plasticity = true;
    s.elongation_limit = true;
    return s;
  }
};

/// The load levels S/σ_y: `step`, 2·step, … up to `last`.
struct Stepping {
  double step = 0.02;
  double last = 2.0;
  std::size_t max_iterations = 4000; ///< ADR iterations per increment
  std::vector<double> levels() const {
    std::vector<double> out;
    for (int k = 1; k * step <= last + 1e-12; ++k) {
      out.push_back(k * step);
    }
    return out;
  }
};

/// The outward unit normal at (x, y) of the confocal ellipse through it: dz/dξ = c sinh(ξ + iη).
Vec3 outward_normal(const Vec3& p, double c) {
  const auto [xi, eta] = elliptic_coordinates(p[0], p[1], c);
  const std::complex<double> s = std::sinh(std::complex<double>(xi, eta));
  const double m = std::abs(s);
  return {s.real() / m, s.imag() / m, 0};
}

/// The perimeter of the ellipse ξ = ξ_max: ∫ c √(sinh²ξ + sin²η) dη over a period (the
/// trapezoidal rule is spectrally accurate for a periodic integrand).
double perimeter(double c, double xi_max) {
  constexpr int n = 2048;
  double sum = 0;
  const double sh = std::sinh(xi_max);
  for (int k = 0; k < n; ++k) {
    const double s = std::sin(2 * std::numbers::pi * k / n);
    sum += std::sqrt(sh * sh + s * s);
  }
  return c * sum * 2 * std::numbers::pi / n;
}

/// How far the plastic zone reaches: the distance from the nearer crack tip (±c, 0) within which
/// 90 % of the particles with a yielded or failed arm lie, over c (a percentile, so that a few
/// stray yielded arms do not set it). Griffith's energy balance assumes the dissipation stays at
/// the tip (small-scale yielding); a reach comparable with the distance to the boundary zone,
/// c (cosh ξ_b − 1) on the major axis, means it does not.
double plastic_reach(const Model& m, double c) {
  std::vector<double> distance;
  for (std::size_t i = 0; i < m.body_particle_count(); ++i) {
    bool yielded = false;
    for (std::size_t k = m.family.offsets[i]; !yielded && k < m.family.offsets[i + 1]; ++k) {
      yielded = m.state.plastic_stretch[k] != 0 || m.state.broken[k] != 0;
    }
    if (yielded) {
      const Vec3& x = m.particles.position[i];
      distance.push_back(std::min(std::hypot(x[0] - c, x[1]), std::hypot(x[0] + c, x[1])));
    }
  }
  if (distance.empty()) {
    return 0;
  }
  const auto at = distance.begin() +
                  static_cast<std::ptrdiff_t>(0.9 * static_cast<double>(distance.size() - 1));
  std::nth_element(distance.begin(), at, distance.end());
  return *at / c;
}

struct Failure {
  double delta_over_c = 0;
  double failure_stress = 0;    ///< peak σ_b [Pa]
  double failure_level = 0;     ///< S/σ_y at the peak
  double reach_at_peak = 0;     ///< plastic_reach at the peak
  double elastic_factor = 0;    ///< σ_b/S after the first increment (nearly elastic)
  double first_break_level = 0; ///< S/σ_y of the first increment with a broken arm
  bool failed = false;          ///< σ_b fell `failure_drop` below its peak
  Json json;
};

/// A disk built once for every δ_e of a sweep (the arm weights' balance is the costly part of
/// the set-up): its scene, model, boundary zone and that zone's outward normals.
struct DiskModel {
  Disk disk;
  Scene scene;
  Model model;
  double zone_edge = 0; ///< ξ of the boundary zone's inner edge
  std::vector<std::uint32_t> held;
  std::vector<Vec3> normal;
  double perimeter = 0; ///< P × thickness [m²]
  double setup_seconds = 0;
};

DiskModel build_disk(const Disk& d) {
  const auto start = std::chrono::steady_clock::now();
  DiskModel m;
  m.disk = d;
  // The boundary zone: the fewest rings of zones that the builder accepts, i.e. that hold every
  // arm of a free particle which would reach outside the disk.
  for (int rings = 1;; ++rings) {
    try {
      const EllipticDiskSpec spec = d.spec(rings);
      m.scene = elliptic_disk_scene(spec);
      m.zone_edge = spec.held_from_xi();
      break;
    } catch (const std::invalid_argument&) {
      if (rings >= d.zones_xi / 2) {
        throw;
      }
    }
  }
  m.model = build_model(m.scene);
  m.held = quasi_static::particles_in(m.model, m.scene.model.supports.front().region);
  for (std::uint32_t i : m.held) {
    m.normal.push_back(outward_normal(m.model.particles.position[i], d.c));
  }
  m.perimeter = perimeter(d.c, d.xi_max) * m.scene.model.dimension.thickness;
  m.setup_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return m;
}

/// The model at another elongation limit: eq. 118's per-arm limit δ_e/|ξ| scales with δ_e (one
/// material, so no minimum over the ends changes).
Model with_elongation_limit(const DiskModel& dm, double elongation_limit) {
  Model model = dm.model;
  Material& steel = model.spec.materials.front();
  const double ratio = elongation_limit / steel.elongation_limit.value();
  for (double& limit : model.field.bond_critical_stretch) {
    limit *= ratio;
  }
  steel.elongation_limit = elongation_limit;
  return model;
}

/// One disk loaded to failure at δ_e = `delta_over_c`·c: the history in DIR/curve.csv (one row per
/// relaxed increment) and the particles after the last increment in DIR/griffith-last.vtu.
Failure run_to_failure(const DiskModel& dm, double delta_over_c, const Stepping& st,
                       const std::filesystem::path& dir, bool progress) {
  const EllipticDiskTable1 t;
  const Disk& d = dm.disk;
  const Scene& scene = dm.scene;
  Model model = with_elongation_limit(dm, delta_over_c * d.c);
  const auto& held = dm.held;
  const auto& normal = dm.normal;
  const double P = dm.perimeter;
  Failure f;
  f.delta_over_c = delta_over_c;
  double last_stress = 0;
  quasi_static::Settings s;
  s.levels = st.levels();
  s.max_iterations = st.max_iterations;
  s.residual_tolerance = increment_tolerance;
  s.progress = progress;
  s.done = [&](const Simulation&) { return f.failed; };
  Json curve = Json::array();
  const std::string header =
      "increment,level,remote_stress_Pa,boundary_stress_Pa,broken_arms,plastic_reach_over_c,"
      "iterations,residual,converged";
  CurveRecorder record(dir, header, {}, "griffith",
                       [&](const Simulation& sim, const quasi_static::IncrementInfo& inc) {
                         // R_i = −b_i V_i, the force the zone's support exerts on particle i.
                         double sum = 0;
                         for (std::size_t k = 0; k < held.size(); ++k) {
                           const std::size_t i = held[k];
                           for (int a = 0; a < 2; ++a) {
                             sum -= sim.state().force[3 * i + static_cast<std::size_t>(a)] *
                                    sim.model().particles.volume[i] * normal[k][a];
                           }
                         }
                         last_stress = sum / P;
                         const double reach = plastic_reach(sim.model(), d.c);
                         if (inc.index == 1) {
                           f.elastic_factor = last_stress / (inc.fraction * t.yield_stress);
                         }
                         if (last_stress > f.failure_stress) {
                           f.failure_stress = last_stress;
                           f.failure_level = inc.fraction;
                           f.reach_at_peak = reach;
                         }
                         f.failed = last_stress < (1.0 - failure_drop) * f.failure_stress;
                         const std::size_t broken = quasi_static::broken_bonds(sim.model());
                         if (broken > 0 && f.first_break_level == 0) {
                           f.first_break_level = inc.fraction;
                         }
                         if (f.failed && !dir.empty()) {
                           write_vtu(dir / "griffith-last.vtu", sim);
                         }
                         Json row;
                         row["level"] = inc.fraction;
                         row["boundary_over_yield"] = last_stress / t.yield_stress;
                         row["broken_arms"] = broken;
                         row["plastic_reach_over_c"] = reach;
                         row["converged"] = inc.converged;
                         curve.push_back(row);
                         return fmt::format("{},{:.6f},{:.6e},{:.6e},{},{:.4f},{},{:.3e},{}",
                                            inc.index, inc.fraction, inc.fraction * t.yield_stress,
                                            last_stress, broken, reach, inc.iterations,
                                            inc.residual, inc.converged ? 1 : 0);
                       });
  const quasi_static::Outcome outcome =
      quasi_static::run(model, scene.solver, scene.initial, s, std::ref(record));

  Json& j = f.json;
  j["c"] = d.c;
  j["elongation_limit"] = delta_over_c * d.c;
  j["delta_over_c"] = delta_over_c;
  j["sqrt_delta_over_c"] = std::sqrt(delta_over_c);
  j["particles"] = model.size();
  j["arms"] = model.family.directed_bond_count() / 2;
  j["boundary_zone_particles"] = held.size();
  j["boundary_zone_inner_xi"] = dm.zone_edge;
  j["failed"] = f.failed;
  j["failure_stress"] = f.failure_stress;
  j["failure_over_yield"] = f.failure_stress / t.yield_stress;
  j["failure_level"] = f.failure_level;
  j["first_break_level"] = f.first_break_level;
  j["plastic_reach_over_c_at_peak"] = f.reach_at_peak;
  j["elastic_boundary_over_remote"] = f.elastic_factor;
  j["boundary_zone_distance_over_c"] = std::cosh(dm.zone_edge) - 1.0;
  j["setup_seconds"] = dm.setup_seconds;
  record_outcome(j, outcome, true);
  j["curve"] = curve;
  fmt::print("   c = {:.4g} m, delta_e = c/{:.0f}: sigma_f/sigma_y = {:.4f} at S/sigma_y = {:.3f} "
             "({}; {} particles, {} increments, {} not converged, {:.0f} s)\n",
             d.c, 1.0 / delta_over_c, f.failure_stress / t.yield_stress, f.failure_level,
             f.failed ? "failed" : "NOT failed", model.size(), outcome.increments.size(),
             increments_not_converged(outcome), outcome.wall_seconds);
  std::fflush(stdout);
  return f;
}

struct Variant {
  std::string name;
  Disk disk;
  Stepping stepping;
  std::vector<int> divisors;   ///< δ_e = c/divisor for the sweep, the last the smallest δ_e
  bool fit_gated = true;       ///< R² gated (a sensitivity variant runs one δ_e, no line)
  bool half_delta_pair = true; ///< also the pair at half the smallest δ_e (reported)
};

/// σ_f(c/2)/σ_f(c) at δ_e = c/`divisor` against √2: the long disk's run (`long_run`, or a run
/// made here) beside the short disk's. "passed": both failed and the ratio within the gate.
Json crack_length_pair(const DiskModel& long_disk, const DiskModel& short_disk, int divisor,
                       const Failure* long_run, const Stepping& st,
                       const std::filesystem::path& dir, bool progress) {
  const double delta_e = long_disk.disk.c / divisor;
  Failure made;
  if (long_run == nullptr) {
    made = run_to_failure(long_disk, 1.0 / divisor, st, dir / fmt::format("c-over-{}", divisor),
                          progress);
    long_run = &made;
  }
  const double c_short = short_disk.disk.c;
  Failure half = run_to_failure(short_disk, delta_e / c_short, st,
                                dir / fmt::format("half-crack-delta-c-over-{}", divisor), progress);
  const double ratio = half.failure_stress / long_run->failure_stress;
  const double ratio_error = ratio / std::numbers::sqrt2 - 1.0;
  Json sc;
  sc["elongation_limit"] = delta_e;
  sc["long_delta_over_c"] = 1.0 / divisor;
  sc["c_long"] = long_disk.disk.c;
  sc["c_short"] = c_short;
  sc["xi_max_short"] = short_disk.disk.xi_max;
  sc["zones_xi_short"] = short_disk.disk.zones_xi;
  sc["failure_stress_long"] = long_run->failure_stress;
  sc["failure_stress_short"] = half.failure_stress;
  sc["ratio"] = ratio;
  sc["reference_ratio"] = std::numbers::sqrt2;
  sc["error"] = ratio_error;
  // The same ratio in the remote stress S of the imposed field (the load axis): eq. 116 is the
  // exact elastic field of either disk, so linear elastic fracture mechanics gives exactly √2 in
  // S, while σ_b = κ S with a factor κ that depends on the disk's size over its crack (the first
  // increment's σ_b/S, `elastic_boundary_over_remote`). Gated as σ_b is: a ratio right in σ_b
  // but not in S would be right only through κ.
  const double remote_ratio = half.failure_level / long_run->failure_level;
  const double remote_error = remote_ratio / std::numbers::sqrt2 - 1.0;
  sc["remote_ratio"] = remote_ratio;
  sc["remote_ratio_error"] = remote_error;
  if (long_run == &made) {
    sc["long_run"] = std::move(made.json);
  }
  sc["short_run"] = std::move(half.json);
  sc["passed"] = long_run->failed && half.failed && std::abs(ratio_error) <= scaling_gate &&
                 std::abs(remote_error) <= scaling_gate;
  fmt::print("   c/2 at delta_e = c/{}: sigma_f ratio {:.4f} vs sqrt(2) ({:+.2f} %); in the remote "
             "stress S {:.4f} ({:+.2f} %)\n",
             divisor, ratio, 100 * ratio_error, remote_ratio, 100 * remote_error);
  return sc;
}

Json run_variant(const Context& ctx, const Variant& v) {
  const auto start = std::chrono::steady_clock::now();
  const EllipticDiskTable1 t;
  Json out;
  out["case"] = v.name;
  out["quantity"] = "failure stress of a cracked elliptical disk vs the elongation limit δ_e and "
                    "the crack length (Griffith, Olsson et al. eq. 117, Fig. 14)";
  Json& res = out["resolution"];
  res["zones"] = Json::array_of(std::vector<double>{static_cast<double>(v.disk.zones_xi),
                                                    static_cast<double>(v.disk.zones_eta)});
  res["pattern"] = v.disk.pattern;
  res["xi_max"] = v.disk.xi_max;
  res["paper_particles"] = EllipticDiskTable1{}.zones_xi * EllipticDiskTable1{}.zones_eta *
                           EllipticDiskTable1{}.pattern * EllipticDiskTable1{}.pattern;
  res["load_step_over_yield"] = v.stepping.step;
  if (v.disk.band.spacing > 0) {
    res["path_band_spacing_over_c"] = v.disk.band.spacing / v.disk.c;
    res["path_band_half_length_over_c"] = v.disk.band.half_length / v.disk.c;
    res["path_band_half_width_over_c"] = v.disk.band.half_width / v.disk.c;
  }
  const std::filesystem::path dir = ctx.output_dir / v.name;

  std::vector<double> x, y;
  Json rows = Json::array();
  bool all_failed = true;
  Failure at_scaling;
  const DiskModel disk = build_disk(v.disk);
  for (int divisor : v.divisors) {
    Failure f = run_to_failure(disk, 1.0 / divisor, v.stepping,
                               dir / fmt::format("c-over-{}", divisor), ctx.progress);
    all_failed = all_failed && f.failed;
    if (f.failed) {
      x.push_back(std::sqrt(f.delta_over_c));
      y.push_back(f.failure_stress / t.yield_stress);
    }
    if (divisor == v.divisors.back()) {
      at_scaling = f;
    }
    rows.push_back(std::move(f.json));
  }
  out["sweep"] = std::move(rows);
  bool fit_passed = false;
  if (x.size() >= 2) {
    const LineFit fit = fit_line(x, y);
    out["pd"]["slope"] = fit.slope;
    out["pd"]["intercept"] = fit.intercept;
    out["pd"]["r_squared"] = fit.r_squared;
    fit_passed = fit.r_squared >= r_squared_gate;
    fmt::print("   sigma_f/sigma_y = {:.4f} sqrt(delta_e/c) {:+.4f}, R^2 = {:.4f} ({} points)\n",
               fit.slope, fit.intercept, fit.r_squared, x.size());
  }

  // The c^(−1/2) law at fixed δ_e: the crack of half the length in the same outer boundary, at
  // the sweep's smallest δ_e, and reported beside it at half that δ_e (the short crack then at
  // the sweep's smallest δ_e/c; see the file's head).
  const DiskModel short_disk = build_disk(v.disk.shorter_crack(0.5));
  const int smallest = v.divisors.back();
  Json pair =
      crack_length_pair(disk, short_disk, smallest, &at_scaling, v.stepping, dir, ctx.progress);
  const bool scaling_passed = pair.find("passed")->boolean().value_or(false);
  const double ratio_error = *pair.find("error")->number();
  out["crack_length_scaling"] = std::move(pair);
  if (v.half_delta_pair) {
    out["crack_length_scaling_half_delta"] =
        crack_length_pair(disk, short_disk, 2 * smallest, nullptr, v.stepping, dir, ctx.progress);
  }
  out["reference"]["r_squared"] = r_squared_gate;
  out["reference"]["ratio"] = std::numbers::sqrt2;
  out["error"]["ratio"] = std::abs(ratio_error);
  finish_case(out,
              fmt::format("every run fails (σ_b falls {:g} % below its peak); R² of σ_f/σ_y "
                          "against √(δ_e/c) ≥ {:g}; σ_f(c/2)/σ_f(c) within {:g} % of √2 at the "
                          "sweep's smallest δ_e, in σ_b and in the remote stress S",
                          100 * failure_drop, r_squared_gate, 100 * scaling_gate),
              all_failed && (fit_passed || !v.fit_gated) && scaling_passed, start);
  return out;
}

/// The elongation limits of the full sweeps: c/750 … c/3250 in steps of c/250, eleven values
/// (§10.4 steps Fig. 14 by c/250 from c/500; docs/theory/griffith.md says why the sweeps start at
/// c/750).
std::vector<int> fig14_sweep() {
  std::vector<int> divisors;
  for (int k = 750; k <= 3250; k += 250) {
    divisors.push_back(k);
  }
  return divisors;
}

/// A disk finer than the CI one (zones along ξ, around, pattern) at ΔS = 0.005 σ_y, with the
/// c^(−1/2) ratio gated and the pair at half the smallest δ_e reported.
Variant finer_variant(std::string name, std::array<int, 3> zones, std::vector<int> divisors) {
  Variant v;
  v.name = std::move(name);
  v.disk.zones_xi = zones[0];
  v.disk.zones_eta = zones[1];
  v.disk.pattern = zones[2];
  v.stepping.step = 0.005;
  v.divisors = std::move(divisors);
  return v;
}

/// The disk of the gated c^(−1/2) comparison (docs/theory/griffith.md, "Design"): zones of Δξ = 0.1
/// and Δη = 2π/20 with 4 × 4 particles out to `xi_max` (≥ 2.7: the boundary zone several plastic
/// zones away from either crack), and the crack's path |x| ≤ 2c, |y| ≤ c/2 at the one spacing
/// c/`per_c` for both crack lengths, so that neither the disk's edge nor its grading sets where
/// the growing crack arrests.
Variant path_variant(std::string name, double xi_max, double per_c, std::vector<int> divisors) {
  Variant v = finer_variant(std::move(name), {static_cast<int>(std::lround(10 * xi_max)), 20, 4},
                            std::move(divisors));
  const double c = v.disk.c;
  v.disk.xi_max = xi_max;
  v.disk.band = {c / per_c, 2 * c, c / 2};
  return v;
}

} // namespace

Json run_griffith(const Context& ctx) {
  Variant v;
  v.name = "griffith";
  v.stepping.step = 0.01;
  v.divisors = {750, 1000, 1500, 2250, 3250};
  v.half_delta_pair = false;
  return run_variant(ctx, v);
}

Json run_griffith_full(const Context& ctx) {
  return run_variant(ctx, path_variant("griffith-full", 2.7, 32, fig14_sweep()));
}

Json run_griffith_boundary(const Context& ctx) {
  // griffith-resolution's c^(−1/2) pair on a larger disk: does the failure stress still move
  // with it? At the path spacing of griffith-resolution, c/64, where the horizon is below the
  // c/3250 process zone: at griffith-full's c/32 it is not, and the pair moved from −3.3 % to
  // −6.1 % with the boundary, against +1.4 % and +1.9 % at c/64 (docs/theory/griffith.md).
  Variant v = path_variant("griffith-boundary", 3.2, 64, {3250});
  v.fit_gated = false;
  v.half_delta_pair = false;
  return run_variant(ctx, v);
}

Json run_griffith_resolution(const Context& ctx) {
  // griffith-full's c^(−1/2) pair with the crack's path at twice the density, the finest
  // affordable here (22,468 particles; c/48 at commit 90b1437).
  Variant v = path_variant("griffith-resolution", 2.7, 64, {3250});
  v.fit_gated = false;
  v.half_delta_pair = false;
  return run_variant(ctx, v);
}

Json run_griffith_table1(const Context& ctx) {
  // Table 1's particle density (the builder's reading: 5 × 5 particles in zones of Δξ = π/40,
  // Δη = π/20) on this case's ξ_max = 2: 25 × 40 zones, 25,000 particles, and the full sweep:
  // its R² gate is the issue's, which is about eight or more elongation limits. It fails both
  // gates (R² 0.9736, pair +7.4 %): the five largest δ_e fail above σ_y, far from
  // small-scale yielding (the six below give R² 0.998), and without the path band the crack
  // grows into the grading's coarser zones. docs/theory/griffith.md has the numbers.
  Variant v = finer_variant("griffith-table1", {25, 40, 5}, fig14_sweep());
  // At this density, without the path band, the c/750 crack still holds at S = 2 σ_y (σ_b/S
  // 0.68: the plate yields widely) since each increment's plastic flow is recomputed from its
  // start (docs/theory/griffith.md); the load goes on until it runs.
  v.stepping.last = 3.0;
  return run_variant(ctx, v);
}

PD_VERIFICATION_RUN("griffith", run_griffith);
PD_VERIFICATION_RUN("griffith-full", run_griffith_full);
PD_VERIFICATION_RUN("griffith-boundary", run_griffith_boundary);
PD_VERIFICATION_RUN("griffith-resolution", run_griffith_resolution);
PD_VERIFICATION_RUN("griffith-table1", run_griffith_table1);

} // namespace pd::verification
