// SUNDIALS ARKode ERKStep (6.4.1) as a libpd integrator.
//
// The first-order system. y = [u; v] (6N values, all three components of every particle), with
//   u' = v,   v' = a(u, v, t) = (b(X + u) + F(t) b_ext)/ρ − (c_v/ρ) v,
// b the PD internal force density (Miranda eq. 27), F the load ramp (eq. 33) and c_v the
// kinematic damping coefficient (Miranda §3.2) as a term of the right-hand side. The state holds
// displacements u, not positions y = X + u, so that the adaptive error test weighs
// rtol·|u| + atol instead of rtol·|X|, which would swamp every displacement.
//
// Supports. Constrained components are not integrated: their derivative is the prescribed rate
// F'(t)·value (0 for fixed ones), and the force evaluation always takes their exact value
// F(t)·value (apply_constraints), so they cannot drift whatever the table.
//
// State wrapping. ARKode keeps its own solution vector y_n (cloned at ERKStepCreate and advanced
// internally) and copies it into the caller's output vector after each step, so a zero-copy wrap of
// libpd's State is not possible with ERKStep: State keeps y = X + u and v in two std::vectors, and
// even a ManyVector over them would be a copy target, not ARKode's state. The cheapest correct way
// is one contiguous 6N buffer [u; v] owned by the integrator and wrapped without copy by
// N_VMake_Serial; it is ARKode's y0 and output vector. State is synchronised at step boundaries
// (y = X + u, v), O(N) against the O(N·bonds) force evaluations of each step; if the caller
// changes the State's time (a new run), the integrator restarts from it with ERKStepReset.
//
// Split runs (MPI). Each rank's vector holds its own particles and its halo copies; stages combine
// vectors entry by entry, and every reduction the adaptive steps take is an exact sum (or extremum)
// over the owned entries, reduced over the ranks (OwnedNorms below), so a split run accepts and
// rejects the steps one process does, bit for bit.
//
// History. ForceEvaluator::compute updates bond history (damage, plastic stretch) in place, and
// ERK stages are trial evaluations (and adaptive steps may be rejected), so arkode refuses models
// with damage or plasticity (make_integrator throws; the scene parser reports it first).
//
// SUNDIALS issue #311 (fixed in 6.7.0). At the end of a step ERKStep 6.4.1 copies the last
// stage's right-hand side into the first stage of the next step whenever c_s = 1, even if the last
// row of A differs from bᵀ (not FSAL). Measured on y'' = −y
// (tests/unit/time/integrator_order_test.cpp): classic RK4 falls to order 3, ARK324L2SA-ERK and
// Sayfy–Aburub to order 2, and Heun–Euler keeps order 2 but has a 2.5× larger error and grows far
// faster. For the offered tables with c_s = 1 that are not FSAL (heun-euler, rk4) the integrator
// calls ERKStepReset before every step, which makes ERKStep recompute f(t_n, y_n) for the first
// stage: s right-hand sides per step, the correct count for a non-FSAL table. Native tables with
// c_s ≠ 1 or true FSAL need no work-around.
//
// Checkpoints (fixed steps). A continuing ERKStep enters step n+1 with f(t_n, y_n) in hand:
// evaluated at the end of step n (c_s ≠ 1) or copied from step n's last stage (c_s = 1). For FSAL
// tables that stage is f at z_s = y_{n−1} + h Σ_j a_sj F_j with a_s = bᵀ, the sum that gives y_n
// (b_s = 0 adds an exact zero), so it is f(t_n, y_n) bit for bit. A restored run keeps [u; v]
// bitwise (not y = X + u, which would round u) and starts a fresh ERKStep from it, which evaluates
// f(t_n, y_n) itself: the same bits, and an evaluation the saved run has already counted, so it is
// not counted twice (checkpoint_test compares states and counters for rk4, knoth-wolke,
// bogacki-shampine and dormand-prince). The work-around tables reset ERKStep before every step, so
// a restart is like any of their steps. Refused: tables with c_s = 1 that are not FSAL run without
// the work-around (their copied stage is not f(t_n, y_n) and cannot be rebuilt), and adaptive
// steps (step size, error-controller history and stability-limited step live inside ERKStep and
// cannot be set back).
#include "libpd/core/binary_state.hpp"
#include "libpd/core/exact_sum.hpp"
#include "libpd/kernel/force_kernel.hpp"
#include "libpd/time/integrator.hpp"
#include "libpd/time/stability.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <limits>
#include <map>
#include <mutex>
#include <stdexcept>

#ifdef LIBPD_HAVE_SUNDIALS
#include <arkode/arkode_butcher_erk.h>
#include <arkode/arkode_erkstep.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#endif

namespace pd {

bool arkode_available() {
#ifdef LIBPD_HAVE_SUNDIALS
  return true;
#else
  return false;
#endif
}

bool ButcherTableau::hit_by_issue_311() const {
  if (stages < 1 || std::abs(c[static_cast<std::size_t>(stages - 1)] - 1.0) > 1e-12) {
    return false;
  }
  const auto s = static_cast<std::size_t>(stages);
  for (std::size_t j = 0; j < s; ++j) {
    if (std::abs(a[(s - 1) * s + j] - b[j]) > 1e-14) {
      return true; // c_s = 1 but not first-same-as-last
    }
  }
  return false;
}

#ifdef LIBPD_HAVE_SUNDIALS

namespace {

ButcherTableau from_sundials(ARKodeButcherTable t, std::string name) {
  ButcherTableau out;
  out.name = std::move(name);
  out.stages = t->stages;
  out.order = t->q;
  out.embedded_order = t->d != nullptr ? t->p : 0;
  const auto s = static_cast<std::size_t>(t->stages);
  out.c.assign(t->c, t->c + s);
  out.b.assign(t->b, t->b + s);
  if (t->d != nullptr) {
    out.d.assign(t->d, t->d + s);
  }
  out.a.resize(s * s);
  for (std::size_t i = 0; i < s; ++i) {
    for (std::size_t j = 0; j < s; ++j) {
      out.a[i * s + j] = t->A[i][j];
    }
  }
  return out;
}

ButcherTableau load_native(ARKODE_ERKTableID id, std::string name) {
  ARKodeButcherTable t = ARKodeButcherTable_LoadERK(id);
  if (t == nullptr) {
    throw std::runtime_error(fmt::format("SUNDIALS has no ERK table {}", static_cast<int>(id)));
  }
  ButcherTableau out = from_sundials(t, std::move(name));
  ARKodeButcherTable_Free(t);
  return out;
}

} // namespace

ButcherTableau sundials_erk_tableau(int table_id) {
  return load_native(static_cast<ARKODE_ERKTableID>(table_id),
                     fmt::format("sundials-erk-{}", table_id));
}

ButcherTableau butcher_tableau(ArkodeTable table) {
  const std::string name = to_string(table);
  switch (table) {
  case ArkodeTable::heun_euler:
    return load_native(ARKODE_HEUN_EULER_2_1_2, name);
  case ArkodeTable::bogacki_shampine:
    return load_native(ARKODE_BOGACKI_SHAMPINE_4_2_3, name);
  case ArkodeTable::knoth_wolke:
    return load_native(ARKODE_KNOTH_WOLKE_3_3, name);
  case ArkodeTable::rk4: {
    // Kutta's classic method (Hairer, Nørsett & Wanner, Solving ODE I, Table 1.2).
    ButcherTableau t;
    t.name = name;
    t.stages = 4;
    t.order = 4;
    t.c = {0, 0.5, 0.5, 1};
    t.a = {0, 0, 0, 0, 0.5, 0, 0, 0, 0, 0.5, 0, 0, 0, 0, 1, 0};
    t.b = {1.0 / 6, 1.0 / 3, 1.0 / 3, 1.0 / 6};
    return t;
  }
  case ArkodeTable::zonneveld:
    return load_native(ARKODE_ZONNEVELD_5_3_4, name);
  case ArkodeTable::cash_karp:
    return load_native(ARKODE_CASH_KARP_6_4_5, name);
  case ArkodeTable::fehlberg:
    return load_native(ARKODE_FEHLBERG_6_4_5, name);
  case ArkodeTable::dormand_prince:
    return load_native(ARKODE_DORMAND_PRINCE_7_4_5, name);
  }
  throw std::logic_error("unknown ARKode table");
}

namespace {

/// Norms over the whole body for a split run (and the same code in one process): the entries of
/// the owned particles only (a halo copy is another rank's entry, and its values between two
/// exchanges are not the owner's), summed exactly (core/exact_sum.hpp) and reduced over the ranks,
/// so every rank takes the same step-size decisions and the steps are those of one process. The
/// vector [u; v] holds 6 values per local particle. SUNDIALS' serial vector keeps no user
/// pointer; the integrator's SUNContext, which every clone carries, is the key.
struct OwnedNorms {
  const Ownership* ownership = nullptr;
  std::size_t particles = 0; ///< local particles (the vector has 6 per particle)
  double global_entries = 0; ///< 6 × the whole model's particles

  bool owns_entry(sunindextype e) const {
    return ownership->owns((static_cast<std::size_t>(e) % (3 * particles)) / 3);
  }
};

std::mutex owned_norms_mutex;
std::map<SUNContext, OwnedNorms>& owned_norms_by_context() {
  static std::map<SUNContext, OwnedNorms> by_context;
  return by_context;
}

const OwnedNorms& owned_norms(N_Vector v) {
  const std::lock_guard lock(owned_norms_mutex);
  return owned_norms_by_context().at(v->sunctx);
}

template <class Term>
double owned_exact_sum(const OwnedNorms& on, N_Vector x, Term term) {
  const sunindextype n = N_VGetLength_Serial(x);
  ExactSum sum;
  for (sunindextype e = 0; e < n; ++e) {
    if (on.owns_entry(e)) {
      sum.add(term(e));
    }
  }
  return on.ownership->communicator().sum(sum);
}

template <class Term>
double owned_extremum(N_Vector x, bool largest, Term term) {
  const OwnedNorms& on = owned_norms(x);
  const sunindextype n = N_VGetLength_Serial(x);
  double out =
      largest ? -std::numeric_limits<double>::infinity() : std::numeric_limits<double>::infinity();
  for (sunindextype e = 0; e < n; ++e) {
    if (on.owns_entry(e)) {
      out = largest ? std::max(out, term(e)) : std::min(out, term(e));
    }
  }
  const Communicator& comm = on.ownership->communicator();
  return largest ? comm.max(out) : comm.min(out);
}

/// Σ (x w)² over the owned entries, where `mask` (if given) is positive; the three weighted norms
/// are this sum over the whole model's entries (RMS) or alone (L2).
double owned_weighted_squares(const OwnedNorms& on, N_Vector x, N_Vector w,
                              const double* mask = nullptr) {
  const double* xd = N_VGetArrayPointer(x);
  const double* wd = N_VGetArrayPointer(w);
  return owned_exact_sum(on, x, [&](sunindextype e) {
    const double p = mask == nullptr || mask[e] > 0 ? xd[e] * wd[e] : 0.0;
    return p * p;
  });
}

sunrealtype owned_wrms_norm(N_Vector x, N_Vector w) {
  const OwnedNorms& on = owned_norms(x);
  return std::sqrt(owned_weighted_squares(on, x, w) / on.global_entries);
}

sunrealtype owned_wrms_norm_mask(N_Vector x, N_Vector w, N_Vector id) {
  const OwnedNorms& on = owned_norms(x);
  return std::sqrt(owned_weighted_squares(on, x, w, N_VGetArrayPointer(id)) / on.global_entries);
}

sunrealtype owned_wl2_norm(N_Vector x, N_Vector w) {
  return std::sqrt(owned_weighted_squares(owned_norms(x), x, w));
}

sunrealtype owned_dot(N_Vector x, N_Vector y) {
  const double* xd = N_VGetArrayPointer(x);
  const double* yd = N_VGetArrayPointer(y);
  return owned_exact_sum(owned_norms(x), x, [&](sunindextype e) { return xd[e] * yd[e]; });
}

sunrealtype owned_l1_norm(N_Vector x) {
  const double* xd = N_VGetArrayPointer(x);
  return owned_exact_sum(owned_norms(x), x, [&](sunindextype e) { return std::abs(xd[e]); });
}

sunrealtype owned_max_norm(N_Vector x) {
  const double* xd = N_VGetArrayPointer(x);
  return std::max(0.0, owned_extremum(x, true, [&](sunindextype e) { return std::abs(xd[e]); }));
}

sunrealtype owned_min(N_Vector x) {
  const double* xd = N_VGetArrayPointer(x);
  return owned_extremum(x, false, [&](sunindextype e) { return xd[e]; });
}

/// Every reduction ERKStep may take goes through the owned entries; the fused ones fall back to
/// these (SUNDIALS loops over the single operations when a fused one is absent).
void use_owned_norms(N_Vector v) {
  N_Vector_Ops ops = v->ops;
  ops->nvwrmsnorm = owned_wrms_norm;
  ops->nvwrmsnormmask = owned_wrms_norm_mask;
  ops->nvwl2norm = owned_wl2_norm;
  ops->nvdotprod = owned_dot;
  ops->nvl1norm = owned_l1_norm;
  ops->nvmaxnorm = owned_max_norm;
  ops->nvmin = owned_min;
  ops->nvminquotient = nullptr; // used by implicit constraint handling only
  ops->nvdotprodmulti = nullptr;
  ops->nvwrmsnormvectorarray = nullptr;
  ops->nvwrmsnormmaskvectorarray = nullptr;
}

class ArkodeIntegrator final : public Integrator {
public:
  ArkodeIntegrator(Model& m, ForceEvaluator& f, const IntegratorSettings& s)
      : model_(m), forces_(f), damping_(s.damping), ramp_(s.ramp), spec_(s.arkode),
        stable_dt_(s.stable_dt), cfl_(s.cfl_fraction), tableau_(butcher_tableau(s.arkode.table)) {
    if (spec_.adaptive && tableau_.embedded_order == 0) {
      throw std::invalid_argument(
          fmt::format("ARKode table '{}' has no embedded method: it runs with fixed steps only",
                      tableau_.name));
    }
    reset_each_step_ = spec_.issue_311_workaround && tableau_.hit_by_issue_311();
    beta_ = imaginary_stability_interval(tableau_);
    ndof_ = 3 * m.size();
    if (SUNContext_Create(nullptr, &context_) != 0) {
      throw std::runtime_error("SUNContext_Create failed");
    }
    buffer_.assign(2 * ndof_, 0.0);
    scratch_position_.assign(ndof_, 0.0);
    scratch_force_.assign(ndof_, 0.0);
    y_ = N_VMake_Serial(static_cast<sunindextype>(2 * ndof_), buffer_.data(), context_);
    {
      const std::lock_guard lock(owned_norms_mutex);
      const Ownership& own = m.ownership;
      owned_norms_by_context()[context_] = {
          &own, m.size(),
          6.0 * static_cast<double>(own.partial() ? own.global_particles : m.size())};
    }
    use_owned_norms(y_); // ERKStep's clones copy the operations
    constraint_rate_.assign(ndof_, 0.0);
    constrained_ = held_dofs(m);
  }

  ~ArkodeIntegrator() override {
    if (memory_ != nullptr) {
      ERKStepFree(&memory_);
    }
    if (table_ != nullptr) {
      ARKodeButcherTable_Free(table_);
    }
    if (y_ != nullptr) {
      N_VDestroy(y_);
    }
    if (context_ != nullptr) {
      {
        const std::lock_guard lock(owned_norms_mutex);
        owned_norms_by_context().erase(context_);
      }
      SUNContext_Free(&context_);
    }
  }

  ArkodeIntegrator(const ArkodeIntegrator&) = delete;
  ArkodeIntegrator& operator=(const ArkodeIntegrator&) = delete;

  StepReport step(State& st, double dt) override {
    ++calls_;
    if (restored_) {
      restored_ = false;
      start();
    } else if (memory_ == nullptr || st.time != time_) {
      load(st);
    }
    const double t_out = time_ + dt;
    int flag = 0;
    if (!spec_.adaptive) {
      if (dt != fixed_dt_) {
        ERKStepSetFixedStep(memory_, dt);
        fixed_dt_ = dt;
      }
      if (reset_each_step_ && steps_in_run_ > 0) {
        ERKStepReset(memory_, time_, y_); // issue #311 work-around: recompute f(t_n, y_n)
      }
      double t_ret = time_;
      flag = ERKStepEvolve(memory_, t_out, y_, &t_ret, ARK_ONE_STEP);
      ++steps_in_run_;
    } else {
      ERKStepSetStopTime(memory_, t_out);
      double t_ret = time_;
      std::size_t guard = 0;
      while (flag >= 0 && t_ret < t_out && guard++ < 10'000'000) {
        if (reset_each_step_ && steps_in_run_ > 0) {
          double h_last = 0;
          ERKStepGetCurrentStep(memory_, &h_last);
          ERKStepSetInitStep(memory_, h_last); // keeps Reset from re-estimating h0
          ERKStepReset(memory_, t_ret, y_);
          ERKStepSetStopTime(memory_, t_out); // Reset clears the stop time
        }
        flag = ERKStepEvolve(memory_, t_out, y_, &t_ret, ARK_ONE_STEP);
        ++steps_in_run_;
        if (flag == ARK_TSTOP_RETURN) {
          break;
        }
      }
    }
    long steps = 0;
    ERKStepGetNumSteps(memory_, &steps);
    internal_steps_ = steps_before_ + static_cast<std::size_t>(steps); // Reset keeps counters
    time_ = t_out;
    st.time = t_out;
    ++st.step;
    if (flag < 0) {
      // An error (e.g. a step size below the minimum as the solution blows up): report it as
      // non-finite so the run stops as unstable.
      StepReport r;
      r.max_displacement_squared = std::numeric_limits<double>::quiet_NaN();
      return r;
    }
    store(st);
    return displacement_report(model_, st.position.data());
  }

  std::string name() const override { return "arkode:" + tableau_.name; }
  std::size_t internal_steps() const override { return internal_steps_; }
  double stability_scale() const override {
    // β/2 keeps the eq. 31 margin of central differences. Heun–Euler has β = 0 (|R(iy)| > 1 for
    // all y ≠ 0): undamped runs grow for any Δt, so it takes half the central-difference step.
    return beta_ > 0 ? 0.5 * beta_ : 0.5;
  }

  std::string checkpoint_refusal() const override {
    if (spec_.adaptive) {
      return "adaptive ARKode steps cannot be checkpointed: the step size and the error "
             "controller's history live inside SUNDIALS and cannot be restored (use fixed steps, "
             "solver.arkode.adaptive: false, or run without checkpoints)";
    }
    if (copies_last_stage() && !is_fsal()) {
      return fmt::format("ARKode table '{}' without the issue #311 work-around carries a stale "
                         "first stage from step to step, which a restart cannot reproduce",
                         tableau_.name);
    }
    return {};
  }

protected:
  void save_state(CheckpointWriter& w) const override {
    if (const std::string why = checkpoint_refusal(); !why.empty()) {
      throw CheckpointError(why);
    }
    w.f64(time_);
    w.u64(internal_steps_);
    w.per_particle(buffer_, 3); // [u; v]: two blocks of three values per particle
  }

  void restore_state(CheckpointReader& r) override {
    if (const std::string why = checkpoint_refusal(); !why.empty()) {
      r.fail(why);
    }
    time_ = r.f64();
    internal_steps_ = r.u64();
    steps_before_ = internal_steps_;
    const std::vector<double> saved = r.per_particle(buffer_.size(), 3, "ARKode state [u; v]");
    std::copy(saved.begin(), saved.end(), buffer_.begin()); // y_ wraps buffer_'s storage
    if (memory_ != nullptr) {
      ERKStepFree(&memory_); // the next step starts a fresh ERKStep from the restored [u; v]
      memory_ = nullptr;
    }
    fixed_dt_ = 0;
    restored_ = true;
    // A fresh ERKStep evaluates f(t_n, y_n), which the saved run had already evaluated (and
    // counted) or copied at the end of its last step; the work-around tables reset every step
    // anyway.
    uncounted_evaluations_ = reset_each_step_ ? 0 : 1;
  }

private:
  /// ERKStep 6.4.1 reuses the last stage as the next first stage (c_s = 1, no reset per step).
  bool copies_last_stage() const {
    return !reset_each_step_ && tableau_.stages > 0 &&
           tableau_.c[static_cast<std::size_t>(tableau_.stages - 1)] == 1.0;
  }
  bool is_fsal() const { return !tableau_.hit_by_issue_311(); }

  static int rhs(sunrealtype t, N_Vector y, N_Vector ydot, void* data) {
    auto* self = static_cast<ArkodeIntegrator*>(data);
    self->evaluate(t, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot));
    return 0;
  }

  static int stability(N_Vector, sunrealtype, sunrealtype* h_stable, void* data) {
    *h_stable = static_cast<ArkodeIntegrator*>(data)->stable_dt_;
    return 0;
  }

  static void silence(int, const char*, const char*, char*, void*) {
    // Failures are reported through the return flag (the run stops as unstable); SUNDIALS'
    // default handler would print to stderr from inside a library.
  }

  void evaluate(double t, const double* y, double* ydot) {
    const auto& x = model_.particles.position;
    double* pos = scratch_position_.data();
    double* b = scratch_force_.data();
    const double* u = y;
    const double* v = y + ndof_;
    const auto n = static_cast<std::ptrdiff_t>(model_.size());
#pragma omp parallel for schedule(static) if (model_.size() >= parallel_min_particles)
    for (std::ptrdiff_t ii = 0; ii < n; ++ii) {
      const auto i = static_cast<std::size_t>(ii);
      for (std::size_t c = 0; c < 3; ++c) {
        pos[3 * i + c] = x[i][c] + u[3 * i + c];
      }
    }
    apply_constraints(model_, ramp_, t, pos, nullptr);
    forces_.compute(pos, b);
    if (uncounted_evaluations_ > 0) {
      --uncounted_evaluations_;
    } else {
      ++force_evaluations_;
    }
    const double load = ramp_.factor(t);
    const double rate = ramp_.rate(t);
    const double* ext =
        model_.external_force_density.empty() ? nullptr : model_.external_force_density.data();
    double* du = ydot;
    double* dv = ydot + ndof_;
#pragma omp parallel for schedule(static) if (model_.size() >= parallel_min_particles)
    for (std::ptrdiff_t ii = 0; ii < n; ++ii) {
      const auto i = static_cast<std::size_t>(ii);
      const double inv_rho = 1.0 / model_.density[i];
      for (std::size_t c = 0; c < 3; ++c) {
        const std::size_t d = 3 * i + c;
        if (constrained_[d]) {
          du[d] = rate * constraint_rate_[d];
          dv[d] = 0;
          continue;
        }
        const double f = ext != nullptr ? b[d] + load * ext[d] : b[d];
        du[d] = v[d];
        dv[d] = inv_rho * (f - damping_ * v[d]);
      }
    }
  }

  /// (Re)start from the State: u = y − X, v.
  void load(const State& st) {
    const auto& x = model_.particles.position;
    for (std::size_t d = 0; d < ndof_; ++d) {
      buffer_[d] = st.position[d] - x[d / 3][d % 3];
      buffer_[ndof_ + d] = st.velocity[d];
    }
    time_ = st.time;
    start();
  }

  /// (Re)start ERKStep at time_ from buffer_.
  void start() {
    for (const Constraint& c : model_.constraints) {
      constraint_rate_[3 * c.particle + c.component] = c.value;
    }
    steps_in_run_ = 0;
    if (memory_ == nullptr) {
      memory_ = ERKStepCreate(rhs, time_, y_, context_);
      if (memory_ == nullptr) {
        throw std::runtime_error("ERKStepCreate failed");
      }
      ERKStepSetUserData(memory_, this);
      ERKStepSetErrHandlerFn(memory_, silence, nullptr);
      std::vector<double> a(tableau_.a);
      if (table_ != nullptr) {
        ARKodeButcherTable_Free(table_); // a restore starts a second ERKStep
      }
      table_ = ARKodeButcherTable_Create(
          tableau_.stages, tableau_.order, tableau_.embedded_order,
          const_cast<double*>(tableau_.c.data()), a.data(), const_cast<double*>(tableau_.b.data()),
          tableau_.d.empty() ? nullptr : const_cast<double*>(tableau_.d.data()));
      if (table_ == nullptr || ERKStepSetTable(memory_, table_) != ARK_SUCCESS) {
        throw std::runtime_error(fmt::format("ERKStep rejected table '{}'", tableau_.name));
      }
      ERKStepSetMaxNumSteps(memory_, -1); // no limit per call: the run loop limits steps
      if (spec_.adaptive) {
        ERKStepSStolerances(memory_, spec_.rtol, spec_.atol);
        if (stable_dt_ > 0) {
          ERKStepSetStabilityFn(memory_, stability, this);
          ERKStepSetCFLFraction(memory_, cfl_);
        }
      }
    } else {
      ERKStepReset(memory_, time_, y_);
    }
  }

  /// State ← y: positions X + u with exact constraint values, velocities, and the last force.
  void store(State& st) {
    const auto& x = model_.particles.position;
    for (std::size_t d = 0; d < ndof_; ++d) {
      st.position[d] = x[d / 3][d % 3] + buffer_[d];
      st.velocity[d] = buffer_[ndof_ + d];
    }
    apply_constraints(model_, ramp_, st.time, st.position.data(), st.velocity.data());
    // b of the last right-hand side: f(t_{n+1}, y_{n+1}) for native tables (their end-of-step
    // evaluation, or the FSAL stage); the last stage for the work-around tables, which differs by
    // O(Δt·|v|) and only feeds the steady-state residual.
    st.force = scratch_force_;
  }

  Model& model_;
  ForceEvaluator& forces_;
  double damping_;
  LoadRamp ramp_;
  ArkodeSpec spec_;
  double stable_dt_;
  double cfl_;
  ButcherTableau tableau_;
  bool reset_each_step_ = false;
  double beta_ = 0;
  std::size_t ndof_ = 0;
  SUNContext context_ = nullptr;
  N_Vector y_ = nullptr;
  void* memory_ = nullptr;
  ARKodeButcherTable table_ = nullptr;
  std::vector<double> buffer_; ///< [u; v], ARKode's y0 and output vector
  std::vector<double> scratch_position_;
  std::vector<double> scratch_force_;
  std::vector<double> constraint_rate_; ///< prescribed value per constrained dof (× F'(t))
  std::vector<std::uint8_t> constrained_;
  double time_ = 0;
  double fixed_dt_ = 0;
  std::size_t steps_in_run_ = 0;
  std::size_t internal_steps_ = 0;
  std::size_t steps_before_ = 0; ///< internal steps before a restore (a new ERKStep counts from 0)
  bool restored_ = false;
  std::size_t uncounted_evaluations_ = 0;
};

} // namespace

std::unique_ptr<Integrator> make_arkode_integrator(const IntegratorSettings& settings, Model& model,
                                                   ForceEvaluator& forces) {
  if (model.effects.damage || model.effects.plasticity) {
    throw std::invalid_argument(
        "the arkode integrator cannot run damage or plasticity: its stage evaluations would "
        "update bond history (use damped-euler, verlet or adr)");
  }
  return std::make_unique<ArkodeIntegrator>(model, forces, settings);
}

#else // LIBPD_HAVE_SUNDIALS

ButcherTableau sundials_erk_tableau(int) {
  throw std::runtime_error("libpd was built without SUNDIALS (LIBPD_WITH_SUNDIALS=OFF)");
}

ButcherTableau butcher_tableau(ArkodeTable) {
  throw std::runtime_error("libpd was built without SUNDIALS (LIBPD_WITH_SUNDIALS=OFF)");
}

std::unique_ptr<Integrator> make_arkode_integrator(const IntegratorSettings&, Model&,
                                                   ForceEvaluator&) {
  throw std::invalid_argument(
      "the arkode integrator needs SUNDIALS: rebuild with -DLIBPD_WITH_SUNDIALS=ON");
}

#endif // LIBPD_HAVE_SUNDIALS

} // namespace pd
