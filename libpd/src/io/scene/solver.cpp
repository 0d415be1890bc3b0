// The `solver` section with its `steady` and `arkode` subsections: time integration and stopping.
#include "bind.hpp"
#include "sections.hpp"

namespace pd::scene {

namespace {

using Steady = SteadyStateCriterion;

constexpr Key steady_keys[] = {
    {.name = "kinetic_tolerance",
     .type = Type::number,
     .doc = "converged when kinetic energy ≤ this × strain energy",
     .range = positive,
     .bind = field_with_default<&Steady::kinetic_tolerance>()},
    {.name = "force_tolerance",
     .type = Type::number,
     .doc = "and residual force ≤ this × reference force (loads, or support reactions)",
     .range = positive,
     .bind = field_with_default<&Steady::force_tolerance>()},
    {.name = "check_every",
     .type = Type::integer,
     .doc = "steps between convergence checks",
     .unit = "steps",
     .range = at_least_one,
     .bind = field_with_default<&Steady::check_every>()},
};

constexpr Key arkode_keys[] = {
    {.name = "table",
     .type = Type::choice,
     .doc = "Butcher table of ERKStep (SUNDIALS 6.4.1): those that compute correctly with it; "
            "heun-euler and rk4 run with the issue-311 work-around",
     .choices = enum_words<ArkodeTable>,
     .bind = field_with_default<&ArkodeSpec::table>()},
    {.name = "adaptive",
     .type = Type::boolean,
     .doc = "false: fixed steps of solver.dt; true: error-controlled steps within each solver.dt "
            "(tables with an embedding only)",
     .bind = field_with_default<&ArkodeSpec::adaptive>()},
    {.name = "rtol",
     .type = Type::number,
     .doc = "relative tolerance of the adaptive error test",
     .range = positive,
     .bind = field_with_default<&ArkodeSpec::rtol>()},
    {.name = "atol",
     .type = Type::number,
     .doc = "absolute tolerance of the adaptive error test, on u [m] and v [m/s]",
     .range = positive,
     .bind = field_with_default<&ArkodeSpec::atol>()},
};

constexpr Key solver_keys[] = {
    {.name = "integrator",
     .type = Type::choice,
     .doc = "time integrator; damped-euler and arkode apply kinematic damping, adr computes its "
            "own",
     .choices = enum_words<IntegratorKind>,
     .bind = field_with_default<&SolverSpec::integrator>()},
    {.name = "dt",
     .type = Type::number_or_auto,
     .doc = "time step; auto = safety × the stable time step (Miranda eq. 31)",
     .unit = "s",
     .range = positive,
     .fallback = "auto",
     .bind = field<&SolverSpec::dt>()},
    {.name = "safety",
     .type = Type::number,
     .doc = "factor on the stable time step when dt is auto",
     .range = {0, 1, true, false},
     .range_hint = "use a factor in (0, 1], e.g. 0.8; above 1 the explicit scheme is unstable",
     .bind = field_with_default<&SolverSpec::safety>()},
    {.name = "end_time",
     .type = Type::number,
     .doc = "simulated time at which the run stops (give end_time, steady or both)",
     .unit = "s",
     .range = positive,
     .example = "0.05",
     .bind = field<&SolverSpec::end_time>()},
    {.name = "ramp_time",
     .type = Type::number,
     .doc = "loads and prescribed displacements grow linearly over this time (eq. 33)",
     .unit = "s",
     .range = non_negative,
     .bind = field_with_default<&SolverSpec::ramp_time>()},
    {.name = "damping",
     .type = Type::number,
     .doc = "kinematic damping coefficient c_v (needs the damping effect)",
     .unit = "kg/(m³ s)",
     .range = non_negative,
     .bind = field_with_default<&SolverSpec::damping>()},
    {.name = "max_steps",
     .type = Type::integer,
     .doc = "hard limit on the number of steps",
     .unit = "steps",
     .range = at_least_one,
     .bind = field_with_default<&SolverSpec::max_steps>()},
    {.name = "blowup_displacement",
     .type = Type::number,
     .doc = "a larger displacement stops the run as unstable; 0 = bounding-box diagonal",
     .unit = "m",
     .range = non_negative,
     .bind = field_with_default<&SolverSpec::blowup_displacement>()},
    {.name = "load_steps",
     .type = Type::integer,
     .doc = "integrator static with damage (quasi-static fracture): the prescribed displacements "
            "and loads grow in this many equal levels, each solved to equilibrium with the "
            "most overstretched bond broken first and the rest solved again; the failure load "
            "does not depend on it",
     .unit = "levels",
     .range = at_least_one,
     .show = Show::commented,
     .bind = field_with_default<&SolverSpec::load_steps>()},
    {.name = "small_displacements",
     .type = Type::boolean,
     .doc = "true: bond forces linearised at the reference configuration, the linear-elastic "
            "problem a finite-element reference solves (pd verify sets it); false: each bond's "
            "stretch measure at any rotation. Elastic bond-based models only",
     .show = Show::commented,
     .bind = field_with_default<&SolverSpec::small_displacements>()},
    {.name = "steady",
     .type = Type::section,
     .doc = "steady-state stop; its presence (even empty) enables it",
     .show = Show::commented,
     .section = &steady_section},
    {.name = "arkode",
     .type = Type::section,
     .doc = "options of the arkode integrator (SUNDIALS ARKode ERKStep)",
     .show = Show::commented,
     .section = &arkode_section},
    {.name = "stop_when",
     .type = Type::section,
     .doc = "a failure criterion on a probe: the run stops with status 'failed' and exit code 0",
     .show = Show::commented,
     .section = &stop_when_section},
};

constexpr Key stop_when_keys[] = {
    {.name = "probe",
     .type = Type::string,
     .doc = "name of the probe watched, checked after every step",
     .example = "reaction",
     .need = Need::required},
    {.name = "drops_below",
     .type = Type::number,
     .doc = "stop once |value| falls below this fraction of its peak |value| so far and bonds "
            "have broken since that peak (a reaction after the specimen broke; a swing of the "
            "probe with no bond broken is not a failure, and without damage nothing can fail)",
     .range = {0, 1, true, true},
     .example = "0.5",
     .need = Need::one_of,
     .group = 1},
    {.name = "exceeds",
     .type = Type::number,
     .doc = "stop once |value| exceeds this level (damage, a displacement), in the probe's unit",
     .range = positive,
     .example = "0.3",
     .need = Need::one_of,
     .group = 1,
     .show = Show::commented},
};

} // namespace

constinit const Section steady_section{"under 'solver.steady'", steady_keys};
constinit const Section arkode_section{"under 'solver.arkode'", arkode_keys};
constinit const Section solver_section{"under 'solver'", solver_keys};
constinit const Section stop_when_section{"under 'solver.stop_when'", stop_when_keys};

void read_solver(Reader& r, SolverSpec& solver, StopWhenSpec& stop_when, Marks& marks) {
  marks.solver = r.section(marks.top, "solver");
  r.read_bound(marks.solver, solver);
  if (marks.solver.has("steady")) {
    const Fields steady = r.section(marks.solver, "steady");
    solver.steady.enabled = true;
    r.read_bound(steady, solver.steady);
  }
  if (marks.solver.has("arkode")) {
    r.read_bound(r.section(marks.solver, "arkode"), solver.arkode);
  }
  if (marks.solver.has("stop_when")) {
    const Fields f = r.section(marks.solver, "stop_when");
    stop_when.probe = *r.string(f, "probe");
    marks.stop_when_probe = f.find("probe")->at();
    stop_when.drops_below = r.number(f, "drops_below").value_or(0.0);
    stop_when.exceeds = r.number(f, "exceeds").value_or(0.0);
  }
}

} // namespace pd::scene
