// Adaptive dynamic relaxation (ADR) for quasi-static runs: Kilic & Madenci 2010, "An adaptive
// dynamic relaxation method for quasi-static simulations using the peridynamic theory", Theor.
// Appl. Fract. Mech. 53:194–201 (cited by Pasupathy, ref. 6), after Underwood 1983.
//
// The static problem b(u) + F b_ext = 0 is solved as the steady state of the fictitious damped
// system  Λ ü + c_n Λ u̇ = F(u),  F = b(u) + F b_ext,  integrated by central differences with a
// fictitious time step Δt = 1:
//
//   fictitious density   λ_ii ≥ ¼ Δt² Σ_j |K_ij|                                  (Underwood)
//   first step           u̇^{1/2}   = Δt F^0 / (2 λ)
//   later steps          u̇^{n+½}   = [(2 − c_n Δt) u̇^{n−½} + 2 Δt F^n/λ] / (2 + c_n Δt)
//                        u^{n+1}   = u^n + Δt u̇^{n+½}
//   damping              c_n = 2 sqrt( (uⁿᵀ ¹Kⁿ uⁿ) / (uⁿᵀ uⁿ) )   (0 if the quotient is ≤ 0)
//   local stiffness      ¹K_ii = −(F_i^n/λ_ii − F_i^{n−1}/λ_ii) / (Δt u̇_i^{n−½})   (0 if u̇_i = 0)
//
// c_n is the critical damping 2ω of the lowest mode that the current displacement excites (the
// Rayleigh quotient of the diagonal estimate of Λ⁻¹K estimates ω²), so the damping adapts every
// step and no damping coefficient has to be chosen.
//
// The stiffness sum. The linearised bond operator (Miranda eq. 30) gives, for bond ij with
// k_ij = c_ij V_j/|ξ_ij| and unit vector n = ξ/|ξ|, the 3×3 blocks K_ii += k n⊗n and
// K_ij = −k n⊗n. The Gershgorin row sum of dof (i, a) is therefore at most
//   Σ_j |K_(ia),·| = Σ_j 2 k_ij |n_a| (|n_x| + |n_y| + |n_z|),
// which we evaluate exactly per degree of freedom. In 1D it is 2 Σ_j k_ij, so λ = ½ Σ_j k_ij: the
// eq. 31 condition Δt² < 2ρ/Σ_j k_ij with Δt = 1 and ρ = λ. Taking only the eq. 31 sum
// (λ = ¼ Σ_j k_ij) would be unstable: for the 1D bar with m = 3.015 and the linear volume
// correction the alternating mode v_j = (−1)^j has (Kv)_i = Σ_{j at odd distance} 2 k_ij v_i
// ≈ 1.40 (Σ_j k_ij) v_i, beyond 4λ = Σ_j k_ij.
#include "libpd/core/binary_state.hpp"
#include "libpd/kernel/force_kernel.hpp"
#include "libpd/kernel/linear_operator.hpp"
#include "libpd/time/integrator.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace pd {

std::vector<double> adr_fictitious_density(const Model& m) {
  const std::size_t n = m.size();
  std::vector<double> rows(3 * n, 0.0);
  // Row (i, c) of Aᵀ K A is bounded by Σ_d |A_di| Σ_e |K_de| ‖A_e‖₁: each bond's entries count
  // with the row norms of its two ends (1 for free particles), then dependants' rows fold.
  const auto reach = constraint_row_norms(m);
  for (std::size_t i = 0; i < n; ++i) {
    double* row = &rows[3 * i];
    // Every bond, broken or not: λ is the bound of the undamaged operator.
    for_each_linearised_bond(m, i, BrokenBonds::included, [&](const LinearisedBond& b) {
      double l1 = 0;
      for (std::size_t c = 0; c < 3; ++c) {
        l1 += std::abs(b.direction[c]);
      }
      const double ends = reach[i] + reach[b.neighbour];
      for (std::size_t c = 0; c < 3; ++c) {
        row[c] += ends * b.stiffness * std::abs(b.direction[c]) * l1; // Gershgorin row sum
      }
    });
  }
  // A source's row of Aᵀ K A also holds its dependants' rows: adding them keeps the bound.
  fold_mirror_bounds(m, rows.data());
  std::vector<double> lambda(3 * n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    const double* row = &rows[3 * i];
    const double largest = std::max({row[0], row[1], row[2]});
    for (std::size_t c = 0; c < 3; ++c) {
      // λ_ii = ¼ Δt² Σ_j |K_ij| with Δt = 1. A component without stiffness (y, z of a 1D model)
      // carries no force either; the particle's largest value keeps the division finite.
      const double sum = row[c] > 0 ? row[c] : largest;
      lambda[3 * i + c] = sum > 0 ? 0.25 * sum : 1.0;
    }
  }
  return lambda;
}

namespace {

class AdaptiveDynamicRelaxation final : public Integrator {
public:
  AdaptiveDynamicRelaxation(Model& m, ForceEvaluator& f, const IntegratorSettings& s)
      : model_(m), forces_(f), ramp_(s.ramp) {
    const std::size_t n = m.size();
    lambda_ = adr_fictitious_density(m);
    velocity_.assign(3 * n, 0.0);
    previous_.assign(3 * n, 0.0);
    constrained_ = held_dofs(m);
  }

  StepReport step(State& st, double dt) override {
    ++calls_;
    double* y = st.position.data();
    double* b = st.force.data();
    forces_.compute(y, b);
    ++force_evaluations_;
    const double t_new = st.time + dt;
    const double load = ramp_.factor(t_new);
    const double* ext =
        model_.external_force_density.empty() ? nullptr : model_.external_force_density.data();
    const std::size_t ndof = st.position.size();
    const auto& x = model_.particles.position;

    // Damping from the Rayleigh quotient of the local stiffness. Each particle's three terms
    // are added in a fixed order, then the particles' sums exactly over the owned particles:
    // bitwise the same for any thread and rank count, at one exact addition per particle and
    // sum against the O(N·bonds) force evaluation.
    double c_n = 0;
    if (started_) {
      std::array<ExactSum, 2> sums;
      auto& [num, den] = sums;
      const Ownership& own = model_.ownership;
      for (std::size_t i = 0; i < ndof / 3; ++i) {
        if (!own.owns(i)) {
          continue;
        }
        double particle_num = 0, particle_den = 0;
        for (std::size_t d = 3 * i; d < 3 * i + 3; ++d) {
          if (constrained_[d]) {
            continue;
          }
          const double f = ext != nullptr ? b[d] + load * ext[d] : b[d];
          const double u = y[d] - x[i][d % 3];
          const double vel = velocity_[d];
          if (vel != 0) {
            const double k_local = -(f - previous_[d]) / (lambda_[d] * vel); // ¹K_ii, Δt = 1
            particle_num += u * k_local * u;
          }
          particle_den += u * u;
        }
        num.add(particle_num);
        den.add(particle_den);
      }
      own.communicator().sum(sums);
      const double q = den.value() > 0 ? num.value() / den.value() : 0.0;
      c_n = q > 0 && std::isfinite(q) ? 2.0 * std::sqrt(q) : 0.0;
    }
    last_damping_ = c_n;

    const double inv_dt = 1.0 / dt; // fictitious velocity reported in units of the step's time
    const auto n = static_cast<std::ptrdiff_t>(model_.size());
    const bool first = !started_;
#pragma omp parallel for schedule(static) if (model_.size() >= parallel_min_particles)
    for (std::ptrdiff_t ii = 0; ii < n; ++ii) {
      const auto i = static_cast<std::size_t>(ii);
      for (std::size_t c = 0; c < 3; ++c) {
        const std::size_t d = 3 * i + c;
        const double f = ext != nullptr ? b[d] + load * ext[d] : b[d];
        previous_[d] = f;
        if (constrained_[d]) {
          velocity_[d] = 0;
          continue;
        }
        const double a = f / lambda_[d];
        velocity_[d] =
            first ? 0.5 * a : ((2.0 - c_n) * velocity_[d] + 2.0 * a) / (2.0 + c_n); // Δt = 1
        y[d] += velocity_[d];
        st.velocity[d] = velocity_[d] * inv_dt;
      }
    }
    started_ = true;
    apply_constraints(model_, ramp_, t_new, y, st.velocity.data());
    st.time = t_new;
    ++st.step;
    return displacement_report(model_, y);
  }

  std::string name() const override {
    return "adr";
  }

  // Positions are rounded at every iteration, as in damped Euler, but c_n has no fixed value to
  // put into kinematic_damping_amplification: once the residual reaches the floor, the Rayleigh
  // quotient it comes from is the round-off noise's own, and c_n is 0 in most iterations. What is
  // left is a measurement: on two 2D cantilevers under their own weight (steel, 1 × 0.1 m at
  // λ = 1 cm; concrete, 3.5 × 0.4 m at λ = 5 cm placed 100 m from the origin) the residual hovers
  // at 4–9× the floor for 10^5 iterations and only then sinks towards it. 5 is the middle of that
  // band.
  double round_off_amplification(double /*dt*/) const override {
    return 5.0;
  }

  double last_damping() const {
    return last_damping_;
  }

protected:
  // λ and the constraint mask follow from the model; the half-step velocity and F^{n−1} are
  // history (the damping c_n of the next step is computed from them).
  void save_state(CheckpointWriter& w) const override {
    w.boolean(started_);
    w.f64(last_damping_);
    w.per_particle(velocity_, 3);
    w.per_particle(previous_, 3);
  }
  void restore_state(CheckpointReader& r) override {
    started_ = r.boolean();
    last_damping_ = r.f64();
    velocity_ = r.per_particle(velocity_.size(), 3, "ADR velocity");
    previous_ = r.per_particle(previous_.size(), 3, "ADR previous force");
  }

private:
  Model& model_;
  ForceEvaluator& forces_;
  LoadRamp ramp_;
  std::vector<double> lambda_;   ///< fictitious density per dof
  std::vector<double> velocity_; ///< u̇^{n−½} in fictitious time
  std::vector<double> previous_; ///< F^{n−1}
  std::vector<std::uint8_t> constrained_;
  bool started_ = false;
  double last_damping_ = 0;
};

} // namespace

std::unique_ptr<Integrator> make_adr_integrator(const IntegratorSettings& settings, Model& model,
                                                ForceEvaluator& forces) {
  return std::make_unique<AdaptiveDynamicRelaxation>(model, forces, settings);
}

} // namespace pd
