// elliptic-disk (issue 17, Olsson, Ander & Williams 2021 §10.2–10.3, Fig. 10): the elastic
// convergence of the virtual-fibre model on the paper's graded disk. The disk
// (elliptic_disk.hpp) has its boundary zone held at the closed form of eq. 116, so eq. 116 is
// its exact solution; the case relaxes it by ADR (the static solver refuses the fibre model) and
// measures the RMS displacement error of the interior against eq. 116 at several densities
// (particles per zone side, the zone grid fixed), as Fig. 10 does.
//
// "Interior" is every particle not held: the held zone is exact by construction, so counting it
// would only dilute the error by an amount that depends on the zone's width. The held zone is at
// least a horizon deep (checked when the disk is built), so every interior particle has a full
// neighbourhood. The crack faces and tips are interior (eq. 116's √r singularity).
//
// The error measures, each over the interior:
//   rms        = √(Σ|u − u₁₁₆|² / n) / √(Σ|u₁₁₆|² / n)   (per particle, as Fig. 10's RMS)
//   l2         = √(Σ V|u − u₁₁₆|² / Σ V|u₁₁₆|²)        (volume-weighted: the field's L2 error)
// and, reported only, the rms over the particles farther than c/4 from both crack tips (the √r
// singularity's share of the error),
// `crack_opening_ratio`, the mean of v/v₁₁₆ over the particles within 1.5 local spacings of the
// crack's faces away from its tips (|x| < 0.85 c), reported only,
// and `rms_metres`, the unnormalised RMS. The observed rate is the slope of log(rms) against
// log(particle count), fitted (runner/observed_order.hpp) against the mean spacing √(A/n): the
// order in spacing is twice the rate in particle count (2D).
//
// Gate: each run reaches its steady state, rms falls at every refinement and the observed order
// is at least `min_order`. Fig. 10 plots the RMS error against particle count for five densities
// up to 39,200 particles but states no rate or value, so the order held to is the library's:
// first order in spacing (docs/theory/elliptic-disk.md), less 0.2 for a least-squares slope over
// four or five levels of Monte Carlo sets.
//
// `elliptic-disk` (label verification): a coarser zone grid, 10 × 20 zones, 3…6 particles per
// zone side (1,800 … 7,200 particles). `elliptic-disk-convergence` (verification-full): the
// paper's grid, 20 × 40 zones, 3…7 particles per side (7,200 … 39,200), Fig. 10's densities.
//
// Measured, and the diagnosis of what did not converge before the relaxed moduli
// (fibre_relaxation.cpp): docs/theory/elliptic-disk.md. In short (seed 1, --threads 1), RMS
// error and crack opening ratio:
//   elliptic-disk             1,800 … 7,200: 1.79, 1.41, 1.12, 0.89 %, openings 0.9987–1.0001,
//                             order 1.00 in spacing (seeds 2–5: 1.06–1.28).
//   elliptic-disk-convergence 7,200 … 39,200: 0.98, 0.75, 0.62, 0.48, 0.43 %, openings
//                             0.9979–0.9996, order 0.99 (seeds 2, 3: 1.00, 1.01). Before the
//                             correction the crack opened 1 % too wide at every density (the
//                             unbalanced network's Poisson ratio, 0.305 for 0.3), the order was
//                             0.39 and seed 2 failed.
//   elliptic-disk-regular     (no noise, CI grid) 0.62, 0.38, 0.27 % (L2 0.35, 0.20, 0.14 %), order
//                             1.61, crack opening 1.0016 → 1.0005: the balance applies, no
//                             relaxation is needed.
// ADR's steady state (force 1e-7, kinetic 1e-12) is far below the error: 1e-10 / 1e-20 leave
// every RMS of elliptic-disk unchanged in 4 digits.
#include "elliptic_disk.hpp"
#include "libpd/app/run.hpp"
#include "observed_order.hpp"
#include "verification.hpp"

#include <cmath>
#include <cstdio>
#include <fmt/format.h>
#include <stdexcept>
#include <string>
#include <vector>

namespace pd::verification {

namespace {

constexpr double min_order = 0.8;

struct DiskError {
  Json json;
  std::size_t particles = 0;
  double mean_spacing = 0; ///< √(area / particles)
  double rms = 0;
  double l2 = 0;
  double seconds = 0; ///< set-up (arms, balance) and solve
  bool converged = false;
};

/// The disk of `spec` relaxed and compared with eq. 116 over its interior.
DiskError run_disk(const Context& ctx, const EllipticDiskSpec& spec, const std::string& folder) {
  const Scene scene = elliptic_disk_scene(spec);
  RunOptions opt = case_run_options(ctx, folder);
  opt.write_vtu = false;
  opt.keep_final_field = true;
  const RunOutcome run = run_scene(scene, opt);
  const PointCloud& cloud = *scene.model.bodies.front().points;
  if (run.positions.size() != cloud.count()) {
    throw std::logic_error("elliptic disk: the run's particles are not the disk's");
  }
  double error2 = 0, exact2 = 0, v_error2 = 0, v_exact2 = 0, area = 0;
  double far_error2 = 0, far_exact2 = 0; // beyond c/4 of both tips
  double opening_ratio = 0;              // Σ v/v₁₁₆ over the crack faces' particles
  std::size_t face_particles = 0;
  const double c = spec.table.focal_half_distance;
  std::size_t interior = 0;
  for (std::size_t i = 0; i < cloud.count(); ++i) {
    const Vec3& x = run.positions[i];
    if (x != cloud.position[i]) {
      throw std::logic_error("elliptic disk: the run's particle order is not the disk's");
    }
    area += cloud.volume[i] / scene.model.dimension.thickness;
    if (spec.held(x)) {
      continue;
    }
    const Vec3 exact = spec.exact_displacement(x);
    double e2 = 0, u2 = 0;
    for (std::size_t k = 0; k < 2; ++k) {
      const double d = run.displacement[3 * i + k] - exact[k];
      e2 += d * d;
      u2 += exact[k] * exact[k];
    }
    error2 += e2;
    exact2 += u2;
    v_error2 += cloud.volume[i] * e2;
    v_exact2 += cloud.volume[i] * u2;
    // The crack faces: within 1.5 local spacings (√ of the particle's area) of the crack, away
    // from the tips' singularity.
    const double spacing = std::sqrt(cloud.volume[i] / scene.model.dimension.thickness);
    if (std::abs(x[0]) < 0.85 * c && std::abs(x[1]) < 1.5 * spacing) {
      opening_ratio += run.displacement[3 * i + 1] / exact[1];
      ++face_particles;
    }
    if (std::min(std::hypot(x[0] - c, x[1]), std::hypot(x[0] + c, x[1])) > c / 4) {
      far_error2 += e2;
      far_exact2 += u2;
    }
    ++interior;
  }
  DiskError out;
  out.particles = run.particles;
  out.mean_spacing = std::sqrt(area / static_cast<double>(run.particles));
  out.rms = std::sqrt(error2 / exact2);
  out.seconds = run.setup_seconds + run.result.wall_seconds;
  out.converged = run.result.status == RunStatus::converged;
  out.l2 = std::sqrt(v_error2 / v_exact2);
  const double l2 = out.l2;
  Json& j = out.json;
  j["pattern"] = spec.pattern;
  j["particles"] = run.particles;
  j["interior_particles"] = interior;
  j["held_particles"] = run.particles - interior;
  j["arms"] = run.bonds;
  j["mean_spacing"] = out.mean_spacing;
  j["rms"] = out.rms;
  j["l2"] = l2;
  j["rms_metres"] = std::sqrt(error2 / static_cast<double>(interior));
  j["rms_beyond_quarter_c_of_the_tips"] = std::sqrt(far_error2 / far_exact2);
  const double opening = face_particles ? opening_ratio / static_cast<double>(face_particles) : 0.0;
  j["crack_opening_ratio"] = face_particles ? Json(opening) : Json{};
  j["status"] = to_string(run.result.status);
  j["steps"] = run.result.steps;
  j["setup_seconds"] = run.setup_seconds;
  j["solve_seconds"] = run.result.wall_seconds;
  if (const Json* balance = run.summary.find("fibre_balance")) {
    j["fibre_balance"] = *balance;
  }
  fmt::print("   {:>6} particles ({} interior): RMS error {:.4e} (L2 {:.4e}), crack opening × "
             "{:.4f}, {} steps, {}, set-up {:.1f} s, solve {:.1f} s\n",
             run.particles, interior, out.rms, l2, opening, run.result.steps,
             out.converged ? "converged" : "NOT converged", run.setup_seconds,
             run.result.wall_seconds);
  std::fflush(stdout); // a long case shows each run as it ends
  return out;
}

/// Runs of the disk at several densities, coarsest first, and the observed order of their RMS
/// error.
struct Series {
  Json rows = Json::array();
  ObservedOrder order;
  bool falling = true;   ///< the RMS error falls at every refinement
  bool converged = true; ///< every run reached its steady state
};

Series run_series(const Context& ctx, const std::string& folder, const EllipticDiskSpec& base,
                  const std::vector<int>& patterns) {
  Series s;
  std::vector<std::pair<double, double>> spacing_error;
  for (const int p : patterns) {
    EllipticDiskSpec spec = base;
    spec.pattern = p;
    DiskError e = run_disk(ctx, spec, fmt::format("{}/p{}", folder, p));
    s.converged = s.converged && e.converged;
    s.falling = s.falling && (spacing_error.empty() || e.rms < spacing_error.back().second);
    spacing_error.emplace_back(e.mean_spacing, e.rms);
    s.rows.push_back(std::move(e.json));
  }
  s.order = observed_order(spacing_error);
  // RMS ∝ h^p and h ∝ n^(−1/2) in 2D: RMS ∝ n^(−p/2).
  fmt::print("   observed order {} (RMS ∝ n^−{:.3f} in particle count)\n", s.order.text(),
             s.order.order ? *s.order.order / 2 : 0.0);
  return s;
}

Json series_json(Series& s) {
  Json j;
  j["runs"] = std::move(s.rows);
  j["observed_order"] = to_json(s.order);
  j["rate_in_particle_count"] = s.order.order ? Json(*s.order.order / 2) : Json{};
  return j;
}

/// The gated series at `patterns`.
Json run_densities(const Context& ctx, const std::string& name, const EllipticDiskSpec& base,
                   const std::vector<int>& patterns) {
  const auto start = std::chrono::steady_clock::now();
  Json out;
  out["case"] = name;
  out["quantity"] = "RMS displacement error of the interior against eq. 116 (Olsson et al. 2021, "
                    "Fig. 10), virtual fibres, graded elliptical disk";
  out["zones"] = Json::array_of(std::vector<int>{base.zones_xi(), base.zones_eta()});
  out["xi_max"] = base.xi_max;
  out["remote_stress"] = base.remote_stress;
  out["monte_carlo_sweeps"] = base.sweeps;
  Series gated = run_series(ctx, name, base, patterns);
  const bool ordered = gated.order.order && *gated.order.order >= min_order;
  const bool passed = gated.converged && gated.falling && ordered;
  Json series = series_json(gated);
  out["runs"] = *series.find("runs");
  out["observed_order"] = *series.find("observed_order");
  out["rate_in_particle_count"] = *series.find("rate_in_particle_count");
  out["pd"]["observed_order"] = gated.order.order ? Json(*gated.order.order) : Json{};
  out["reference"]["min_observed_order"] = min_order;
  finish_case(out,
              fmt::format("every run at its steady state, the RMS error falling at every "
                          "refinement and the observed order in spacing ≥ {:g}",
                          min_order),
              passed, start);
  return out;
}

/// The coarse zone grid of the CI case.
EllipticDiskSpec coarse_grid() {
  EllipticDiskSpec spec;
  spec.table.zones_xi /= 2; // 10 × 20 zones instead of 20 × 40
  spec.table.zones_eta /= 2;
  return spec;
}

/// The uniform sets' particle count and time at a graded set's error: log n and log t are
/// interpolated linearly in log(error) between the two uniform sets around it (extrapolated from
/// the nearest two beyond them, and said so). The error is the volume-weighted L2 one: the
/// per-particle RMS weights the field where the particles are, which for the graded set is at the
/// crack tips, so it would not compare the two sets' fields. Where the uniform sets' error does
/// not fall with refinement there is no such set: the match is null, with the reason.
Json equal_error(const DiskError& graded, const std::vector<DiskError>& uniform) {
  const double e = graded.l2;
  Json m;
  m["graded_particles"] = graded.particles;
  m["l2"] = e;
  m["graded_seconds"] = graded.seconds;
  for (std::size_t k = 1; k < uniform.size(); ++k) {
    if (!(uniform[k].l2 < uniform[k - 1].l2)) {
      m["how"] = "none: the uniform sets' L2 error does not fall with refinement";
      fmt::print("   graded {} particles, L2 error {:.4e}: no uniform set matches it (their "
                 "error does not fall)\n",
                 graded.particles, e);
      return m;
    }
  }
  std::size_t k = 1; // interpolate between uniform[k − 1] and uniform[k]
  while (k + 1 < uniform.size() && uniform[k].l2 > e) {
    ++k;
  }
  const DiskError& a = uniform[k - 1];
  const DiskError& b = uniform[k];
  const double f = std::log(e / a.l2) / std::log(b.l2 / a.l2);
  const auto at = [f](double va, double vb) {
    return std::exp(std::log(va) + f * (std::log(vb) - std::log(va)));
  };
  const double particles = at(static_cast<double>(a.particles), static_cast<double>(b.particles));
  const double seconds = at(a.seconds, b.seconds);
  const bool inside = f >= 0 && f <= 1;
  m["uniform_particles"] = std::lround(particles);
  m["particle_ratio"] = particles / static_cast<double>(graded.particles);
  m["uniform_seconds"] = seconds;
  m["time_ratio"] = seconds / graded.seconds;
  m["how"] = inside ? "interpolated" : "extrapolated beyond the uniform sets run";
  fmt::print(
      "   graded {} particles, L2 error {:.4e}: a uniform set needs {:.0f} particles ({:.3g}×), "
      "{:.1f} s against {:.1f} s ({:.3g}×; {})\n",
      graded.particles, e, particles, particles / static_cast<double>(graded.particles), seconds,
      graded.seconds, seconds / graded.seconds, inside ? "interpolated" : "extrapolated");
  return m;
}

Json rows_of(const std::vector<DiskError>& runs) {
  Json a = Json::array();
  for (const DiskError& r : runs) {
    a.push_back(r.json);
  }
  return a;
}

/// Graded sets of `base` at `patterns` per zone side and uniform ones at spacings c/`per_c` (the
/// same held zone), and the uniform set matching each graded one's error.
Json compare_sets(const Context& ctx, const std::string& folder, const EllipticDiskSpec& base,
                  const std::vector<int>& patterns, const std::vector<double>& per_c,
                  bool& converged) {
  std::vector<DiskError> graded, uniform;
  for (const int p : patterns) {
    EllipticDiskSpec spec = base;
    spec.pattern = p;
    graded.push_back(run_disk(ctx, spec, fmt::format("{}/graded-p{}", folder, p)));
    converged = converged && graded.back().converged;
  }
  for (const double k : per_c) {
    EllipticDiskSpec spec = base;
    spec.particles = DiskParticles::uniform;
    spec.uniform_spacing = base.table.focal_half_distance / k;
    uniform.push_back(run_disk(ctx, spec, fmt::format("{}/uniform-c{}", folder, k)));
    uniform.back().json["spacing"] = spec.uniform_spacing;
    converged = converged && uniform.back().converged;
  }
  Json out;
  out["monte_carlo_sweeps"] = base.sweeps;
  out["zones"] = Json::array_of(std::vector<int>{base.zones_xi(), base.zones_eta()});
  out["graded"] = rows_of(graded);
  out["uniform"] = rows_of(uniform);
  Json matches = Json::array();
  for (const DiskError& g : graded) {
    matches.push_back(equal_error(g, uniform));
  }
  out["equal_error"] = std::move(matches);
  return out;
}

} // namespace

Json run_elliptic_disk_saving(const Context& ctx) {
  const auto start = std::chrono::steady_clock::now();
  Json out;
  out["case"] = "elliptic-disk-saving";
  out["quantity"] = "particles and time a uniform particle set needs for the L2 displacement "
                    "error of the graded one (the disk of elliptic-disk-convergence)";
  bool converged = true;
  // The paper's arrangement (Monte Carlo noise, Fig. 8) and grid. Uniform spacings c/12 … c/32:
  // about 2,600 … 18,600 particles (at c/8 a horizon reaches past the held zone, two rings deep).
  fmt::print("   with the Monte Carlo noise of Fig. 8:\n");
  out["noisy"] = compare_sets(ctx, "elliptic-disk-saving", EllipticDiskSpec{}, {3, 5},
                              {12.0, 20.0, 32.0}, converged);
  // The regular zone patterns, whose arms the balance of fibre_arms.hpp makes consistent at most
  // particles; it then dominates the set-up, so the coarse grid of elliptic-disk.
  fmt::print("   regular patterns (no noise), 10 × 20 zones:\n");
  EllipticDiskSpec regular = coarse_grid();
  regular.sweeps = 0;
  out["regular"] = compare_sets(ctx, "elliptic-disk-saving/regular", regular, {3, 4},
                                {8.0, 12.0, 16.0}, converged);
  // The paper's claim, on the sets whose uniform errors fall (the regular ones; the noisy uniform
  // sets are not monotone for this seed, docs/theory/elliptic-disk.md): a uniform set needs more
  // particles than the graded set for the same error.
  const Json* regular_matches = out["regular"].find("equal_error");
  bool saves = regular_matches != nullptr && regular_matches->items() != nullptr;
  for (const Json& m : saves ? *regular_matches->items() : Json::Array{}) {
    const Json* ratio = m.find("particle_ratio");
    saves = saves && ratio != nullptr && ratio->number() && *ratio->number() > 1;
  }
  out["graded_saves_particles"] = saves;
  finish_case(out,
              "every run at its steady state and, on the regular patterns, a uniform set needs "
              "more particles than each graded set for the same RMS error (Olsson et al., Fig. 10)",
              converged && saves, start);
  return out;
}

Json run_elliptic_disk(const Context& ctx) {
  return run_densities(ctx, "elliptic-disk", coarse_grid(), {3, 4, 5, 6});
}

Json run_elliptic_disk_convergence(const Context& ctx) {
  return run_densities(ctx, "elliptic-disk-convergence", EllipticDiskSpec{}, {3, 4, 5, 6, 7});
}

Json run_elliptic_disk_regular(const Context& ctx) {
  // Without noise the arms' balance (fibre_arms.hpp) applies at most particles and takes most of
  // the set-up (489 s at 7,200 particles under load 20, growing faster than the count): the CI
  // case's coarse grid.
  EllipticDiskSpec spec = coarse_grid();
  spec.sweeps = 0;
  return run_densities(ctx, "elliptic-disk-regular", spec, {3, 4, 5});
}

PD_VERIFICATION_RUN("elliptic-disk", run_elliptic_disk);
PD_VERIFICATION_RUN("elliptic-disk-convergence", run_elliptic_disk_convergence);
PD_VERIFICATION_RUN("elliptic-disk-regular", run_elliptic_disk_regular);
PD_VERIFICATION_RUN("elliptic-disk-saving", run_elliptic_disk_saving);

} // namespace pd::verification
