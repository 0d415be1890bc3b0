#include "libpd/time/quasi_static.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fmt/format.h>
#include <stdexcept>

namespace pd::quasi_static {

/// Σ b_c V over the particles: the force the bonds exert on them (the support supplies −that).
double bond_force(const Simulation& sim, const std::vector<std::uint32_t>& particles,
                  int component) {
  double sum = 0;
  for (std::uint32_t i : particles) {
    sum += sim.state().force[3 * i + static_cast<std::size_t>(component)] *
           sim.model().particles.volume[i];
  }
  return sum;
}

/// Particles of a region (any body), as the model resolves supports.
std::vector<std::uint32_t> particles_in(const Model& model, const Region& region) {
  std::vector<std::uint32_t> out;
  const double tol = 1e-6 * model.spec.lattice.spacing;
  for (std::size_t i = 0; i < model.body_particle_count(); ++i) {
    if (region.contains(model.particles.position[i], model.spec.dimension.dim, tol)) {
      out.push_back(static_cast<std::uint32_t>(i));
    }
  }
  return out;
}

/// Broken bonds (each counted once).
std::size_t broken_bonds(const Model& model) {
  std::size_t n = 0;
  for (std::uint8_t b : model.state.broken) {
    n += b;
  }
  return n / 2;
}

namespace {

/// The prescribed values of the model's constraints, which are then set to zero: the increments
/// scale the full values themselves.
std::vector<double> take_prescribed_values(Model& model) {
  std::vector<double> full(model.constraints.size());
  for (std::size_t k = 0; k < full.size(); ++k) {
    full[k] = model.constraints[k].value;
    model.constraints[k].value = 0;
  }
  return full;
}

/// The scene's solver settings as one increment's solve uses them: `kind`, Δt = 1 (ADR's
/// fictitious time), no ramp, no end time or steady check (the increment loop decides when an
/// increment has converged) and no step limit of its own.
SolverSpec increment_solver(const SolverSpec& scene_solver, IntegratorKind kind) {
  SolverSpec solver = scene_solver;
  solver.integrator = kind;
  solver.dt = 1.0;
  solver.ramp_time = 0;
  solver.end_time.reset();
  solver.steady.enabled = false;
  solver.max_steps = 1'000'000'000;
  return solver;
}

/// ‖free-dof force‖ / max(‖reactions‖, 5 % of the largest reactions so far), the force on
/// each degree of freedom a particle's force density times its volume. After a failure the
/// reactions fall towards zero and a residual relative to them can never become small; the
/// reference is therefore never below 5 % of the largest reactions so far, which this object
/// remembers between calls.
class RelativeResidual {
public:
  explicit RelativeResidual(const Model& model) : model_(model), constrained_(3 * model.size(), 0) {
    for (const Constraint& c : model.constraints) {
      constrained_[3 * c.particle + c.component] = 1;
    }
  }

  double operator()(const Simulation& sim) {
    double free = 0, reactions = 0;
    for (std::size_t d = 0; d < constrained_.size(); ++d) {
      const double f = sim.state().force[d] * model_.particles.volume[d / 3];
      (constrained_[d] ? reactions : free) += f * f;
    }
    largest_reactions_ = std::max(largest_reactions_, std::sqrt(reactions));
    const double reference = std::max(std::sqrt(reactions), 0.05 * largest_reactions_);
    return reference > 0 ? std::sqrt(free) / reference : std::sqrt(free);
  }

private:
  const Model& model_;
  std::vector<std::uint8_t> constrained_;
  double largest_reactions_ = 0;
};

/// The displacement of every degree of freedom from the model's reference positions.
std::vector<double> displacement_of(const Simulation& sim, const Model& model) {
  const std::size_t ndof = 3 * model.size();
  std::vector<double> u(ndof);
  for (std::size_t d = 0; d < ndof; ++d) {
    u[d] = sim.state().position[d] - model.particles.position[d / 3][d % 3];
  }
  return u;
}

/// Every constraint at `fraction` of its full prescribed value.
void set_constraint_level(Model& model, const std::vector<double>& full, double fraction) {
  for (std::size_t k = 0; k < full.size(); ++k) {
    model.constraints[k].value = fraction * full[k];
  }
}

/// Method::static_: one step of the static solver per level (it solves, breaks and re-solves
/// until no bond is beyond s0), the residual measured as the ADR path measures it.
Outcome run_static(Model& model, const SolverSpec& scene_solver, const InitialSpec& initial,
                   const Settings& settings, const IncrementObserver& after_increment) {
  using clock = std::chrono::steady_clock;
  const auto start = clock::now();
  Outcome out;
  const std::vector<double> full = take_prescribed_values(model);
  Simulation sim(model, increment_solver(scene_solver, IntegratorKind::static_solve), initial);
  const std::size_t ndof = 3 * model.size();
  const std::vector<std::uint8_t> held = held_dofs(model);
  double largest_reactions = 0;
  const int n = static_cast<int>(settings.levels.size());
  for (int inc = 1; inc <= n; ++inc) {
    const double fraction = settings.levels[static_cast<std::size_t>(inc - 1)];
    for (std::size_t k = 0; k < full.size(); ++k) {
      model.constraints[k].value = fraction * full[k];
    }
    const RunResult result = sim.run();
    if (result.status != RunStatus::converged) {
      out.stop_reason = result.message;
      break;
    }
    // ‖free-dof force‖ / max(‖reactions‖, 5 % of the largest so far), as run() below.
    double free = 0, reactions = 0;
    for (std::size_t d = 0; d < ndof; ++d) {
      const double f = sim.state().force[d] * model.particles.volume[d / 3];
      (held[d] ? reactions : free) += f * f;
    }
    largest_reactions = std::max(largest_reactions, std::sqrt(reactions));
    const double reference = std::max(std::sqrt(reactions), 0.05 * largest_reactions);
    const double r = reference > 0 ? std::sqrt(free) / reference : std::sqrt(free);
    const Json summary = sim.integrator().summary();
    const auto count = [&](const char* key) {
      const Json* v = summary.find(key);
      return v && v->number() ? static_cast<std::size_t>(*v->number()) : std::size_t{0};
    };
    IncrementInfo info{inc,
                       fraction,
                       count("newton_iterations"),
                       r,
                       r <= settings.residual_tolerance,
                       count("break_events")};
    out.iterations += info.iterations;
    out.increments.push_back(info);
    after_increment(sim, info);
    const double wall = std::chrono::duration<double>(clock::now() - start).count();
    if (settings.progress) {
      fmt::print(stderr, "  increment {:>3}/{}: {:>4} break events, residual {:.2e}, {:.0f} s\n",
                 inc, n, info.break_events, r, wall);
    }
    if (inc == n) {
      out.completed = true;
    } else if (settings.done && settings.done(sim)) {
      out.stop_reason = fmt::format("stopped by the case after increment {} of {}", inc, n);
      break;
    } else if (settings.wall_limit_seconds > 0 && wall > settings.wall_limit_seconds) {
      out.stop_reason = fmt::format("wall limit {:.0f} s reached after increment {} of {}",
                                    settings.wall_limit_seconds, inc, n);
      break;
    }
  }
  out.wall_seconds = std::chrono::duration<double>(clock::now() - start).count();
  return out;
}

/// While alive the force kernel breaks no bond (s0 is no_limit, uniform and per bond):
/// run_fracture decides which bonds break. The destructor puts the model's values back.
class HeldStrength {
public:
  explicit HeldStrength(Model& m)
      : m_(m), uniform_(m.field.critical_stretch), per_bond_(m.field.bond_critical_stretch) {
    m_.field.critical_stretch = no_limit;
    std::fill(m_.field.bond_critical_stretch.begin(), m_.field.bond_critical_stretch.end(),
              no_limit);
  }
  ~HeldStrength() {
    m_.field.critical_stretch = uniform_;
    std::copy(per_bond_.begin(), per_bond_.end(), m_.field.bond_critical_stretch.begin());
  }
  HeldStrength(const HeldStrength&) = delete;
  HeldStrength& operator=(const HeldStrength&) = delete;
  double s0(std::size_t k) const { return per_bond_.empty() ? uniform_ : per_bond_[k]; }

private:
  Model& m_;
  double uniform_;
  std::vector<double> per_bond_;
};

/// s/s0 of every directed bond at positions y, as the force kernel measures s (0 for a broken
/// bond), and the energy bond k stored, V_i · ½ c_k w(s), the kernel's strain_energy term.
template <class Stretch>
struct BondMeasure {
  static void ratios(const Model& m, const double* y, const HeldStrength& held,
                     std::vector<double>& ratio) {
    for (std::size_t i = 0; i < m.size(); ++i) {
      for (std::size_t k = m.family.offsets[i]; k < m.family.offsets[i + 1]; ++k) {
        ratio[k] = m.state.broken[k] ? 0.0 : stretch(m, y, i, k).stretch / held.s0(k);
      }
    }
  }
  static double energy(const Model& m, const double* y, std::size_t i, std::size_t k) {
    const double c = m.field.per_bond() ? m.field.bond_stiffness[k] : m.field.stiffness;
    return 0.5 * m.particles.volume[i] * c *
           Stretch::bond_energy(distance_squared(y, i, m.family.neighbour[k]),
                                m.family.inverse_length[k]);
  }
  static double distance_squared(const double* y, std::size_t i, std::size_t j) {
    double r2 = 0;
    for (int c = 0; c < 3; ++c) {
      const double d = y[3 * j + c] - y[3 * i + c];
      r2 += d * d;
    }
    return r2;
  }
  static StretchResult stretch(const Model& m, const double* y, std::size_t i, std::size_t k) {
    return Stretch::evaluate(distance_squared(y, i, m.family.neighbour[k]),
                             m.family.inverse_length[k]);
  }
};

template <class Visit>
auto with_measure(StretchKind kind, Visit&& visit) {
  switch (kind) {
  case StretchKind::modified:
    return visit(BondMeasure<ModifiedStretch>{});
  case StretchKind::fast:
    return visit(BondMeasure<FastStretch>{});
  case StretchKind::exact:
    break;
  }
  return visit(BondMeasure<ExactStretch>{});
}

/// Bonds whose s/s0 is within this fraction of the largest break together: the two tips of a
/// symmetric crack reach s0 together to the solve's accuracy (Newton stops at 1e-6 of the load),
/// and which of them broke first would otherwise be decided by round-off.
constexpr double break_group_tolerance = 1e-6;

} // namespace

FractureOutcome run_fracture(Simulation& sim, Model& model, const FractureSettings& settings,
                             const FractureObserver& observer) {
  FractureOutcome out;
  const std::vector<double> full = take_prescribed_values(model);
  const std::vector<double> full_load = model.external_force_density;
  const HeldStrength held(model);
  std::vector<double> ratio(model.family.neighbour.size(), 0.0);
  const auto set_level = [&](double fraction) {
    set_constraint_level(model, full, fraction);
    for (std::size_t d = 0; d < full_load.size(); ++d) {
      model.external_force_density[d] = fraction * full_load[d];
    }
  };
  // Equilibrium at `fraction`; false where there is none with the bonds left (the static solve
  // did not converge or its displacement blew up): after bonds broke, the specimen failed.
  const auto solve = [&](double fraction) {
    set_level(fraction);
    const RunResult r = sim.run();
    ++out.solves;
    const Json summary = sim.integrator().summary();
    const Json* solves = summary.find("solves");
    const Json* converged = summary.find("converged_solves");
    const bool ok = r.status == RunStatus::converged && solves && converged &&
                    solves->number() == converged->number();
    if (!ok && out.bonds_broken == 0) {
      throw std::runtime_error(fmt::format(
          "quasi-static fracture: the static solve at load factor {:.6g} failed before any bond "
          "broke: {}",
          fraction, r.message.empty() ? sim.integrator().report() : r.message));
    }
    if (!ok) {
      out.end = FractureOutcome::End::no_equilibrium;
      out.message = fmt::format(
          "no equilibrium at load factor {:.6g} after {} bonds broke: the specimen failed "
          "(largest load factor in equilibrium {:.6g}; the final state is the broken specimen "
          "unloaded)",
          fraction, out.bonds_broken, out.peak_load_factor);
      // The failed solve's state is meaningless (a loose piece under load has no finite
      // displacement); the broken specimen without load has one, and the run's files show it.
      set_level(0);
      sim.run();
      ++out.solves;
    }
    return ok;
  };
  const auto largest_ratio = [&]() {
    with_measure(model.effects.stretch, [&](auto m) {
      m.ratios(model, sim.state().position.data(), held, ratio);
      return 0;
    });
    return ratio.empty() ? 0.0 : *std::max_element(ratio.begin(), ratio.end());
  };
  const auto stop = [&](const char* why) {
    out.end = FractureOutcome::End::stopped;
    out.message = why;
  };
  for (std::size_t level = 1; level <= settings.levels.size(); ++level) {
    const double target = settings.levels[level - 1];
    for (;;) {
      if (settings.stop_requested && settings.stop_requested()) {
        stop("stopped by a request (signal)");
        return out;
      }
      if (!solve(target)) {
        return out;
      }
      const double r = largest_ratio();
      if (r <= 1) {
        break;
      }
      // The bonds' stretches are linear in the level while no bond breaks: the most overstretched
      // bond is at s0 at target / r. Solved there, not scaled, so that every probe (damage too)
      // and the stored energies are those of an equilibrium.
      const double critical = target / r;
      if (!solve(critical)) {
        return out;
      }
      const double rc = largest_ratio();
      out.peak_load_factor = std::max(out.peak_load_factor, critical);
      FracturePoint point{level, critical, true, out.bonds_broken, out.dissipated_energy, 0};
      std::vector<std::size_t> breaking;
      for (std::size_t k = 0; k < ratio.size(); ++k) {
        if (ratio[k] > 0 && ratio[k] >= rc * (1 - break_group_tolerance)) {
          breaking.push_back(k);
        }
      }
      if (breaking.empty()) { // rc ≤ 0: the level's stretch was not linear in it
        throw std::logic_error(fmt::format(
            "quasi-static fracture: no bond at s0 at the critical load factor {:.6g}", critical));
      }
      point.breaking = breaking.size();
      if (!observer(sim, point)) {
        stop("stopped by the observer");
        return out;
      }
      const double* y = sim.state().position.data();
      std::size_t row = 0;
      for (std::size_t k : breaking) {
        while (model.family.offsets[row + 1] <= k) {
          ++row;
        }
        out.dissipated_energy +=
            with_measure(model.effects.stretch, [&](auto m) { return m.energy(model, y, row, k); });
        model.state.broken[k] = 1;
      }
      // Directed bonds: each pair is counted once, as broken_bonds counts.
      out.bonds_broken = broken_bonds(model);
      ++out.break_events;
    }
    out.peak_load_factor = std::max(out.peak_load_factor, target);
    const FracturePoint point{level, target, false, out.bonds_broken, out.dissipated_energy, 0};
    if (!observer(sim, point)) {
      stop("stopped by the observer");
      return out;
    }
  }
  return out;
}

Outcome run(Model& model, const SolverSpec& scene_solver, const InitialSpec& initial,
            const Settings& settings, const IncrementObserver& after_increment) {
  if (settings.method == Method::static_) {
    return run_static(model, scene_solver, initial, settings, after_increment);
  }
  using clock = std::chrono::steady_clock;
  const auto start = clock::now();
  Outcome out;
  const std::vector<double> full = take_prescribed_values(model);
  Simulation sim(model, increment_solver(scene_solver, IntegratorKind::adr), initial);

  const std::size_t ndof = 3 * model.size();
  RelativeResidual residual(model);
  auto displacement = [&]() { return displacement_of(sim, model); };
  auto set_level = [&](double fraction) { set_constraint_level(model, full, fraction); };

  const int n = static_cast<int>(settings.levels.size());
  auto level = [&](int k) {
    return k > 0 ? settings.levels[static_cast<std::size_t>(k - 1)] : 0.0;
  };
  int inc = 1;
  std::size_t it = 0;
  std::vector<double> u_start = displacement(), u_previous_start = u_start;
  bool extrapolate = false;
  // ADR's iterations are a fictitious path to each increment's equilibrium: the predictor's
  // extrapolation and the overshoot after arms break stretch arms further than the equilibrium
  // does. Plastic flow along that path is not the material's, so the fibre kernel recomputes each
  // arm's plastic stretch from the increment's start at every evaluation (a return mapping over
  // the increment, as an implicit solver makes it). Measured on griffith's c/3250 crack: with
  // the plastic stretch accumulated along the path, σ_f rose 25 % from path spacing c/32 to c/64;
  // recomputed, 12 % (docs/theory/griffith.md).
  const bool plastic_from_increment_start =
      model.effects.bond_model == BondModel::virtual_fibres && model.effects.plasticity;
  auto begin_increment = [&]() {
    if (plastic_from_increment_start) {
      model.state.plastic_stretch_at_increment_start = model.state.plastic_stretch;
    }
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
    const double r = residual(sim);
    if (r > settings.residual_tolerance && it < settings.max_iterations) {
      return true;
    }
    IncrementInfo info{inc, level(inc), it, r, r <= settings.residual_tolerance};
    out.increments.push_back(info);
    after_increment(sim, info);
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
  model.state.plastic_stretch_at_increment_start.clear(); // later runs accumulate in place
  if (result.status == RunStatus::unstable) {
    out.stop_reason = result.message;
  }
  out.wall_seconds = std::chrono::duration<double>(clock::now() - start).count();
  return out;
}

} // namespace pd::quasi_static
