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
// Cholesky when it is symmetric, an LU factorisation otherwise). Then Newton on the real force
// kernel, r = b(y) + b_ext on the free dofs, until ‖r‖ ≤ tolerance ‖b_ext‖: each step solves
// J δ = r by conjugate gradients preconditioned with the factor, J the kernel's own tangent by
// finite differences (modified Newton, δ = K⁻¹ r, when K is not symmetric). For finite stretch
// this converges to the nonlinear equilibrium that dynamic relaxation finds, and a wrong assembly
// cannot pass (a preconditioner that is not the kernel's linearisation shows as a residual that
// does not fall after the linear solve).
// The solve is at the full load: a ramp has no meaning here.
#include "libpd/time/static_solver.hpp"

#include "libpd/core/binary_state.hpp"
#include "libpd/kernel/force_kernel.hpp"
#include "libpd/kernel/linear_operator.hpp"
#include "libpd/kernel/round_off.hpp"
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
  /// One term u_g += coefficient · u_dof of a dependent dof (its sources are free or prescribed).
  struct Term {
    std::size_t dof;
    double coefficient;
  };
  std::vector<std::ptrdiff_t> free_index; ///< free unknown, or none
  std::vector<std::vector<Term>> terms;   ///< a dependant's sources (mirror image, extrapolation)
  std::vector<double> prescribed;         ///< value of a fixed/prescribed dof (full load)
  std::vector<std::uint8_t> kind;         ///< 0 free, 1 prescribed, 2 dependant
  std::vector<std::uint8_t> folds_row;    ///< a dependant whose equation folds onto its sources
  std::vector<std::size_t> free_dofs;     ///< global dof of each unknown
};

DofMap map_dofs(const Model& m) {
  const std::size_t ndof = 3 * m.size();
  DofMap d;
  d.free_index.assign(ndof, DofMap::none);
  d.terms.assign(ndof, {});
  d.prescribed.assign(ndof, 0.0);
  d.kind.assign(ndof, 0);
  d.folds_row.assign(ndof, 0);
  const int dim = m.spec.dimension.dim;
  for (std::size_t g = 0; g < ndof; ++g) {
    if (static_cast<int>(g % 3) >= dim) {
      d.kind[g] = 1; // out-of-plane components stay zero
    }
  }
  const bool consistent = consistent_mirror_coupling(m);
  for (const Constraint& c : m.constraints) {
    const std::size_t g = 3 * c.particle + c.component;
    if (c.mirror_of != Constraint::no_mirror) {
      d.kind[g] = 2;
      d.terms[g] = {{3 * c.mirror_of + c.component, c.mirror_sign}};
      d.folds_row[g] = consistent ? 1 : 0;
    } else {
      d.kind[g] = 1;
      d.prescribed[g] = c.value;
    }
  }
  const ExtrapolatedParticles& e = m.extrapolated;
  for (std::size_t k = 0; k < e.size(); ++k) {
    for (std::size_t a = 0; a < static_cast<std::size_t>(dim); ++a) {
      const std::size_t g = 3 * e.particle[k] + a;
      d.kind[g] = 2;
      d.folds_row[g] = 1;
      for (std::size_t t = e.offsets[k]; t < e.offsets[k + 1]; ++t) {
        d.terms[g].push_back({3 * e.source[t] + a, e.sign(k, a) * e.coefficient[t]});
      }
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

/// The system in force units (each equation of particle i times V_i). With u = A u_f + u_p (A maps
/// the unknowns to every dof: free dofs themselves, dependants through their terms; u_p holds the
/// prescribed values and what dependants take from prescribed sources) and B the map of equations
/// (a free row times its particle's volume; a dependant whose forces fold sends its row, times
/// its own volume, to its sources with its coefficients, as fold_mirror_forces does), it is
/// Bᵀ K A u_f = Bᵀ (b_ext − K u_p): Aᵀ (V K) A, symmetric, when every dependant folds; V (K_ff +
/// K_fd A) under `copy` mirrors. Sparse products, not per-bond folding: an extrapolated particle
/// has ~20 sources, and a bond between two of them would otherwise add 20² entries.
StaticSystem assemble(const Model& m, const DofMap& d) {
  using Sparse = Eigen::SparseMatrix<double>;
  const auto ndof = static_cast<Eigen::Index>(3 * m.size());
  const auto n = static_cast<Eigen::Index>(d.free_dofs.size());
  const auto& volume = m.particles.volume;

  // K per unit volume over every dof.
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(18 * m.family.directed_bond_count());
  for (std::size_t i = 0; i < m.size(); ++i) {
    for_each_linearised_bond(m, i, BrokenBonds::left_out, [&](const LinearisedBond& b) {
      if (b.stiffness == 0.0) {
        return; // bonds between two dependants carry no energy (ghost_layers.hpp)
      }
      for (std::size_t a = 0; a < 3; ++a) {
        for (std::size_t c = 0; c < 3; ++c) {
          const double k = b.stiffness * b.direction[a] * b.direction[c];
          const auto row = static_cast<Eigen::Index>(3 * i + a);
          triplets.emplace_back(row, static_cast<Eigen::Index>(3 * i + c), k);
          triplets.emplace_back(row, static_cast<Eigen::Index>(3 * b.neighbour + c), -k);
        }
      }
    });
  }
  Sparse K(ndof, ndof);
  K.setFromTriplets(triplets.begin(), triplets.end());
  triplets.clear();
  triplets.shrink_to_fit();

  // A (columns) and B (equations, in force units: V_g for a free row, a·V_d for a folded one).
  std::vector<Eigen::Triplet<double>> a_entries;
  std::vector<Eigen::Triplet<double>> b_entries;
  Eigen::VectorXd known = Eigen::VectorXd::Zero(ndof);
  for (std::size_t g = 0; g < d.kind.size(); ++g) {
    const auto row = static_cast<Eigen::Index>(g);
    if (d.kind[g] == 0) {
      a_entries.emplace_back(row, d.free_index[g], 1.0);
      b_entries.emplace_back(row, d.free_index[g], volume[g / 3]);
    } else if (d.kind[g] == 1) {
      known[row] = d.prescribed[g];
    } else {
      for (const DofMap::Term& t : d.terms[g]) {
        if (d.kind[t.dof] == 0) {
          a_entries.emplace_back(row, d.free_index[t.dof], t.coefficient);
          if (d.folds_row[g]) {
            b_entries.emplace_back(row, d.free_index[t.dof], t.coefficient * volume[g / 3]);
          }
        } else {
          known[row] += t.coefficient * d.prescribed[t.dof];
        }
      }
    }
  }
  Sparse A(ndof, n);
  A.setFromTriplets(a_entries.begin(), a_entries.end());
  Sparse B(ndof, n);
  B.setFromTriplets(b_entries.begin(), b_entries.end());

  Eigen::VectorXd load = Eigen::VectorXd::Zero(ndof);
  const std::vector<double>& ext = m.external_force_density;
  for (std::size_t g = 0; g < ext.size(); ++g) {
    load[static_cast<Eigen::Index>(g)] = ext[g];
  }
  const Eigen::VectorXd rhs = B.transpose() * (load - K * known);
  Eigen::SparseMatrix<double, Eigen::RowMajor> reduced = B.transpose() * (K * A);
  reduced.prune(0.0);
  reduced.makeCompressed();
  StaticSystem system;
  system.unknowns = d.free_dofs;
  system.row_offsets.assign(reduced.outerIndexPtr(), reduced.outerIndexPtr() + n + 1);
  system.columns.assign(reduced.innerIndexPtr(), reduced.innerIndexPtr() + reduced.nonZeros());
  system.values.assign(reduced.valuePtr(), reduced.valuePtr() + reduced.nonZeros());
  system.rhs.assign(rhs.data(), rhs.data() + n);
  return system;
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

    // Linear solution, then Newton on the force kernel's residual.
    const LoadRamp full;
    double* y = st.position.data();
    auto place = [&](const Eigen::VectorXd& du) {
      for (Eigen::Index k = 0; k < n; ++k) {
        y[d.free_dofs[static_cast<std::size_t>(k)]] += du[k];
      }
      apply_constraints(model_, full, 0.0, y, nullptr);
    };
    // r = V (b(y) + b_ext) on the unknowns: the force the current state leaves unbalanced.
    auto residual_at = [&](const double* at) {
      forces_.compute(at, st.force.data());
      ++force_evaluations_;
      Eigen::VectorXd r(n);
      for (Eigen::Index k = 0; k < n; ++k) {
        const std::size_t g = d.free_dofs[static_cast<std::size_t>(k)];
        r[k] = model_.particles.volume[g / 3] * (st.force[g] + (ext.empty() ? 0.0 : ext[g]));
      }
      return r;
    };
    place(factor->solve(rhs));
    const double load = std::max(rhs.norm(), 1e-300);
    std::vector<std::uint8_t> held(d.kind.size());
    std::transform(d.kind.begin(), d.kind.end(), held.begin(),
                   [](std::uint8_t kind) { return static_cast<std::uint8_t>(kind != 0); });
    const double floor = residual_round_off_floor(model_, y, held) / load;
    // A residual that stopped falling is accepted up to this: 1e-6 of the load, or just above
    // the round-off floor where that is higher (a light load on a stiff, fine or far-off body).
    const double acceptable = std::max(acceptable_residual, round_off_margin * floor);
    std::size_t iterations = 0;
    double residual = 0;
    double previous = std::numeric_limits<double>::infinity();
    for (;; ++iterations) {
      const Eigen::VectorXd r = residual_at(y);
      residual = r.norm() / load;
      // Converged, or at the round-off floor (the residual stops falling).
      const bool stalled = residual <= acceptable && residual > 0.5 * previous;
      if (residual <= newton_tolerance || stalled || iterations >= max_newton_iterations) {
        break;
      }
      previous = residual;
      place(symmetric ? newton_step(r, y, d, *factor, residual_at) : factor->solve(r));
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
    j["round_off_floor"] = floor;
    report_ = fmt::format(
        "static solve: {} unknowns, {} nonzeros, {} ({} operator, ‖K−Kᵀ‖/‖K‖ = {:.1e}); "
        "assembly {:.3f} s, symmetry check {:.3f} s, factorisation {:.3f} s (factor {} nonzeros, "
        "{:.1f} MiB), {} Newton iterations {:.3f} s, residual {:.2e} of the load (round-off floor "
        "{:.1e})",
        n, nonzeros, factor->name(), symmetric ? "symmetric" : "nonsymmetric", asym, s(t0, t1),
        s(t1, t_check), s(t_check, t2), factor->factor_nonzeros(),
        static_cast<double>(factor->factor_bytes()) / (1024.0 * 1024.0), iterations, s(t2, t3),
        residual, floor);
    if (residual > acceptable) {
      throw std::runtime_error(fmt::format("static solve did not converge: {}", report_));
    }
  }

  /// The Newton step J δ = r, J the tangent of the force kernel at y (finite differences of the
  /// kernel: exact for every stretch measure and every coupling the integrators use), solved by
  /// conjugate gradients preconditioned with the factored K of the reference state. Modified
  /// Newton (δ = K⁻¹ r) is this with one CG iteration; it stalls when the tangent has moved away
  /// from K, as in a slender cantilever under the exact stretch: the rotation's second-order
  /// stretch θ²/2 gave a residual 300× the load after the linear solve, and modified Newton still
  /// 35× after 8 iterations (2 m × 0.1 m × 0.1 m, λ = 0.02 m). CG needs K⁻¹J only to have few
  /// distinct eigenvalues, which holds when J differs from K by a few modes.
  template <typename Residual>
  Eigen::VectorXd newton_step(const Eigen::VectorXd& r, const double* y, const DofMap& d,
                              const SparseFactorisation& factor, const Residual& residual_at) {
    const auto n = r.size();
    std::vector<double> yp(y, y + 3 * model_.size()), ym = yp;
    const LoadRamp full;
    // J v = −(r(y + h v) − r(y − h v)) / 2h, h so that the largest move is 1e-5 λ: central
    // differences are then exact to ~1e-10 and the positions' round-off stays below 1e-9.
    auto tangent = [&](const Eigen::VectorXd& v) {
      const double h =
          1e-5 * model_.spec.lattice.spacing / std::max(v.lpNorm<Eigen::Infinity>(), 1e-300);
      for (Eigen::Index k = 0; k < n; ++k) {
        const std::size_t g = d.free_dofs[static_cast<std::size_t>(k)];
        yp[g] = y[g] + h * v[k];
        ym[g] = y[g] - h * v[k];
      }
      apply_constraints(model_, full, 0.0, yp.data(), nullptr);
      apply_constraints(model_, full, 0.0, ym.data(), nullptr);
      const Eigen::VectorXd rp = residual_at(yp.data());
      return Eigen::VectorXd(-(rp - residual_at(ym.data())) / (2 * h));
    };
    // CG to a relative residual of 1e-3 (Newton stays quadratic down to that factor per step).
    Eigen::VectorXd x = Eigen::VectorXd::Zero(n), res = r, z = factor.solve(res), p = z;
    double rz = res.dot(z);
    const double stop = 1e-3 * r.norm();
    for (std::size_t it = 0; it < max_cg_iterations && res.norm() > stop; ++it) {
      const Eigen::VectorXd q = tangent(p);
      const double pq = p.dot(q);
      if (!(pq > 0)) {
        break; // not positive along p: keep what CG has (at least the modified Newton step)
      }
      const double alpha = rz / pq;
      x += alpha * p;
      res -= alpha * q;
      z = factor.solve(res);
      const double rz_next = res.dot(z);
      p = z + (rz_next / rz) * p;
      rz = rz_next;
    }
    return x.isZero() ? factor.solve(r) : x;
  }

  static constexpr std::size_t max_cg_iterations = 50;
  static constexpr double newton_tolerance = 1e-10;
  /// A residual that stopped falling is accepted below this (relative to the load), or below
  /// round_off_margin × the round-off floor where that is higher (kernel/round_off.hpp).
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
  // ‖K − Kᵀ‖_F / ‖K‖_F with Eigen's transpose of the row-major view (a sorted merge, no search).
  const auto n = static_cast<Eigen::Index>(size());
  const Eigen::Map<const Eigen::SparseMatrix<double, Eigen::RowMajor, int>> k(
      n, n, static_cast<Eigen::Index>(values.size()), row_offsets.data(), columns.data(),
      values.data());
  const Eigen::SparseMatrix<double, Eigen::RowMajor, int> kt = k.transpose();
  const double norm = k.norm();
  return norm > 0 ? (k - kt).norm() / norm : 0.0;
}

StaticSystem assemble_static_system(const Model& model) {
  return assemble(model, map_dofs(model));
}

std::unique_ptr<Integrator> make_static_solver(const IntegratorSettings&, Model& model,
                                               ForceEvaluator& forces) {
  return std::make_unique<StaticSolver>(model, forces);
}

} // namespace pd
