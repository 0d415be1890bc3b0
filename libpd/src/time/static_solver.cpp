// solver.integrator: static — the quasi-static answer of an elastic body as one sparse solve
// (issue 15), beside dynamic relaxation.
//
// The linearised bond operator (Miranda eq. 30; kernel/linear_operator.hpp) gives, for bond ij
// with k_ij = c_ij V_j/|ξ_ij| and n = ξ/|ξ|, the blocks K_ii += k n⊗n, K_ij = −k n⊗n, per unit
// volume, so that b(u) ≈ −K u. Equilibrium b(u) + b_ext = 0 becomes K u = b_ext on the free
// degrees of freedom, with the constraints substituted:
//   fixed or prescribed dof   its value moves to the right-hand side;
//   mirror dependant          u_d = σ u_m: its column folds onto the master's (copy coupling:
//                             K_ff + K_fd R), and under consistent coupling its row folds too,
//                             weighted σ V_d / V_m, as fold_mirror_forces does (Rᵀ K R).
// K is assembled once and factored (time/sparse_factorisation.hpp: CHOLMOD's supernodal
// Cholesky when it is symmetric, an LU factorisation otherwise). Then modified Newton on the
// real force kernel: u ← u + K⁻¹ r(u), r = b(y) + b_ext on the free dofs, until
// ‖r‖ ≤ tolerance ‖b_ext‖: for finite stretch this converges to the nonlinear equilibrium that
// dynamic relaxation finds, and a wrong assembly cannot pass (its iteration would not converge).
// The solve is at the full load: a ramp has no meaning here.
#include "libpd/time/static_solver.hpp"

#include "libpd/core/binary_state.hpp"
#include "libpd/kernel/force_kernel.hpp"
#include "libpd/kernel/linear_operator.hpp"
#include "libpd/time/integrator.hpp"
#include "sparse_factorisation.hpp"

#include <Eigen/SparseCore>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <fmt/format.h>
#include <limits>
#include <stdexcept>
#include <vector>

namespace pd {

namespace {

/// Where a global dof's displacement comes from.
struct DofMap {
  static constexpr std::ptrdiff_t none = -1;
  std::vector<std::ptrdiff_t> free_index; ///< free unknown, or none
  std::vector<std::ptrdiff_t> master;     ///< for mirror dependants: the master's global dof
  std::vector<double> sign;               ///< σ of a mirror dependant
  std::vector<double> prescribed;         ///< value of a fixed/prescribed dof (full load)
  std::vector<std::uint8_t> kind;         ///< 0 free, 1 prescribed, 2 mirror dependant
  std::vector<std::size_t> free_dofs;     ///< global dof of each unknown
};

DofMap map_dofs(const Model& m) {
  const std::size_t ndof = 3 * m.size();
  DofMap d;
  d.free_index.assign(ndof, DofMap::none);
  d.master.assign(ndof, DofMap::none);
  d.sign.assign(ndof, 0.0);
  d.prescribed.assign(ndof, 0.0);
  d.kind.assign(ndof, 0);
  const int dim = m.spec.dimension.dim;
  for (std::size_t g = 0; g < ndof; ++g) {
    if (static_cast<int>(g % 3) >= dim) {
      d.kind[g] = 1; // out-of-plane components stay zero
    }
  }
  for (const Constraint& c : m.constraints) {
    const std::size_t g = 3 * c.particle + c.component;
    if (c.mirror_of != Constraint::no_mirror) {
      d.kind[g] = 2;
      d.master[g] = static_cast<std::ptrdiff_t>(3 * c.mirror_of + c.component);
      d.sign[g] = c.mirror_sign;
    } else {
      d.kind[g] = 1;
      d.prescribed[g] = c.value;
    }
  }
  for (std::size_t g = 0; g < ndof; ++g) {
    if (d.kind[g] == 0) {
      d.free_index[g] = static_cast<std::ptrdiff_t>(d.free_dofs.size());
      d.free_dofs.push_back(g);
    }
  }
  return d;
}

/// The equations that make up each unknown's row (Rᵀ, in force units): its own dof's equation
/// times V_i and, under consistent mirror coupling, that of every mirror dependant whose master
/// it is, times σ V_d (fold_mirror_forces' weight σ V_d / V_m, times V_m). Other dofs' equations
/// are reactions, not equations.
struct RowSources {
  std::vector<std::size_t> offsets; ///< n + 1
  std::vector<std::size_t> dof;     ///< global dof of each equation folded in
  std::vector<double> weight;
};

RowSources row_sources(const Model& m, const DofMap& d) {
  const std::size_t n = d.free_dofs.size();
  const bool fold = consistent_mirror_coupling(m);
  RowSources r;
  r.offsets.assign(n + 1, 0);
  for (std::size_t k = 0; k < n; ++k) {
    r.offsets[k + 1] = 1;
  }
  for (std::size_t g = 0; g < d.kind.size() && fold; ++g) {
    if (d.kind[g] == 2) {
      ++r.offsets[static_cast<std::size_t>(d.free_index[static_cast<std::size_t>(d.master[g])]) +
                  1];
    }
  }
  for (std::size_t k = 0; k < n; ++k) {
    r.offsets[k + 1] += r.offsets[k];
  }
  r.dof.resize(r.offsets[n]);
  r.weight.resize(r.offsets[n]);
  std::vector<std::size_t> next(r.offsets.begin(), r.offsets.end() - 1);
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t g = d.free_dofs[k];
    r.dof[next[k]] = g;
    r.weight[next[k]++] = m.particles.volume[g / 3];
  }
  for (std::size_t g = 0; g < d.kind.size() && fold; ++g) {
    if (d.kind[g] == 2) {
      const auto k = static_cast<std::size_t>(d.free_index[static_cast<std::size_t>(d.master[g])]);
      r.dof[next[k]] = g;
      r.weight[next[k]++] = d.sign[g] * m.particles.volume[g / 3];
    }
  }
  return r;
}

/// One row of K being summed: a dense scatter over the unknowns, the columns touched listed.
class RowAccumulator {
public:
  explicit RowAccumulator(std::size_t n) : value_(n, 0.0), touched_(n, 0) {}

  /// Coefficient `value` on global dof g (R): an unknown's column, its master's (times σ) for a
  /// mirror dependant, or for a prescribed dof its known value moved to the right-hand side.
  void add(const DofMap& d, std::size_t g, double value, double& rhs) {
    if (d.kind[g] == 0) {
      add_column(static_cast<std::size_t>(d.free_index[g]), value);
    } else if (d.kind[g] == 2) {
      const auto master = static_cast<std::size_t>(d.master[g]);
      add_column(static_cast<std::size_t>(d.free_index[master]), d.sign[g] * value);
    } else {
      rhs -= value * d.prescribed[g];
    }
  }

  /// Append the row (columns ascending) to the system and start the next one.
  void close(StaticSystem& s) {
    std::sort(columns_.begin(), columns_.end());
    for (const std::size_t c : columns_) {
      s.columns.push_back(static_cast<int>(c));
      s.values.push_back(value_[c]);
      value_[c] = 0.0;
      touched_[c] = 0;
    }
    columns_.clear();
    s.row_offsets.push_back(static_cast<int>(s.columns.size()));
  }

private:
  void add_column(std::size_t c, double value) {
    if (!touched_[c]) {
      touched_[c] = 1;
      columns_.push_back(c);
    }
    value_[c] += value;
  }

  std::vector<double> value_;
  std::vector<std::uint8_t> touched_;
  std::vector<std::size_t> columns_;
};

/// K and f in compressed rows, straight from the bond family: row by row, each row's equations
/// (row_sources) summed over their particles' bonds, k_ij n⊗n on i's columns and −k_ij n⊗n on j's.
StaticSystem assemble(const Model& m, const DofMap& d) {
  const std::size_t n = d.free_dofs.size();
  const RowSources sources = row_sources(m, d);
  StaticSystem s;
  s.unknowns = d.free_dofs;
  s.rhs.assign(n, 0.0);
  // At most 3 (bonds + 1) entries per equation folded in: reserved once, checked against int.
  std::size_t bound = 0;
  for (const std::size_t g : sources.dof) {
    bound += 3 * (m.family.offsets[g / 3 + 1] - m.family.offsets[g / 3] + 1);
  }
  if (bound > static_cast<std::size_t>(std::numeric_limits<int>::max())) {
    throw std::runtime_error(fmt::format(
        "static solve: the stiffness matrix may hold up to {} entries, beyond the 32-bit indices "
        "of the sparse solvers; use a dynamic integrator (adr) for this model",
        bound));
  }
  s.columns.reserve(bound);
  s.values.reserve(bound);
  s.row_offsets.reserve(n + 1);
  s.row_offsets.push_back(0);
  const std::vector<double>& ext = m.external_force_density;
  RowAccumulator row(n);
  for (std::size_t r = 0; r < n; ++r) {
    for (std::size_t q = sources.offsets[r]; q < sources.offsets[r + 1]; ++q) {
      const std::size_t g = sources.dof[q], i = g / 3, a = g % 3;
      const double w = sources.weight[q];
      for_each_linearised_bond(m, i, BrokenBonds::left_out, [&](const LinearisedBond& b) {
        for (std::size_t c = 0; c < 3; ++c) {
          const double k = w * b.stiffness * b.direction[a] * b.direction[c];
          row.add(d, 3 * i + c, k, s.rhs[r]);
          row.add(d, 3 * b.neighbour + c, -k, s.rhs[r]);
        }
      });
      if (!ext.empty()) {
        s.rhs[r] += w * ext[g];
      }
    }
    row.close(s);
  }
  s.columns.shrink_to_fit();
  s.values.shrink_to_fit();
  return s;
}

/// K as the factorisations take it, compressed by columns; the rows are freed. A symmetric K's
/// rows are its columns (Kᵀ = K to round-off); otherwise the rows are transposed into columns.
Eigen::SparseMatrix<double> column_major(StaticSystem system, bool symmetric) {
  const auto n = static_cast<Eigen::Index>(system.size());
  const auto nnz = static_cast<Eigen::Index>(system.values.size());
  if (symmetric) {
    return Eigen::Map<const Eigen::SparseMatrix<double, Eigen::ColMajor, int>>(
        n, n, nnz, system.row_offsets.data(), system.columns.data(), system.values.data());
  }
  return Eigen::Map<const Eigen::SparseMatrix<double, Eigen::RowMajor, int>>(
      n, n, nnz, system.row_offsets.data(), system.columns.data(), system.values.data());
}

class StaticSolver final : public Integrator {
public:
  StaticSolver(Model& model, ForceEvaluator& forces) : model_(model), forces_(forces) {
    if (model.effects.damage || model.effects.plasticity) {
      throw std::invalid_argument(
          "solver.integrator: static solves elastic bodies only (no damage or plasticity yet): "
          "use adr or damped-euler for this scene");
    }
  }

  StepReport step(State& st, double dt) override {
    ++calls_;
    if (!solved_) {
      solve(st);
      solved_ = true;
    }
    st.time += dt;
    ++st.step;
    return displacement_report(model_, st.position.data());
  }

  bool finished() const override { return solved_; }
  std::string name() const override { return "static"; }
  std::string checkpoint_refusal() const override {
    return "a static solve is one step: there is nothing to continue (rerun it instead)";
  }
  std::string report() const override { return report_; }
  Json summary() const override { return details_; }

private:
  void solve(State& st) {
    using clock = std::chrono::steady_clock;
    const auto t0 = clock::now();
    const DofMap d = map_dofs(model_);
    const auto n = static_cast<Eigen::Index>(d.free_dofs.size());
    const std::vector<double>& ext = model_.external_force_density;
    StaticSystem system = assemble(model_, d);
    const auto t1 = clock::now();
    const double asym = system.asymmetry();
    const auto t_check = clock::now();
    const bool symmetric = asym <= 1e-12;
    const std::size_t nonzeros = system.values.size();
    const Eigen::VectorXd rhs = Eigen::Map<const Eigen::VectorXd>(system.rhs.data(), n);
    const Eigen::SparseMatrix<double> K = column_major(std::move(system), symmetric);
    const std::unique_ptr<SparseFactorisation> factor = factorise(K, symmetric);
    const auto t2 = clock::now();
    auto solve_with = [&](const Eigen::VectorXd& b) { return factor->solve(b); };

    // Linear solution, then modified Newton on the force kernel's residual.
    const LoadRamp full;
    double* y = st.position.data();
    Eigen::VectorXd u = solve_with(rhs);
    auto place = [&](const Eigen::VectorXd& du) {
      for (Eigen::Index k = 0; k < n; ++k) {
        y[d.free_dofs[static_cast<std::size_t>(k)]] += du[k];
      }
      apply_constraints(model_, full, 0.0, y, nullptr);
    };
    place(u);
    const double load = rhs.norm();
    std::size_t iterations = 0;
    double residual = 0;
    double previous = std::numeric_limits<double>::infinity();
    for (;; ++iterations) {
      forces_.compute(y, st.force.data());
      ++force_evaluations_;
      Eigen::VectorXd r(n);
      for (Eigen::Index k = 0; k < n; ++k) {
        const std::size_t g = d.free_dofs[static_cast<std::size_t>(k)];
        r[k] = model_.particles.volume[g / 3] * (st.force[g] + (ext.empty() ? 0.0 : ext[g]));
      }
      residual = r.norm() / std::max(load, 1e-300);
      // Converged, or at the round-off floor of the force sums (the residual stops falling; a
      // body force on a coarse 2D body floors near 1e-5 of the load, see issue 14).
      const bool floor = residual <= acceptable_residual && residual > 0.5 * previous;
      if (residual <= newton_tolerance || floor || iterations >= max_newton_iterations) {
        break;
      }
      previous = residual;
      place(solve_with(r));
    }
    std::fill(st.velocity.begin(), st.velocity.end(), 0.0);
    const auto t3 = clock::now();
    const auto s = [](auto a, auto b) { return std::chrono::duration<double>(b - a).count(); };
    Json& j = details_;
    j = Json::object();
    j["solver"] = factor->name();
    j["symmetric"] = symmetric;
    j["asymmetry"] = asym;
    j["unknowns"] = static_cast<std::size_t>(n);
    j["nonzeros"] = nonzeros;
    j["factor_nonzeros"] = factor->factor_nonzeros();
    j["factor_bytes"] = factor->factor_bytes();
    j["assembly_seconds"] = s(t0, t1);
    j["symmetry_check_seconds"] = s(t1, t_check);
    j["factorisation_seconds"] = s(t_check, t2);
    j["newton_seconds"] = s(t2, t3);
    j["newton_iterations"] = iterations;
    j["residual"] = residual;
    report_ = fmt::format(
        "static solve: {} unknowns, {} nonzeros, {} ({} operator, ‖K−Kᵀ‖/‖K‖ = {:.1e}); "
        "assembly {:.3f} s, symmetry check {:.3f} s, factorisation {:.3f} s (factor {} nonzeros, "
        "{:.1f} MiB), {} Newton iterations {:.3f} s, residual {:.2e} of the load",
        n, nonzeros, factor->name(), symmetric ? "symmetric" : "nonsymmetric", asym, s(t0, t1),
        s(t1, t_check), s(t_check, t2), factor->factor_nonzeros(),
        static_cast<double>(factor->factor_bytes()) / (1024.0 * 1024.0), iterations, s(t2, t3),
        residual);
    if (residual > acceptable_residual) {
      throw std::runtime_error(fmt::format("static solve did not converge: {}", report_));
    }
  }

  static constexpr double newton_tolerance = 1e-10;
  /// A residual that stopped falling is accepted below this (relative to the load).
  static constexpr double acceptable_residual = 1e-6;
  static constexpr std::size_t max_newton_iterations = 50;

  Model& model_;
  ForceEvaluator& forces_;
  bool solved_ = false;
  std::string report_;
  Json details_;
};

} // namespace

void StaticSystem::multiply(const double* x, double* y) const {
  for (std::size_t r = 0; r < size(); ++r) {
    double sum = 0;
    for (auto q = static_cast<std::size_t>(row_offsets[r]);
         q < static_cast<std::size_t>(row_offsets[r + 1]); ++q) {
      sum += values[q] * x[columns[q]];
    }
    y[r] = sum;
  }
}

double StaticSystem::asymmetry() const {
  // Each entry against its mirror image, found by bisection in the sorted row of its column.
  double diff = 0, norm = 0;
  for (std::size_t r = 0; r < size(); ++r) {
    for (auto q = static_cast<std::size_t>(row_offsets[r]);
         q < static_cast<std::size_t>(row_offsets[r + 1]); ++q) {
      const auto c = static_cast<std::size_t>(columns[q]);
      const auto first = columns.begin() + row_offsets[c],
                 last = columns.begin() + row_offsets[c + 1];
      const auto at = std::lower_bound(first, last, static_cast<int>(r));
      const bool stored = at != last && *at == static_cast<int>(r);
      const double mirror = stored ? values[static_cast<std::size_t>(at - columns.begin())] : 0.0;
      // A pair stored both ways is met twice; an entry whose image is a zero only once.
      diff += (stored ? 1.0 : 2.0) * (values[q] - mirror) * (values[q] - mirror);
      norm += values[q] * values[q];
    }
  }
  return std::sqrt(diff / std::max(norm, 1e-300));
}

StaticSystem assemble_static_system(const Model& model) {
  return assemble(model, map_dofs(model));
}

std::unique_ptr<Integrator> make_static_solver(const IntegratorSettings&, Model& model,
                                               ForceEvaluator& forces) {
  return std::make_unique<StaticSolver>(model, forces);
}

} // namespace pd
