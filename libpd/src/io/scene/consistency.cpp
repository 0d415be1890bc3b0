// Checks between sections that need no lattice: effects against the materials and the solver,
// solver options against each other, output against probes.
#include "sections.hpp"

#include <algorithm>

namespace pd::scene {

namespace {

/// Each effect needs its material constants; constants without their effect are worth a warning.
void check_materials(Reader& r, const ModelSpec& model, const Marks& marks) {
  const auto& material_nodes = marks.material_nodes;
  for (std::size_t i = 0; i < model.materials.size(); ++i) {
    const Material& m = model.materials[i];
    // Fibre arms fail by plastic elongation instead (check_bond_model).
    const bool fibres = model.effects.bond_model == BondModel::virtual_fibres;
    if (model.effects.damage && !fibres && !m.fracture_energy && !m.critical_stretch) {
      r.fail(material_nodes[i],
             fmt::format("effect 'damage' needs a critical stretch, but material '{}' has neither "
                         "fracture_energy nor critical_stretch",
                         m.name),
             fmt::format("add 'fracture_energy: G0' [J/m²] or 'critical_stretch: s0' to material "
                         "'{}', or remove 'damage' from effects",
                         m.name));
    }
    if (model.effects.plasticity && !m.yield_stretch) {
      r.fail(material_nodes[i],
             fmt::format("effect 'plasticity' needs a yield stretch, but material '{}' has no "
                         "yield_stretch",
                         m.name),
             fmt::format("add 'yield_stretch: s_Y' to material '{}', or remove 'plasticity' from "
                         "effects",
                         m.name));
    }
    const Fields& f = marks.material_fields[i];
    for (const char* key : {"fracture_energy", "critical_stretch"}) {
      if (f.has(key) && !model.effects.damage) {
        r.warn(f.find(key)->name,
               fmt::format("'{}' of material '{}' is unused: the 'damage' effect is not listed",
                           key, m.name));
      }
    }
    if (f.has("elongation_limit") && !(fibres && model.effects.damage)) {
      r.warn(f.find("elongation_limit")->name,
             fmt::format("'elongation_limit' of material '{}' is unused: only the virtual-fibre "
                         "model with the 'damage' effect reads it",
                         m.name));
    }
    if (f.has("yield_stretch") && !model.effects.plasticity) {
      r.warn(f.find("yield_stretch")->name,
             fmt::format("'yield_stretch' of material '{}' is unused: the 'plasticity' effect is "
                         "not listed",
                         m.name));
    }
    const bool used = std::any_of(model.bodies.begin(), model.bodies.end(), [&](const BodySpec& b) {
      return b.material == static_cast<int>(i);
    });
    if (!used) {
      r.warn(material_nodes[i], fmt::format("material '{}' is not used by any body", m.name));
    }
  }
}

void check_solver(Reader& r, const Scene& scene, const Marks& marks) {
  const ModelSpec& model = scene.model;
  const SolverSpec& solver = scene.solver;
  const Fields& sol = marks.solver;
  if (solver.damping > 0 && !model.effects.damping) {
    r.fail(sol.find("damping")->at(),
           fmt::format("'solver.damping' is {} but the 'damping' effect is not listed",
                       format_number(solver.damping)),
           marks.top.has("effects") ? "add 'damping' to 'effects', or set 'damping: 0'"
                                    : "add 'effects: [damping]', or set 'damping: 0'");
  }
  if (model.effects.damping && !(solver.damping > 0)) {
    r.fail(marks.damping_effect, "effect 'damping' is listed but 'solver.damping' is 0",
           "set 'damping: c_v' [kg/(m³ s)] > 0 under 'solver', or remove 'damping' from effects");
  }
  if ((solver.integrator == IntegratorKind::euler_cromer ||
       solver.integrator == IntegratorKind::verlet) &&
      solver.damping > 0) {
    r.fail(sol.find("integrator")->at(),
           fmt::format("integrator '{}' has no damping, but 'solver.damping' is {}",
                       sol.find("integrator")->value.Scalar(), format_number(solver.damping)),
           "use 'integrator: damped-euler' or 'arkode', or set 'damping: 0' and remove the "
           "'damping' effect");
  }
  if (solver.integrator == IntegratorKind::adr && solver.damping > 0) {
    r.warn(sol.find("damping")->at(),
           "'solver.damping' is ignored by the adr integrator: adaptive dynamic relaxation "
           "computes its damping every step (Kilic & Madenci 2010)");
  }
  if (solver.integrator == IntegratorKind::arkode) {
    const YAML::Node at = sol.find("integrator")->at();
    if (!arkode_available()) {
      r.fail(at, "integrator 'arkode' is not available: libpd was built without SUNDIALS",
             "rebuild with -DLIBPD_WITH_SUNDIALS=ON (needs libsundials-dev 6), or choose "
             "another integrator");
    }
    if (model.effects.damage || model.effects.plasticity) {
      r.fail(at,
             fmt::format("integrator 'arkode' cannot run the '{}' effect: its trial stage "
                         "evaluations would update bond history",
                         model.effects.damage ? "damage" : "plasticity"),
             "use damped-euler, verlet or adr for damage and plasticity");
    }
    if (solver.arkode.adaptive && (solver.arkode.table == ArkodeTable::knoth_wolke ||
                                   solver.arkode.table == ArkodeTable::rk4)) {
      const Fields ak = r.section(sol, "arkode");
      r.fail(ak.find("adaptive")->at(),
             fmt::format("table '{}' has no embedded method, so it cannot adapt its steps",
                         to_string(solver.arkode.table)),
             "use 'adaptive: false', or a table with an embedding (heun-euler, bogacki-shampine, "
             "zonneveld, cash-karp, fehlberg, dormand-prince)");
    }
  } else if (sol.has("arkode")) {
    r.warn(sol.find("arkode")->name, "'solver.arkode' is ignored: the integrator is not 'arkode'");
  }
  // The static solver stops by itself after one solve; the explicit schemes need a stop.
  if (solver.integrator != IntegratorKind::static_solve && !solver.end_time &&
      !solver.steady.enabled) {
    r.fail(sol.anchor,
           "neither 'solver.end_time' nor 'solver.steady' is given: the run would not "
           "stop",
           "add 'end_time: T' [s] or a 'steady:' section under 'solver'");
  }
  if (sol.has("load_steps") &&
      (solver.integrator != IntegratorKind::static_solve || !model.effects.damage)) {
    r.fail(sol.find("load_steps")->at(),
           "'solver.load_steps' levels the load of a quasi-static fracture run, which needs "
           "'integrator: static' and the damage effect",
           solver.integrator != IntegratorKind::static_solve
               ? "use 'integrator: static' (a ramp in time is 'ramp_time')"
               : "add 'damage' to 'effects', or remove 'load_steps' (an elastic static solve is "
                 "one solve at the full load)");
  }
  if (solver.small_displacements && !model.effects.elastic_bonds_only()) {
    r.fail(sol.find("small_displacements")->at(),
           fmt::format(
               "'solver.small_displacements' linearises elastic bonds; it cannot run {}",
               model.effects.bond_model == BondModel::virtual_fibres
                   ? "the virtual-fibre model"
                   : (model.effects.damage ? "the 'damage' effect" : "the 'plasticity' effect")),
           "remove 'small_displacements', or the effect");
  }
  if (solver.end_time && solver.ramp_time > *solver.end_time) {
    r.warn(sol.find("ramp_time")->at(),
           fmt::format("'solver.ramp_time' ({} s) exceeds 'solver.end_time' ({} s): the full load "
                       "is never reached",
                       format_number(solver.ramp_time), format_number(*solver.end_time)));
  }
  if (scene.output.history_every > 0 && scene.probes.empty()) {
    r.warn(marks.output.find("history_every")->at(),
           "'output.history_every' is set but there are no probes: no history is written");
  }
}

} // namespace

void check_unique(const Reader& r, std::map<std::string, YAML::Node>& seen, const std::string& name,
                  const YAML::Node& node, std::string_view kind) {
  if (name.empty()) {
    r.fail(node, fmt::format("the name of a {} is empty", kind), "give every item a unique name");
  }
  const auto [it, inserted] = seen.emplace(name, node);
  if (!inserted) {
    r.fail(node, fmt::format("duplicate {} name '{}'", kind, name),
           fmt::format("{} names must be unique; '{}' is already used on line {}", kind, name,
                       source_mark(it->second).line));
  }
}

namespace {

/// A reaction probe names a support that holds particles by value; a damage probe needs damage.
void check_probes(const Reader& r, const Scene& scene, const Marks& marks) {
  const auto& supports = scene.model.supports;
  for (const auto& [name, node] : marks.reaction_supports) {
    const auto s = std::find_if(supports.begin(), supports.end(),
                                [&](const SupportSpec& x) { return x.name == name; });
    if (s == supports.end()) {
      std::vector<std::string_view> names;
      for (const SupportSpec& x : supports) {
        names.push_back(x.name);
      }
      r.fail(node, fmt::format("probe names unknown support '{}'", name),
             suggestion(name, names, "supports defined"));
    }
    if (s->mirrors() || s->symmetric()) {
      r.fail(node,
             fmt::format("support '{}' is a mirror or symmetry support, whose reaction is not "
                         "recorded",
                         name),
             "a reaction probe reads a support with 'fixed' or 'displacement' components");
    }
  }
  for (std::size_t i = 0; i < supports.size(); ++i) {
    if (supports[i].symmetric() && scene.model.surface_correction != SurfaceCorrection::ghost) {
      r.fail(marks.support_nodes[i],
             fmt::format("symmetry support '{}' needs the ghost surface correction: the sites "
                         "beyond the plane are ghosts that take their images' displacements",
                         supports[i].name),
             "remove 'model.surface_correction' (the default is ghost) or write 'ghost'");
    }
  }
  if (scene.stop_when.enabled() &&
      std::none_of(scene.probes.begin(), scene.probes.end(),
                   [&](const ProbeSpec& p) { return p.name == scene.stop_when.probe; })) {
    std::vector<std::string_view> names;
    for (const ProbeSpec& p : scene.probes) {
      names.push_back(p.name);
    }
    r.fail(marks.stop_when_probe,
           fmt::format("'solver.stop_when' watches unknown probe '{}'", scene.stop_when.probe),
           suggestion(scene.stop_when.probe, names, "probes defined"));
  }
  for (const auto& [quantity, node] : marks.probe_quantities) {
    if (quantity == ProbeSpec::Quantity::damage && !scene.model.effects.damage) {
      r.fail(node, "a damage probe needs the damage effect", "add 'damage' to 'effects'");
    }
  }
}

} // namespace

void check_consistency(Reader& r, const Scene& scene, const Marks& marks) {
  check_materials(r, scene.model, marks);
  check_solver(r, scene, marks);
  check_probes(r, scene, marks);
  check_bond_model(r, scene, marks);
}

} // namespace pd::scene
