// Displacement-controlled quasi-static loading for the quasi-brittle cases (rc-beam,
// compression-cube): the prescribed displacements of a scene are applied in equal increments and
// each increment is relaxed with adaptive dynamic relaxation until the out-of-balance force is
// small, so the recorded load–displacement curve is a sequence of equilibrium states with damage
// (Miranda §5.2 loads with a slow ramp under kinematic damping, §3.2; relaxing every increment is
// the quasi-static limit of that ramp and does not depend on a damping coefficient).
//
// Why not a ramp with `steady:`: one ramp gives one steady state at the end; the curve needs the
// equilibrium at every increment. The driver therefore owns the Model and rewrites the prescribed
// values of its constraints between increments (apply_constraints reads them every step).
//
// Each increment: (1) linear predictor — the free particles are moved by the displacement change
// of the previous increment (Simulation::perturb) while the prescribed values jump to the new
// level, so that the bonds next to the moved supports are not stretched by a one-sided jump (a
// jump of Δu over one spacing λ is a stretch Δu/λ, far beyond s0 ≈ 1e-4, and would break bonds
// that equilibrium would never break); the first increment, which has no predictor, moves its
// prescribed values over `first_ramp_iterations` ADR iterations instead; (2) relaxation until
// ‖free-dof force‖ ≤ tol · max(‖reactions‖, 5 % of the largest ‖reactions‖ so far) or
// `max_iterations`. Bonds break during the relaxation, so
// a crack that propagates unstably does so inside the increment, as under displacement control.
#pragma once

#include "libpd/model.hpp"
#include "libpd/output.hpp"
#include "libpd/scene.hpp"
#include "libpd/simulation.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fmt/format.h>
#include <functional>
#include <string>
#include <vector>

namespace pd::verification::quasi_static {

struct Settings {
  /// Levels of the prescribed displacement, as fractions of the scene's values, increasing.
  std::vector<double> levels;
  /// The first increment has no predictor: its prescribed values move over this many iterations.
  std::size_t first_ramp_iterations = 200;
  std::size_t max_iterations = 400; ///< per increment, ramp included
  std::size_t check_every = 10;
  double residual_tolerance = 1e-3;
  std::vector<int> vtu_increments; ///< increments (1-based) after which a VTU is written
  std::string vtu_prefix = "particles";
  std::filesystem::path output_dir; ///< curve.csv and VTU files; empty: none
  double wall_limit_seconds = 0;    ///< stop after the increment that crosses it; 0: none
  bool progress = false;
  /// Checked after every increment; true ends the run early (e.g. a sweep that only needs the
  /// peak). Empty: run all increments.
  std::function<bool(const Simulation&)> done;
};

struct IncrementInfo {
  int index = 0;       ///< 1-based
  double fraction = 0; ///< of the full prescribed displacement
  std::size_t iterations = 0;
  double residual = 0; ///< ‖free-dof force‖ / ‖reactions‖ at the end of the increment
  bool converged = false;
};

struct Outcome {
  std::vector<IncrementInfo> increments;
  bool completed = false; ///< all increments done (not stopped by the wall limit or instability)
  std::string stop_reason;
  double wall_seconds = 0;
  std::size_t iterations = 0;
};

/// Σ b_c V over the particles: the force the bonds exert on them (the support supplies −that).
inline double bond_force(const Simulation& sim, const std::vector<std::uint32_t>& particles,
                         int component) {
  double sum = 0;
  for (std::uint32_t i : particles) {
    sum += sim.state().force[3 * i + static_cast<std::size_t>(component)] *
           sim.model().particles.volume[i];
  }
  return sum;
}

/// Particles of a region (any body), as the model resolves supports.
inline std::vector<std::uint32_t> particles_in(const Model& model, const Region& region) {
  std::vector<std::uint32_t> out;
  const double tol = 1e-6 * model.spec.lattice.spacing;
  for (std::size_t i = 0; i < model.size(); ++i) {
    if (region.contains(model.particles.position[i], model.spec.dimension.dim, tol)) {
      out.push_back(static_cast<std::uint32_t>(i));
    }
  }
  return out;
}

/// Broken bonds (each counted once).
inline std::size_t broken_bonds(const Model& model) {
  std::size_t n = 0;
  for (std::uint8_t b : model.state.broken) {
    n += b;
  }
  return n / 2;
}

/// Run `scene` (its supports' `displacement` values are the full prescribed displacements) through
/// `settings.levels`. After every increment `row(sim, info)` returns a CSV
/// row (without newline); the rows are appended to OUTPUT_DIR/curve.csv, rewritten atomically
/// after every increment so an interrupted run keeps the curve so far.
inline Outcome run(Model& model, const Scene& scene, const Settings& settings,
                   const std::string& csv_header,
                   const std::function<std::string(const Simulation&, const IncrementInfo&)>& row) {
  using clock = std::chrono::steady_clock;
  const auto start = clock::now();
  Outcome out;
  std::vector<double> full(model.constraints.size());
  for (std::size_t k = 0; k < full.size(); ++k) {
    full[k] = model.constraints[k].value;
    model.constraints[k].value = 0;
  }
  SolverSpec solver = scene.solver;
  solver.integrator = IntegratorKind::adr;
  solver.dt = 1.0;
  solver.ramp_time = 0;
  solver.end_time.reset();
  solver.steady.enabled = false;
  solver.max_steps = 1'000'000'000;
  Simulation sim(model, solver, scene.initial);

  const std::size_t ndof = 3 * model.size();
  std::vector<std::uint8_t> constrained(ndof, 0);
  for (const Constraint& c : model.constraints) {
    constrained[3 * c.particle + c.component] = 1;
  }
  // After a failure the reactions fall towards zero and a residual relative to them can never
  // become small; the reference is therefore never below 5 % of the largest reactions so far.
  double largest_reactions = 0;
  auto residual = [&]() {
    double free = 0, reactions = 0;
    for (std::size_t d = 0; d < ndof; ++d) {
      const double f = sim.state().force[d] * model.particles.volume[d / 3];
      (constrained[d] ? reactions : free) += f * f;
    }
    largest_reactions = std::max(largest_reactions, std::sqrt(reactions));
    const double reference = std::max(std::sqrt(reactions), 0.05 * largest_reactions);
    return reference > 0 ? std::sqrt(free) / reference : std::sqrt(free);
  };
  auto displacement = [&]() {
    std::vector<double> u(ndof);
    for (std::size_t d = 0; d < ndof; ++d) {
      u[d] = sim.state().position[d] - model.particles.position[d / 3][d % 3];
    }
    return u;
  };
  auto set_level = [&](double fraction) {
    for (std::size_t k = 0; k < full.size(); ++k) {
      model.constraints[k].value = fraction * full[k];
    }
  };

  std::string csv = csv_header + "\n";
  const auto& dir = settings.output_dir;
  const int n = static_cast<int>(settings.levels.size());
  auto level = [&](int k) {
    return k > 0 ? settings.levels[static_cast<std::size_t>(k - 1)] : 0.0;
  };
  int inc = 1;
  std::size_t it = 0;
  std::vector<double> u_start = displacement(), u_previous_start = u_start;
  bool extrapolate = false;
  auto begin_increment = [&]() {
    it = 0;
    u_previous_start = u_start;
    u_start = displacement();
    if (extrapolate) {
      std::vector<double> du(ndof);
      for (std::size_t d = 0; d < ndof; ++d) {
        du[d] = u_start[d] - u_previous_start[d];
      }
      // The constrained components are set by perturb's apply_constraints; move them first.
      // Linear extrapolation in the load level: scale by the ratio of the level steps.
      const double scale = (level(inc) - level(inc - 1)) / (level(inc - 1) - level(inc - 2));
      for (double& v : du) {
        v *= scale;
      }
      set_level(level(inc));
      sim.perturb(du);
    }
  };
  begin_increment();

  auto observer = [&](const Simulation&) {
    ++it;
    ++out.iterations;
    const std::size_t ramp = inc == 1 ? settings.first_ramp_iterations : 0;
    if (it <= ramp) {
      set_level(level(inc) * static_cast<double>(it) / static_cast<double>(ramp));
      return true;
    }
    const bool check = it % settings.check_every == 0 || it >= settings.max_iterations;
    if (!check) {
      return true;
    }
    const double r = residual();
    if (r > settings.residual_tolerance && it < settings.max_iterations) {
      return true;
    }
    IncrementInfo info{inc, level(inc), it, r, r <= settings.residual_tolerance};
    out.increments.push_back(info);
    csv += row(sim, info) + "\n";
    if (!dir.empty()) {
      write_file_atomically(dir / "curve.csv", csv);
      for (int v : settings.vtu_increments) {
        if (v == inc) {
          write_vtu(dir / fmt::format("{}-inc{:03d}.vtu", settings.vtu_prefix, inc), sim);
        }
      }
    }
    const double wall = std::chrono::duration<double>(clock::now() - start).count();
    if (settings.progress) {
      fmt::print(stderr, "  increment {:>3}/{}: {:>5} iterations, residual {:.2e}, {:.0f} s\n", inc,
                 n, it, r, wall);
    }
    if (inc == n) {
      out.completed = true;
      return false;
    }
    if (settings.done && settings.done(sim)) {
      out.stop_reason = fmt::format("stopped by the case after increment {} of {}", inc, n);
      return false;
    }
    if (settings.wall_limit_seconds > 0 && wall > settings.wall_limit_seconds) {
      out.stop_reason = fmt::format("wall limit {:.0f} s reached after increment {} of {}",
                                    settings.wall_limit_seconds, inc, n);
      return false;
    }
    ++inc;
    extrapolate = true;
    begin_increment();
    return true;
  };
  const RunResult result = sim.run(observer);
  if (result.status == RunStatus::unstable) {
    out.stop_reason = result.message;
  }
  out.wall_seconds = std::chrono::duration<double>(clock::now() - start).count();
  return out;
}

} // namespace pd::verification::quasi_static
