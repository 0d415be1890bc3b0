// solver.integrator: static (issue 15): the one sparse solve refined by Newton agrees with
// dynamic relaxation's steady state, its operator is symmetric under consistent mirror coupling
// and is the linearisation of the force kernel the dynamic integrators use, and what it cannot
// do (plasticity) is refused; damage is tested with the load-stepping driver (quasi_static_test).
#include "libpd/app/run.hpp"
#include "libpd/io/scene.hpp"
#include "libpd/kernel/linear_operator.hpp"
#include "libpd/time/static_solver.hpp"

#include <cmath>
#include <cstdlib>
#include <fmt/format.h>
#include <gtest/gtest.h>
#ifdef _OPENMP
#include <omp.h>
#endif
#ifdef LIBPD_HAVE_SUITESPARSE
#include <SuiteSparse_config.h>
#endif
#include <random>
#include <regex>
#include <set>
#include <string>
#include <vector>

namespace {

/// A small 3D cantilever (λ = h/4 by default), clamped by a mirror at x = 0, tip load down.
std::string cantilever(const std::string& integrator, const std::string& coupling,
                       double spacing = 0.025) {
  return fmt::format(R"(title: small cantilever
dimension: 3
lattice:
  spacing: {}
materials:
  steel:
    youngs_modulus: 200e9
    density: 7850
bodies:
  - name: beam
    material: steel
    box: [[0, 0, 0], [0.6, 0.1, 0.1]]
  - name: clamp
    material: steel
    box: [[-0.1, 0, 0], [0, 0.1, 0.1]]
supports:
  - name: clamp
    box: [[-0.1, 0, 0], [0, 0.1, 0.1]]
    mirror: {{x: 0}}
loads:
  - name: tip
    box: [[0.575, 0, 0], [0.6, 0.1, 0.1]]
    value: [0, 0, -2e4]
model:
  mirror_coupling: {}
solver:
  integrator: {}
  end_time: 1e6
  steady:
    kinetic_tolerance: 1e-16
    force_tolerance: 1e-9
    check_every: 50
probes:
  - name: tip
    box: [[0.575, 0, 0], [0.6, 0.1, 0.1]]
    component: z
)",
                     spacing, coupling, integrator);
}

pd::RunOutcome run(const std::string& text) {
  const pd::Scene scene = pd::parse_scene(text, "cantilever.yaml");
  pd::RunOptions opt;
  opt.stop_on_interrupt = false;
  return pd::run_scene(scene, opt);
}

TEST(StaticSolver, AgreesWithDynamicRelaxation) {
  for (const std::string coupling : {"copy", "consistent"}) {
    SCOPED_TRACE(coupling);
    const pd::RunOutcome s = run(cantilever("static", coupling));
    const pd::RunOutcome a = run(cantilever("adr", coupling));
    ASSERT_EQ(s.result.status, pd::RunStatus::converged) << s.result.message;
    ASSERT_EQ(a.result.status, pd::RunStatus::converged) << a.result.message;
    const double ws = s.probes.at("tip"), wa = a.probes.at("tip");
    EXPECT_LT(ws, 0);
    EXPECT_NEAR(ws / wa, 1.0, 1e-6) << "static " << ws << ", adr " << wa;
    // The static run needs tens of force evaluations (two per CG iteration of each Newton step),
    // dynamic relaxation thousands.
    EXPECT_LT(s.result.force_evaluations, 100u);
    EXPECT_GT(a.result.force_evaluations, 1000u);
  }
}

TEST(StaticSolver, ConsistentMirrorCouplingGivesASymmetricOperator) {
  const pd::RunOutcome s = run(cantilever("static", "consistent"));
  std::smatch m;
  ASSERT_TRUE(std::regex_search(s.result.message, m,
                                std::regex(R"((\w+) operator, ‖VK−\(VK\)ᵀ‖/‖VK‖ = ([0-9.e+-]+))")))
      << s.result.message;
  EXPECT_EQ(m[1].str(), "symmetric");
  EXPECT_LE(std::stod(m[2]), 1e-12);
  // A Cholesky factorisation: CHOLMOD's, or Eigen's where libpd is built without SuiteSparse.
  EXPECT_TRUE(s.result.message.find("CHOLMOD supernodal LLT") != std::string::npos ||
              s.result.message.find("Eigen SimplicialLDLT") != std::string::npos)
      << s.result.message;
  const pd::Json* details = s.summary.find("integrator_details");
  ASSERT_NE(details, nullptr);
  EXPECT_GT(details->find("factor_bytes")->number().value_or(0), 0);
}

/// A short 3D beam (12λ × 3λ × 3λ, m = 3) of two materials (the far half 3× stiffer), clamped by
/// a 3λ block mirrored across x = 0 with consistent coupling, on a jittered lattice with varying
/// particle volumes, tensor surface and moment volume corrections: every way the assembled rows
/// could differ from the kernel's.
pd::Model jittered_two_material_clamped_beam() {
  constexpr double lambda = 1.0;
  pd::ModelSpec spec;
  spec.dimension.dim = 3;
  spec.lattice.spacing = lambda;
  spec.lattice.horizon_factor = 3.0;
  spec.lattice.position_jitter = 0.05; // the mirror images are found on a λ/4 grid
  spec.lattice.volume_variation = 0.2;
  spec.lattice.seed = 11;
  pd::Material soft, stiff;
  soft.youngs_modulus = 1e9;
  stiff.youngs_modulus = 3e9;
  soft.density = stiff.density = 1000;
  spec.materials = {soft, stiff};
  pd::BodySpec near, far;
  near.region.boxes = {pd::Box{{-3 * lambda, 0, 0}, {6 * lambda, 3 * lambda, 3 * lambda}}};
  far.region.boxes = {pd::Box{{6 * lambda, 0, 0}, {12 * lambda, 3 * lambda, 3 * lambda}}};
  far.material = 1;
  spec.bodies = {near, far};
  pd::SupportSpec clamp;
  clamp.name = "clamp";
  clamp.region.boxes = {pd::Box{{-3 * lambda, 0, 0}, {0, 3 * lambda, 3 * lambda}}};
  clamp.mirror[0] = true;
  clamp.mirror_at = {0, 0, 0};
  spec.supports = {clamp};
  spec.surface_correction = pd::SurfaceCorrection::tensor;
  spec.volume_correction = pd::VolumeCorrection::moment;
  spec.mirror_coupling = pd::MirrorCoupling::consistent;
  return pd::build_model(spec);
}

/// ‖K v − (−V ∂b/∂u v)‖ / ‖K v‖ for a random v on the unknowns, the dependants (mirror images,
/// ghosts, quadratic clamps) set from it as every integrator sets them.
double linearisation_mismatch(pd::Model& m) {
  const pd::StaticSystem k = pd::assemble_static_system(m);
  const std::size_t n = k.size();
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> dist(-1.0, 1.0);
  std::vector<double> v(n), kv(n);
  std::vector<double> yp(3 * m.size()), ym(3 * m.size()), bp(3 * m.size()), bm(3 * m.size());
  const double h = 1e-6 * m.spec.lattice.spacing;
  for (std::size_t d = 0; d < yp.size(); ++d) {
    yp[d] = ym[d] = m.particles.position[d / 3][d % 3];
  }
  for (std::size_t r = 0; r < n; ++r) {
    v[r] = dist(rng);
    yp[k.unknowns[r]] += h * v[r];
    ym[k.unknowns[r]] -= h * v[r];
  }
  const pd::LoadRamp full;
  pd::apply_constraints(m, full, 0.0, yp.data(), nullptr);
  pd::apply_constraints(m, full, 0.0, ym.data(), nullptr);
  k.multiply(v.data(), kv.data());
  auto forces = pd::make_constrained_force_evaluator(m);
  forces->compute(yp.data(), bp.data());
  forces->compute(ym.data(), bm.data());
  double diff = 0, norm = 0;
  for (std::size_t r = 0; r < n; ++r) {
    const std::size_t g = k.unknowns[r];
    const double fd = -m.particles.volume[g / 3] * (bp[g] - bm[g]) / (2 * h);
    diff += (fd - kv[r]) * (fd - kv[r]);
    norm += kv[r] * kv[r];
  }
  return std::sqrt(diff / norm);
}

TEST(StaticSolver, AssembledMatrixIsSymmetricAndTheKernelsLinearisation) {
  pd::Model m = jittered_two_material_clamped_beam();
  ASSERT_FALSE(m.constraints.empty());
  for (const pd::Constraint& c : m.constraints) {
    ASSERT_NE(c.mirror_of, pd::Constraint::no_mirror);
  }
  const pd::StaticSystem k = pd::assemble_static_system(m);
  ASSERT_GT(k.size(), 0u);
  EXPECT_LE(k.asymmetry(), 1e-12);
  // K v against the central difference of the forces every integrator gets (Simulation's
  // evaluator, which folds the mirror dependants' forces onto their masters).
  EXPECT_LE(linearisation_mismatch(m), 1e-8);
}

/// A concrete cantilever of span `length` m and section 0.1 × 0.1 m (λ = 0.02 m: five particles
/// through the depth), as a new user writes it: the library's defaults (ghost layers, gradient
/// weights, a quadratic mirror clamp), 1 kN/m on the top layer, the tip's centre probed.
std::string slender_cantilever(double length) {
  return fmt::format(R"(title: slender cantilever
dimension: 3
lattice:
  spacing: 0.02
materials:
  concrete:
    youngs_modulus: 20e9
    density: 2500
bodies:
  - name: beam
    material: concrete
    box: [[0, 0, 0], [{0}, 0.1, 0.1]]
  - name: clamp
    material: concrete
    box: [[-0.08, 0, 0], [0, 0.1, 0.1]]
supports:
  - name: clamp
    box: [[-0.08, 0, 0], [0, 0.1, 0.1]]
    mirror: {{x: 0}}
loads:
  - name: p
    box: [[0, 0, 0.08], [{0}, 0.1, 0.1]]
    type: per_length
    value: [0, 0, -1e3]
    measure: {0}
solver:
  integrator: static
probes:
  - name: tip
    box: [[{1}, 0.04, 0.04], [{0}, 0.06, 0.06]]
    component: z
)",
                     length, length - 0.02);
}

TEST(StaticSolver, AssembledMatrixIsTheKernelsLinearisationUnderTheDefaults) {
  pd::Model m = pd::build_model(pd::parse_scene(slender_cantilever(0.4), "slender.yaml"));
  ASSERT_GT(m.ghost_count, 0u);
  EXPECT_LE(linearisation_mismatch(m), 1e-8);
}

TEST(StaticSolver, NewtonConvergesOnASlenderCantileverUnderTheExactStretch) {
  // L/h = 20: the tip turns by 0.008 rad, whose second-order stretch left a residual 300× the
  // load after the linear solve and stalled modified Newton.
  const pd::RunOutcome s = run(slender_cantilever(2.0));
  ASSERT_EQ(s.result.status, pd::RunStatus::converged) << s.result.message;
  const pd::Json* details = s.summary.find("integrator_details");
  ASSERT_NE(details, nullptr);
  EXPECT_LE(*details->find("residual")->number(), 1e-6);
  // Euler–Bernoulli tip deflection pL⁴/8EI = 0.012 m; PD at x = L − λ/2 is within a few %.
  EXPECT_NEAR(s.probes.at("tip") / -0.012, 1.0, 0.03);
}

TEST(StaticSolver, SmallDisplacementsSolveTheLinearProblem) {
  // Under the exact stretch the slender cantilever's response is not linear in its load (the
  // turned bonds stiffen it); with solver.small_displacements it is, as in the linear-elastic
  // problem a finite-element reference solves (pd verify sets it).
  const auto tip = [](double load, bool small) {
    std::string text = slender_cantilever(2.0);
    text.replace(text.find("[0, 0, -1e3]"), 12, fmt::format("[0, 0, {}]", load));
    if (small) {
      text.replace(text.find("  integrator: static\n"), 21,
                   "  integrator: static\n  small_displacements: true\n");
    }
    const pd::RunOutcome s = run(text);
    EXPECT_EQ(s.result.status, pd::RunStatus::converged) << s.result.message;
    return s.probes.at("tip");
  };
  const double small = tip(-1e3, true), small_four = tip(-4e3, true);
  const double finite = tip(-1e3, false), finite_four = tip(-4e3, false);
  EXPECT_NEAR(small_four / (4 * small), 1.0, 1e-9);
  EXPECT_GT(std::abs(finite_four / (4 * finite) - 1.0), 1e-4); // what the check above would see
  EXPECT_NEAR(small / finite, 1.0, 0.01);                      // and the two agree while small
}

TEST(StaticSolver, LargeModelsWithGhostsSolveByCgPreconditionedWithTheRefittedOperator) {
  // 40 × 40 × 5 particles (24,000 unknowns, above preconditioned_from_unknowns) with the default
  // ghost layers, clamped by a quadratic mirror at x = 0: the factor is of P (the ghosts refitted
  // within 1.5 λ), K is applied matrix-free. A K that is not P's symmetric positive definite
  // partner would stop CG short of its tolerance (500 iterations); Newton then brings the kernel's
  // own residual to the tolerance, and the deflection must be the strip's.
  const std::string text = R"(title: clamped plate strip
dimension: 3
lattice:
  spacing: 0.02
materials:
  concrete:
    youngs_modulus: 20e9
    density: 2500
bodies:
  - name: plate
    material: concrete
    box: [[0, 0, 0], [0.8, 0.8, 0.1]]
  - name: clamp
    material: concrete
    box: [[-0.08, 0, 0], [0, 0.8, 0.1]]
supports:
  - name: clamp
    box: [[-0.08, 0, 0], [0, 0.8, 0.1]]
    mirror: {x: 0}
loads:
  - name: q
    box: [[0, 0, 0.08], [0.8, 0.8, 0.1]]
    type: per_area
    value: [0, 0, -1e4]
    measure: 0.64
solver:
  integrator: static
probes:
  - name: edge
    box: [[0.78, 0.38, 0.04], [0.8, 0.42, 0.06]]
    component: z
)";
  const pd::RunOutcome s = run(text);
  ASSERT_EQ(s.result.status, pd::RunStatus::converged) << s.result.message;
  const pd::Json* details = s.summary.find("integrator_details");
  ASSERT_NE(details, nullptr);
  EXPECT_EQ(details->find("unknowns")->number().value_or(0), 24000);
  EXPECT_NE(details->find("preconditioner")->dump().find("P (refit"), std::string::npos);
  EXPECT_LT(*details->find("linear_cg_iterations")->number(), 200);
  EXPECT_LE(*details->find("residual")->number(), 1e-6);
  // A cantilever strip under q: qL⁴/8EI = 1e4 · 0.8⁴ · 12 / (8 · 20e9 · 0.1³) = 3.1e-4 m; the
  // plate is stiffer across its width (ν), PD within a few % of that.
  EXPECT_LT(s.probes.at("edge"), -2.5e-4);
  EXPECT_GT(s.probes.at("edge"), -3.3e-4);
}

#ifdef _OPENMP
TEST(StaticSolver, GivesBitwiseTheSameResultOnOneAndTwoThreads) {
  // The factor (about 12 M entries) is large enough that OpenBLAS splits its calls between
  // threads when it may: the triangular solves did, and the displacements differed in the last
  // bits between 1 and 2 threads (sparse_factorisation.cpp now keeps CHOLMOD's BLAS on one).
  const std::string text = cantilever("static", "consistent", 0.0125);
  const int saved = omp_get_max_threads();
  std::vector<pd::RunOutcome> runs;
  for (const int threads : {1, 2}) {
    omp_set_num_threads(threads);
    runs.push_back(run(text));
  }
  omp_set_num_threads(saved);
  ASSERT_EQ(runs[0].result.status, pd::RunStatus::converged) << runs[0].result.message;
  ASSERT_EQ(runs[1].result.status, pd::RunStatus::converged) << runs[1].result.message;
  EXPECT_EQ(runs[0].probes.at("tip"), runs[1].probes.at("tip"));
  EXPECT_EQ(runs[0].summary.find("integrator_details")->find("residual")->number(),
            runs[1].summary.find("integrator_details")->find("residual")->number());
}
#endif

TEST(StaticSolver, RefusesAFactorLargerThanTheMemoryItMayUse) {
  // At λ = h/8, 16 MiB holds the cantilever's model (9.5 MiB estimated with the integrator and
  // the build's transients) but not its factor (93 MiB): the solve stops before the numeric
  // factorisation, naming the sizes and what to do instead.
  ::setenv("PD_MEMORY_LIMIT", "16M", 1);
  std::string message;
  try {
    const pd::RunOutcome o = run(cantilever("static", "consistent", 0.0125));
    message = o.result.message;
  } catch (const std::exception& e) {
    message = e.what();
  }
  ::unsetenv("PD_MEMORY_LIMIT");
  if (message.find("CHOLMOD") == std::string::npos &&
      message.find("Cholesky factor would take") == std::string::npos) {
    GTEST_SKIP() << "built without SuiteSparse: the size check needs CHOLMOD's analysis: "
                 << message;
  }
  EXPECT_NE(message.find("the Cholesky factor would take"), std::string::npos) << message;
  EXPECT_NE(message.find("integrator: adr"), std::string::npos) << message;
}

#ifdef LIBPD_HAVE_SUITESPARSE
// Issue 38, item 10: the refusal above threw out of the factorisation's constructor, whose
// destructor then never ran: the symbolic factor and CHOLMOD's workspace leaked (673 KB under
// the sanitizers). Every CHOLMOD allocation is counted through SuiteSparse's allocator hooks.
namespace cholmod_count {
std::set<void*>& live() {
  static std::set<void*> s;
  return s;
}
void* counted(void* p) {
  if (p != nullptr) {
    live().insert(p);
  }
  return p;
}
void* malloc_(std::size_t n) {
  return counted(std::malloc(n));
}
void* calloc_(std::size_t n, std::size_t m) {
  return counted(std::calloc(n, m));
}
void* realloc_(void* p, std::size_t n) {
  void* q = std::realloc(p, n);
  if (q != nullptr) {
    live().erase(p);
    live().insert(q);
  }
  return q;
}
void free_(void* p) {
  live().erase(p);
  std::free(p);
}
} // namespace cholmod_count

TEST(StaticSolver, FreesEveryCholmodAllocationWhenItRefusesAFactor) {
  const auto saved = SuiteSparse_config;
  SuiteSparse_config.malloc_func = cholmod_count::malloc_;
  SuiteSparse_config.calloc_func = cholmod_count::calloc_;
  SuiteSparse_config.realloc_func = cholmod_count::realloc_;
  SuiteSparse_config.free_func = cholmod_count::free_;
  ::setenv("PD_MEMORY_LIMIT", "16M", 1);
  std::string message;
  try {
    message = run(cantilever("static", "consistent", 0.0125)).result.message;
  } catch (const std::exception& e) {
    message = e.what();
  }
  ::unsetenv("PD_MEMORY_LIMIT");
  SuiteSparse_config = saved;
  EXPECT_NE(message.find("the Cholesky factor would take"), std::string::npos) << message;
  EXPECT_EQ(cholmod_count::live().size(), 0u) << "CHOLMOD allocations never freed";
}
#endif

TEST(StaticSolver, RefusesPlasticity) {
  std::string text = cantilever("static", "copy");
  text.replace(text.find("    density: 7850\n"), 18,
               "    density: 7850\n    yield_stretch: 1e-3\n");
  text += "effects: [plasticity]\n";
  EXPECT_THROW(run(text), std::invalid_argument);
}

} // namespace
