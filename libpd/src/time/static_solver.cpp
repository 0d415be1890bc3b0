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
// K is assembled once, in particle blocks (time/static_assembly.hpp), and factored
// (time/sparse_factorisation.hpp: CHOLMOD's supernodal Cholesky when it is symmetric, an LU
// factorisation otherwise). With ghosts (or quadratic clamps) and at least
// preconditioned_from_unknowns unknowns, the factor is instead that of P, the operator with each
// ghost refitted from a smaller cloud (factor_system), and the linear solution is conjugate
// gradients on K applied matrix-free, preconditioned by P (the plate: a 33 M-entry factor
// instead of 93 M). Then Newton on the real force kernel, r = b(y) + b_ext on the free
// dofs, until ‖r‖ ≤ tolerance ‖b_ext‖ (or the residual's round-off floor): each step solves
// J δ = r by conjugate gradients preconditioned with the factor, J the kernel's own tangent by
// finite differences (modified Newton, δ = K⁻¹ r, when K is not symmetric). For finite stretch
// this converges to the nonlinear equilibrium that dynamic relaxation finds, and a wrong assembly
// cannot pass (a preconditioner that is not the kernel's linearisation shows as a residual that
// does not fall after the linear solve).
// The solve is at the full load: a ramp has no meaning here.
//
// Damage (issue 15, event-driven): each step solves equilibrium at the constraints' current values
// on the unbroken bonds (a displacement-controlled driver, time/quasi_static.hpp, moves the
// prescribed values between steps). Then the break event: one
// evaluation of the force kernel at that equilibrium applies the kernel's own rule (eq. 10: every
// bond with s ≥ s0 breaks), and while it broke any bond K is reassembled without them, refactored
// and equilibrium is solved again at the same load. All bonds beyond s0 break in one event, not
// the most overstretched one alone. The sequentially linear analysis of Ni et al. (2018), which
// Bhattacharya, Lipton & Diehl (Int. J. Fract. 2023, doi:10.1007/s10704-023-00711-0) call the
// state of the art for implicit brittle PD, removes one bond (the highest stretch beyond s0) per
// re-solve; that needs a factorisation per bond (the beam breaks 5,400 in its first increment).
// Breaking all at once is the cheaper approximation, and it can overshoot: a bond broken in the
// same event as the one that overloaded it might have unloaded had they broken in turn
// (docs/theory/quasi-brittle.md measures what this does on rc-beam). A scene's quasi-static
// fracture (quasi_static::run_fracture) breaks them in turn instead: it holds the kernel's s0
// itself, so each step here is one solve, and it chooses the bond and the load of each break.
// During Newton the kernel must neither break bonds nor drop the force of a bond beyond s0 (an
// iterate is not an equilibrium): s0 is lifted to no_limit while Newton runs (BreakingSuspended),
// so the residual is the elastic one of the unbroken bonds. Restoring only the broken flags after
// each evaluation is not enough: a bond beyond s0 still carries no force in that evaluation, and
// Newton converged to states whose overstretched bonds carried nothing — measured on rc-beam,
// one event then broke all 134,557 concrete bonds at 0.25 mm, where ADR breaks 5,300.
#include "libpd/time/static_solver.hpp"

#include "libpd/core/binary_state.hpp"
#include "libpd/core/blas.hpp"
#include "libpd/kernel/force_kernel.hpp"
#include "libpd/kernel/linear_operator.hpp"
#include "libpd/kernel/round_off.hpp"
#include "libpd/time/integrator.hpp"
#include "libpd/time/simulation.hpp"
#include "sparse_factorisation.hpp"
#include "static_assembly.hpp"

#include <Eigen/Dense>
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

/// K as the factorisations take it, compressed by columns; the rows are freed. A symmetric K is
/// assembled as its upper triangle by rows, which is its lower triangle by columns (Kᵀ = K to
/// round-off), the triangle the Cholesky factorisation reads; otherwise the rows are transposed
/// into columns.
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

/// Conjugate gradients on `apply` (symmetric positive definite on the iterates' span),
/// preconditioned by `precondition`, from zero until ‖b − A x‖ ≤ relative_tolerance ‖b‖. Stops
/// early, keeping what it has, where A is not positive along a direction.
struct CgResult {
  Eigen::VectorXd x;
  std::size_t iterations = 0;
  bool converged = false;
};
template <typename Apply, typename Precondition>
CgResult preconditioned_cg(const Apply& apply, const Precondition& precondition,
                           const Eigen::VectorXd& b, double relative_tolerance,
                           std::size_t max_iterations) {
  CgResult out{Eigen::VectorXd::Zero(b.size()), 0};
  Eigen::VectorXd res = b, z = precondition(res), p = z;
  double rz = res.dot(z);
  const double stop = relative_tolerance * b.norm();
  while (out.iterations < max_iterations && res.norm() > stop) {
    const Eigen::VectorXd q = apply(p);
    ++out.iterations;
    const double pq = p.dot(q);
    if (!(pq > 0)) {
      break;
    }
    const double alpha = rz / pq;
    out.x += alpha * p;
    res -= alpha * q;
    if (res.norm() <= stop) {
      break; // converged: the next direction (one more preconditioner solve) is not needed
    }
    z = precondition(res);
    const double rz_next = res.dot(z);
    p = z + (rz_next / rz) * p;
    rz = rz_next;
  }
  out.converged = res.norm() <= stop;
  return out;
}

/// While alive, no bond of the model breaks in the force kernel: s0 is no_limit, uniform and per
/// bond; the destructor puts the model's values back.
class BreakingSuspended {
public:
  explicit BreakingSuspended(Model& m) : m_(m), uniform_(m.field.critical_stretch) {
    if (!m_.effects.damage) {
      return;
    }
    per_bond_ = m_.field.bond_critical_stretch;
    m_.field.critical_stretch = no_limit;
    std::fill(m_.field.bond_critical_stretch.begin(), m_.field.bond_critical_stretch.end(),
              no_limit);
  }
  ~BreakingSuspended() {
    if (!m_.effects.damage) {
      return;
    }
    m_.field.critical_stretch = uniform_;
    std::copy(per_bond_.begin(), per_bond_.end(), m_.field.bond_critical_stretch.begin());
  }
  BreakingSuspended(const BreakingSuspended&) = delete;
  BreakingSuspended& operator=(const BreakingSuspended&) = delete;

private:
  Model& m_;
  double uniform_;
  std::vector<double> per_bond_;
};

class StaticSolver final : public Integrator {
public:
  StaticSolver(const IntegratorSettings& settings, Model& model, ForceEvaluator& forces)
      : model_(model), forces_(forces),
        tolerance_(settings.force_tolerance > 0 ? settings.force_tolerance : acceptable_residual) {
    if (model.effects.plasticity) {
      throw std::invalid_argument(
          "solver.integrator: static solves elastic and damaged bodies only (no plasticity yet): "
          "use adr or damped-euler for this scene");
    }
  }

  /// Equilibrium at the constraints' current values; with damage, break events until no bond is
  /// beyond s0. Each call solves again (a load-stepping driver calls it once per load level).
  StepReport step(State& st, double dt) override {
    ++calls_;
    const auto t0 = std::chrono::steady_clock::now();
    solve(st);
    std::size_t events = 0, converged_solves = newton_converged_ ? 1 : 0;
    if (model_.effects.damage) {
      const auto broken = [&] {
        return static_cast<std::size_t>(
            std::count(model_.state.broken.begin(), model_.state.broken.end(), std::uint8_t{1}));
      };
      const std::size_t first = broken();
      for (;;) {
        const std::size_t before = broken();
        forces_.compute(st.position.data(), st.force.data()); // the kernel's damage decision
        ++force_evaluations_;
        if (broken() == before) {
          break; // st.force is b at the equilibrium with the final bonds
        }
        ++events;
        solve(st);
        converged_solves += newton_converged_ ? 1 : 0;
      }
      details_["break_events"] = events;
      details_["bonds_broken"] = (broken() - first) / 2;
    }
    details_["solves"] = events + 1;
    details_["converged_solves"] = converged_solves;
    details_["step_seconds"] =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    solved_ = true;
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
  /// K of the current bonds, factored, and the linearised load f (static_assembly.hpp).
  struct Factored {
    DofMap dofs;
    Eigen::VectorXd rhs;
    std::unique_ptr<SparseFactorisation> factor;
    bool symmetric = false, folds = false;
    /// Whether the factor is of K itself; otherwise of P, the operator with every extrapolated
    /// particle refitted within preconditioner_fit_radius (then rhs is P's, not K's).
    bool exact = true;
    double asymmetry = 0;
    std::size_t nonzeros = 0;
    /// The dofs held to remove a free body's rigid motion (rigid_motion_pins), or none.
    std::vector<std::size_t> pins;
    double check_seconds = 0, assembly_seconds = 0, factorisation_seconds = 0;
  };

  Factored factor_system(bool allow_preconditioner) const {
    using clock = std::chrono::steady_clock;
    const auto t0 = clock::now();
    Factored f;
    // With extrapolated particles (ghosts, quadratic clamps) K = Aᵀ (V K) A couples each body
    // particle with everything within ~5 λ (a ghost's ~50 sources, static_assembly.cpp), and
    // its factor fills in accordingly (the plate: 450 nonzeros per row, a 90 M-entry factor).
    // The factor is then of P, the same operator with each extrapolated particle refitted from
    // the few free particles within preconditioner_fit_radius λ: symmetric and positive definite
    // like K (any A gives a positive semi-definite Aᵀ (V K) A, and the body's bonds and supports
    // make it definite), and close to K in energy, so that conjugate gradients on K converge in a
    // few iterations with P as preconditioner (solve). K itself is applied matrix-free.
    f.pins = rigid_motion_pins(model_);
    if (!f.pins.empty()) {
      require_balanced_loads();
    }
    f.dofs = map_dofs(model_);
    if (allow_preconditioner && !model_.extrapolated.empty() && f.dofs.every_dependant_folds() &&
        f.dofs.free_dofs.size() >= preconditioned_from_unknowns) {
      f.dofs = map_dofs(model_, refit_extrapolation(model_, preconditioner_fit_radius));
      f.exact = false;
    }
    if (!f.pins.empty()) {
      pin_dofs(f.dofs, f.pins);
    }
    const DofMap& d = f.dofs;
    const auto n = static_cast<Eigen::Index>(d.free_dofs.size());
    // Symmetric when every dependant's equation folds onto its sources (Aᵀ (V K) A) and V K is:
    // checked on the bonds, so that only the triangle the factorisation reads is assembled.
    // Under `copy` mirrors the assembled matrix itself is compared with its transpose.
    f.folds = d.every_dependant_folds();
    f.asymmetry = f.folds ? bond_asymmetry(model_) : 0.0;
    f.symmetric = f.folds && f.asymmetry <= 1e-12;
    if (!f.exact && !f.symmetric) { // V K itself is not symmetric: K, for UMFPACK
      f.dofs = map_dofs(model_);
      pin_dofs(f.dofs, f.pins);
      f.exact = true;
    }
    const auto t_check = clock::now();
    StaticSystem system =
        assemble_reduced(model_, d, f.symmetric ? RowPart::upper_half : RowPart::full);
    if (!f.folds) {
      f.asymmetry = system.asymmetry();
    }
    const auto t1 = clock::now();
    // Entries of the whole matrix: the upper triangle's off-diagonal ones count twice.
    f.nonzeros = system.values.size();
    if (f.symmetric) {
      std::size_t diagonal = 0;
      for (std::size_t r = 0; r < system.size(); ++r) {
        const auto first = static_cast<std::size_t>(system.row_offsets[r]);
        diagonal += first < static_cast<std::size_t>(system.row_offsets[r + 1]) &&
                    static_cast<std::size_t>(system.columns[first]) == r;
      }
      f.nonzeros = 2 * f.nonzeros - diagonal;
    }
    f.rhs = Eigen::Map<const Eigen::VectorXd>(system.rhs.data(), n);
    Eigen::SparseMatrix<double> K = column_major(std::move(system), f.symmetric);
    if (model_.effects.damage) {
      // Broken bonds can leave particles without bonds and pieces without supports: K is then
      // singular. A shift of 1e-8 of the mean diagonal keeps it factorable; K only proposes the
      // Newton steps (the residual is the kernel's), so the equilibrium found is not changed.
      const double shift =
          1e-8 * K.diagonal().sum() / static_cast<double>(std::max<Eigen::Index>(n, 1));
      Eigen::SparseMatrix<double> I(n, n);
      I.setIdentity();
      K = K + shift * I;
    }
    std::vector<std::size_t> particle(d.free_dofs.size()); // a particle's unknowns order together
    std::transform(d.free_dofs.begin(), d.free_dofs.end(), particle.begin(),
                   [](std::size_t g) { return g / 3; });
    f.factor = factorise(K, f.symmetric, particle);
    const auto t2 = clock::now();
    const auto s = [](auto a, auto b) { return std::chrono::duration<double>(b - a).count(); };
    f.check_seconds = s(t0, t_check);
    f.assembly_seconds = s(t_check, t1);
    f.factorisation_seconds = s(t1, t2);
    return f;
  }

  /// The linear solution and Newton (attempt) with P's factor where factor_system chooses it;
  /// where CG with it needs more than max_linear_iterations_with_p or Newton more than
  /// max_newton_iterations_with_p steps, once more from the same start with K's own factor. P is
  /// only close to K in energy where the refit changes little: with `volume_correction: none` on
  /// the plate (every bond to δ kept, ghosts a whole horizon deep) Newton preconditioned by P
  /// stalled at 3.4e-4 of the load after 50 steps, where K's factor converges in 3.
  void solve(State& st) {
    const std::vector<double> start = st.position;
    fell_back_ = false;
    Factored f = factor_system(true);
    if (!attempt(st, f) && !f.exact) {
      st.position = start;
      fell_back_ = true;
      f = factor_system(false);
      attempt(st, f);
    }
    if (!f.pins.empty()) {
      remove_rigid_motion(st);
    }
    // With damage a solve that did not converge is reported (converged_solves) rather than
    // thrown: the break event that follows changes the problem, and a load-stepping driver
    // records each level's state.
    if (!newton_converged_ && !model_.effects.damage) {
      throw std::runtime_error(fmt::format("static solve did not converge: {}", report_));
    }
  }

  bool attempt(State& st, const Factored& f) {
    using clock = std::chrono::steady_clock;
    linear_iterations_ = cg_iterations_ = 0;
    linear_seconds_ = 0;
    const DofMap& d = f.dofs;
    const SparseFactorisation& factor = *f.factor;
    const auto n = static_cast<Eigen::Index>(d.free_dofs.size());
    const std::vector<double>& ext = model_.external_force_density;
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
    // Bonds break only at the break events (step), never inside Newton: see the file's heading.
    const BreakingSuspended suspended(model_);
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
    if (model_.effects.damage) {
      // From the reference state, not from the previous equilibrium: with brittle bonds the
      // equilibrium depends only on the bonds left and the prescribed values, and the linear
      // solution K⁻¹ f of those bonds is within O(s²) of it, whereas from the previous state the
      // supports' jump to the new values is a one-sided step of Δu over λ.
      for (const std::size_t g : d.free_dofs) {
        y[g] = model_.particles.position[g / 3][g % 3];
      }
    }
    const Eigen::VectorXd rhs = f.exact ? f.rhs : linearised_load(d);
    const auto t_linear = clock::now();
    if (f.exact) {
      place(factor.solve(rhs));
    } else {
      const CgResult linear = linear_solution(f, rhs);
      place(linear.x);
      if (!linear.converged) {
        // P is not close to K: Newton with it would be slower still. solve falls back to K,
        // whose attempt records the details.
        return false;
      }
    }
    linear_seconds_ = std::chrono::duration<double>(clock::now() - t_linear).count();
    std::vector<std::uint8_t> held(d.kind.size());
    std::transform(d.kind.begin(), d.kind.end(), held.begin(),
                   [](std::uint8_t kind) { return static_cast<std::uint8_t>(kind != 0); });
    const double floor_force = residual_round_off_floor(model_, y, held);
    const double applied = full_load_norm(model_);
    // Converged at the tolerance dynamic relaxation is held to, or just above the round-off floor
    // where that is higher (a light load on a stiff, fine or far-off body). Newton aims at a tenth
    // of it, so that the static answer is the converged one against which relaxation's own error
    // shows. Once within the tolerance, it stops where a step no longer halves the residual
    // (Newton is then at the residual's noise: the plate, 5.2e-8 of the load after two steps and
    // 1.1e-7 after a third, with a floor estimate of 2.5e-8), and a step that made it worse is
    // taken back. Above the tolerance a step may raise the residual on the way (the strip below).
    std::size_t iterations = 0;
    double residual = 0, floor = 0, acceptable = 0;
    double previous = std::numeric_limits<double>::infinity();
    std::vector<double> before;
    for (;; ++iterations) {
      const Eigen::VectorXd r = residual_at(y);
      const double force_reference = applied > 0 ? applied : reactions_norm(st.force, held);
      residual = r.norm() / force_reference;
      floor = floor_force / force_reference;
      acceptable = std::max(tolerance_, round_off_margin * floor);
      const double target = std::max(0.1 * tolerance_, round_off_margin * floor);
      if (iterations == 0) {
        linear_residual_ = residual; // the kernel's residual at the linear solution
      }
      if (residual > previous && previous <= acceptable) {
        std::copy(before.begin(), before.end(), y);
        forces_.compute(y, st.force.data()); // st.force is b at the state returned
        ++force_evaluations_;
        residual = previous;
        --iterations;
        break;
      }
      // With P's factor Newton converges while P is close to K (the plate: 2 steps; a 0.8 m
      // strip whose linear solution leaves 1.19 of the load: 9, not monotonically); where it
      // takes longer than that, K's factor is cheaper (solve).
      const bool slow_with_p = !f.exact && iterations >= max_newton_iterations_with_p;
      const bool stalled = residual <= acceptable && residual > 0.5 * previous;
      if (residual <= target || stalled || slow_with_p || iterations >= max_newton_iterations) {
        break;
      }
      previous = residual;
      before.assign(y, y + st.position.size());
      place(f.symmetric ? newton_step(r, y, d, factor, residual_at) : factor.solve(r));
    }
    std::fill(st.velocity.begin(), st.velocity.end(), 0.0);
    const auto t3 = clock::now();
    newton_converged_ = residual <= acceptable;
    record(f, iterations, residual, floor, std::chrono::duration<double>(t3 - t2).count());
    return newton_converged_;
  }

  /// A body no support holds has an equilibrium only under loads of zero resultant and zero
  /// moment (a bar pulled at both ends); otherwise it would accelerate, and the pins would
  /// carry the difference as reactions the scene does not have.
  void require_balanced_loads() const {
    const std::vector<double>& ext = model_.external_force_density;
    if (ext.empty()) {
      return;
    }
    const auto& x = model_.particles.position;
    const auto& v = model_.particles.volume;
    Vec3 force{0, 0, 0}, moment{0, 0, 0}, centre{0, 0, 0};
    double total = 0, scale = 0, volume = 0, size = 0;
    for (std::size_t i = 0; i < model_.body_particle_count(); ++i) {
      volume += v[i];
      for (std::size_t a = 0; a < 3; ++a) {
        centre[a] += v[i] * x[i][a];
      }
    }
    for (double& c : centre) {
      c /= volume;
    }
    for (std::size_t i = 0; i < model_.body_particle_count(); ++i) {
      const Vec3 f{v[i] * ext[3 * i], v[i] * ext[3 * i + 1], v[i] * ext[3 * i + 2]};
      const Vec3 r{x[i][0] - centre[0], x[i][1] - centre[1], x[i][2] - centre[2]};
      for (std::size_t a = 0; a < 3; ++a) {
        force[a] += f[a];
      }
      moment[0] += r[1] * f[2] - r[2] * f[1];
      moment[1] += r[2] * f[0] - r[0] * f[2];
      moment[2] += r[0] * f[1] - r[1] * f[0];
      total += norm(f);
      size = std::max(size, norm(r));
    }
    scale = total;
    // Each load's resultant is exact to round-off (shared in proportion to volume), so balanced
    // loads cancel to many digits; 1e-9 of the loads' magnitude leaves room for the sums.
    const double tolerance = 1e-9;
    if (norm(force) > tolerance * scale || norm(moment) > tolerance * scale * size) {
      throw std::runtime_error(fmt::format(
          "static solve: no support holds the body and its loads are not balanced (resultant "
          "[{:.4g}, {:.4g}, {:.4g}] N, moment about the centroid [{:.4g}, {:.4g}, {:.4g}] N m), "
          "so it has no equilibrium: add a support (e.g. a fixed box) or balance the loads",
          force[0], force[1], force[2], moment[0], moment[1], moment[2]));
    }
  }

  /// A free body's solution is defined up to a rigid motion; the one reported has none in the
  /// mean: zero volume-weighted mean displacement and rotation about the centroid (the L2
  /// projection off the rigid motions, which is what the FE reference, pd-fem --scene, does too,
  /// so that both report the same displacements).
  void remove_rigid_motion(State& st) {
    const auto& x = model_.particles.position;
    const auto& v = model_.particles.volume;
    const std::size_t body = model_.body_particle_count(); // ghosts follow their sources
    double* y = st.position.data();
    Eigen::Vector3d centre = Eigen::Vector3d::Zero(), mean = Eigen::Vector3d::Zero();
    double volume = 0;
    for (std::size_t i = 0; i < body; ++i) {
      volume += v[i];
      for (std::size_t a = 0; a < 3; ++a) {
        centre[static_cast<Eigen::Index>(a)] += v[i] * x[i][a];
        mean[static_cast<Eigen::Index>(a)] += v[i] * (y[3 * i + a] - x[i][a]);
      }
    }
    centre /= volume;
    mean /= volume;
    // J ω = Σ V r × u with J = Σ V (|r|² I − r rᵀ): the rotation that best fits u − mean.
    Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
    Eigen::Vector3d torque = Eigen::Vector3d::Zero();
    for (std::size_t i = 0; i < body; ++i) {
      const Eigen::Vector3d r = Eigen::Vector3d(x[i][0], x[i][1], x[i][2]) - centre;
      const Eigen::Vector3d u =
          Eigen::Vector3d(y[3 * i] - x[i][0], y[3 * i + 1] - x[i][1], y[3 * i + 2] - x[i][2]) -
          mean;
      inertia += v[i] * (r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose());
      torque += v[i] * r.cross(u);
    }
    Eigen::Vector3d omega = Eigen::Vector3d::Zero();
    if (model_.spec.dimension.dim == 3) {
      omega = inertia.ldlt().solve(torque);
    } else if (model_.spec.dimension.dim == 2) {
      omega[2] = torque[2] / inertia(2, 2);
    }
    const auto dim = static_cast<std::size_t>(model_.spec.dimension.dim);
    for (std::size_t i = 0; i < body; ++i) {
      const Eigen::Vector3d r = Eigen::Vector3d(x[i][0], x[i][1], x[i][2]) - centre;
      const Eigen::Vector3d rigid = mean + omega.cross(r);
      for (std::size_t a = 0; a < dim; ++a) {
        y[3 * i + a] -= rigid[static_cast<Eigen::Index>(a)];
      }
    }
    apply_constraints(model_, LoadRamp{}, 0.0, y, nullptr);
    forces_.compute(y, st.force.data()); // st.force is b at the state returned
    ++force_evaluations_;
  }

  /// The residual is measured as Simulation::force_balance measures it for dynamic relaxation:
  /// against the applied loads (full_load_norm), or, where only displacements are prescribed,
  /// the reactions of the current state (K u_p, the linearised load, is far larger: a bar's
  /// supports push on their neighbours over λ, the bar resists over its length): ‖V b‖ over the
  /// held degrees of freedom (prescribed and dependent).
  double reactions_norm(const std::vector<double>& force,
                        const std::vector<std::uint8_t>& held) const {
    double sum = 0;
    for (std::size_t g = 0; g < held.size(); ++g) {
      const double v = held[g] ? model_.particles.volume[g / 3] * force[g] : 0.0;
      sum += v * v;
    }
    return std::max(std::sqrt(sum), 1e-300);
  }

  void record(const Factored& f, std::size_t iterations, double residual, double floor,
              double newton_seconds) {
    const SparseFactorisation& factor = *f.factor;
    Json& j = details_;
    j = Json::object();
    j["solver"] = factor.name();
    j["blas_kernels"] = openblas_core(); // OpenBLAS's; "" for another BLAS
    j["symmetric"] = f.symmetric;
    j["asymmetry"] = f.asymmetry;
    j["unknowns"] = f.dofs.free_dofs.size();
    j["nonzeros"] = f.nonzeros;
    j["factor_nonzeros"] = factor.factor_nonzeros();
    j["factor_bytes"] = factor.factor_bytes();
    j["assembly_seconds"] = f.assembly_seconds;
    j["symmetry_check_seconds"] = f.check_seconds;
    j["factorisation_seconds"] = f.factorisation_seconds;
    j["analysis_seconds"] = factor.analysis_seconds(); // ordering and symbolic, within the above
    j["newton_seconds"] = newton_seconds;
    j["newton_iterations"] = iterations;
    j["preconditioner"] =
        f.exact ? "K" : fmt::format("P (refit {:.3g} λ)", preconditioner_fit_radius);
    j["preconditioner_fell_back"] = fell_back_; // P did not converge: solved again with K
    j["linear_cg_iterations"] = linear_iterations_;
    j["linear_seconds"] = linear_seconds_;
    j["linear_residual"] = linear_residual_;
    j["newton_cg_iterations"] = cg_iterations_;
    j["residual"] = residual;
    j["round_off_floor"] = floor;
    // No support: the rigid motion is removed (remove_rigid_motion).
    j["free_body"] = !f.pins.empty();
    report_ = fmt::format(
        "static solve: {} unknowns, {} nonzeros, {} ({} operator, {} = {:.1e}); "
        "assembly {:.3f} s, symmetry check {:.3f} s, factorisation {:.3f} s "
        "(analysis {:.3f} s; factor {} nonzeros, {:.1f} MiB), {} Newton iterations "
        "{:.3f} s, residual {:.2e} of the load or reactions (round-off floor {:.1e}){}",
        f.dofs.free_dofs.size(), f.nonzeros, factor.name(),
        f.symmetric ? "symmetric" : "nonsymmetric", f.folds ? "‖VK−(VK)ᵀ‖/‖VK‖" : "‖K−Kᵀ‖/‖K‖",
        f.asymmetry, f.assembly_seconds, f.check_seconds, f.factorisation_seconds,
        factor.analysis_seconds(), factor.factor_nonzeros(),
        static_cast<double>(factor.factor_bytes()) / (1024.0 * 1024.0), iterations, newton_seconds,
        residual, floor,
        f.pins.empty() ? "" : "; no support: a free body, its mean rigid motion removed");
  }

  /// f = Bᵀ (b_ext − K u_p) (static_assembly.hpp) without assembling K: the prescribed values
  /// u_p through the constrained operator (kernel/linear_operator.hpp), the load folded as the
  /// dependants' rows are.
  Eigen::VectorXd linearised_load(const DofMap& d) const {
    std::vector<double> u(d.kind.size(), 0.0), ku(d.kind.size(), 0.0), w(d.kind.size(), 0.0);
    for (std::size_t g = 0; g < d.kind.size(); ++g) {
      u[g] = d.kind[g] == 1 ? d.prescribed[g] : 0.0;
    }
    apply_constrained_operator(model_, u.data(), ku.data());
    if (!model_.external_force_density.empty()) {
      w = model_.external_force_density;
      fold_mirror_forces(model_, w.data());
    }
    Eigen::VectorXd f(static_cast<Eigen::Index>(d.free_dofs.size()));
    for (std::size_t k = 0; k < d.free_dofs.size(); ++k) {
      const std::size_t g = d.free_dofs[k];
      f[static_cast<Eigen::Index>(k)] = model_.particles.volume[g / 3] * (w[g] - ku[g]);
    }
    return f;
  }

  /// K⁻¹ f by conjugate gradients on K, applied matrix-free (apply_constrained_operator: the
  /// bonds once, the extrapolation and its transpose), preconditioned by the factor of P.
  CgResult linear_solution(const Factored& f, const Eigen::VectorXd& rhs) {
    const DofMap& d = f.dofs;
    std::vector<double> u(d.kind.size()), ku(d.kind.size());
    const auto apply = [&](const Eigen::VectorXd& x) {
      std::fill(u.begin(), u.end(), 0.0);
      for (std::size_t k = 0; k < d.free_dofs.size(); ++k) {
        u[d.free_dofs[k]] = x[static_cast<Eigen::Index>(k)];
      }
      apply_constrained_operator(model_, u.data(), ku.data());
      Eigen::VectorXd out(x.size());
      for (std::size_t k = 0; k < d.free_dofs.size(); ++k) {
        const std::size_t g = d.free_dofs[k];
        out[static_cast<Eigen::Index>(k)] = model_.particles.volume[g / 3] * ku[g];
      }
      return out;
    };
    const auto precondition = [&](const Eigen::VectorXd& v) { return f.factor->solve(v); };
    CgResult cg =
        preconditioned_cg(apply, precondition, rhs, linear_tolerance, max_linear_iterations_with_p);
    linear_iterations_ = cg.iterations;
    return cg;
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
    const auto precondition = [&](const Eigen::VectorXd& v) { return factor.solve(v); };
    const CgResult cg = preconditioned_cg(tangent, precondition, r, 1e-3, max_cg_iterations);
    cg_iterations_ += cg.iterations;
    // Not positive along the first direction: the modified Newton step K⁻¹ r.
    return cg.x.isZero() ? precondition(r) : cg.x;
  }

  static constexpr std::size_t max_cg_iterations = 50;
  /// The fit radius of the preconditioner's extrapolation, in λ (factor_system): a ghost's
  /// nearest body particle and its neighbours up to the face diagonals. Measured on the plate
  /// (1 thread, load 17–21): 1.0 λ 34.0 M factor entries, 1.5 λ 32.9 M, 2.0 λ 60.7 M (√6 λ, K
  /// itself: 92.6 M), with about the same CG iterations at each (52, 53 at 1.5 and 2.0 λ).
  static constexpr double preconditioner_fit_radius = 1.5;
  /// Below this many unknowns K itself is factored: its factor is small (the clamped beam,
  /// 10,080 unknowns: 9.6 M entries, 2.1 s under load 21) and the ~90 preconditioned iterations
  /// cost more than they save (4.0 s with P at the same load).
  static constexpr std::size_t preconditioned_from_unknowns = 20000;
  /// The linear solution K⁻¹ f through the preconditioner P (linear_solution): to this relative
  /// residual. It only starts Newton, whose first residual is the kernel's nonlinearity (0.097 of
  /// the load on the plate): solving K u = f beyond a thousandth of that changes nothing Newton
  /// sees. Measured on the plate (1 thread, load 1–2): 1e-10 took 52 iterations and 1e-4 26,
  /// with the same Newton steps (12 and 15 CG iterations) and probes equal to 1e-13; 1e-2 left
  /// more to Newton's CG, whose iterations cost more (two kernel evaluations) and converged more
  /// slowly with P (30.7 s against 23.7 s at load 17–21).
  static constexpr double linear_tolerance = 1e-4;
  /// Where CG preconditioned by P needs more iterations than this, P is too far from K, and K's
  /// own factor (solve's fall-back) is cheaper than going on, although it is larger. Measured on
  /// the plate's sweep (1 thread, load 4–6; P's iterations to 1e-4 / solve with P / with K): the
  /// scene 26 / 4.5 s / 8.9 s, surface_correction none 13 / 3.1 s, volume_correction none (every
  /// bond to δ, ghosts a horizon deep: P's factor 92 M entries, K's 126 M) 149 / 95 s / 13.5 s,
  /// macek-silling + linear (no ghosts, the quadratic clamps refitted) 62 / 32 s / 4.6 s.
  static constexpr std::size_t max_linear_iterations_with_p = 40;
  static constexpr std::size_t max_newton_iterations_with_p = 12;
  /// The residual (relative to the load) a solve must reach when the settings give none, or
  /// round_off_margin × the round-off floor where that is higher (kernel/round_off.hpp).
  static constexpr double acceptable_residual = 1e-6;
  static constexpr std::size_t max_newton_iterations = 50;

  Model& model_;
  ForceEvaluator& forces_;
  double tolerance_;
  bool solved_ = false;
  bool newton_converged_ = false;
  bool fell_back_ = false;
  std::size_t linear_iterations_ = 0, cg_iterations_ = 0;
  double linear_seconds_ = 0, linear_residual_ = 0;
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
  return assemble_reduced(model, map_dofs(model), RowPart::full);
}

std::unique_ptr<Integrator> make_static_solver(const IntegratorSettings& settings, Model& model,
                                               ForceEvaluator& forces) {
  return std::make_unique<StaticSolver>(settings, model, forces);
}

} // namespace pd
