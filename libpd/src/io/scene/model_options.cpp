// The `effects` list and the `model` section: what the bond model simulates and how its bonds are
// corrected.
#include "bind.hpp"
#include "sections.hpp"

#include <algorithm>

namespace pd::scene {

namespace {

constexpr Key model_keys[] = {
    {.name = "bond_model",
     .type = Type::choice,
     .doc = "what the bonds carry: micro-elastic (bond-based, ν fixed by the dimension) or "
            "virtual-fibres (Olsson et al. 2021: arm tensions with a bulk/shear split, the "
            "material's E and ν)",
     .choices = enum_words<BondModel>,
     .bind = field_with_default<&ModelSpec::effects, &EffectSet::bond_model>()},
    {.name = "fibre_kernel_exponent",
     .type = Type::integer,
     .doc = "virtual fibres: exponent k of the kernel (1 − u²/α²)^k, eq. 112",
     .range = at_least_one,
     .bind = field_with_default<&ModelSpec::fibre_kernel, &FibreKernel::exponent>()},
    {.name = "fibre_kernel_alpha",
     .type = Type::number,
     .doc = "virtual fibres: α, a particle's horizon over its size h (eq. 112); on a lattice "
            "h = δ/α, so the arms are the lattice's bonds and α changes nothing",
     .range = positive,
     .bind = field_with_default<&ModelSpec::fibre_kernel, &FibreKernel::alpha>()},
    {.name = "fibre_size_neighbours",
     .type = Type::integer,
     .doc = "virtual fibres, particle files without h: a particle's size is half its mean "
            "distance to this many nearest particles (eq. 115)",
     .range = at_least_one,
     .bind = field_with_default<&ModelSpec::fibre_kernel, &FibreKernel::size_neighbours>()},
    {.name = "stretch",
     .type = Type::choice,
     .doc = "stretch measure (exact eq. 6, modified eq. 17, fast: no square root)",
     .choices = enum_words<StretchKind>,
     .bind = field_with_default<&ModelSpec::effects, &EffectSet::stretch>()},
    {.name = "surface_correction",
     .type = Type::choice,
     .doc = "bond stiffness correction near free surfaces",
     .choices = enum_words<SurfaceCorrection>,
     .bind = field_with_default<&ModelSpec::surface_correction>()},
    {.name = "volume_correction",
     .type = Type::choice,
     .doc = "bond quadrature weights: partial volume of cut cells (linear, exact), "
            "moment-matched lattice weights (moment), or weights that also match a cell's "
            "bending energy (gradient: stiffness on the bonds up to 2 spacings; solved per "
            "particle on a mesh body), or per-pair "
            "weights fitted to each particle's own neighbourhood (fitted: for sets that are not "
            "a lattice)",
     .choices = enum_words<VolumeCorrection>,
     .bind = field_with_default<&ModelSpec::volume_correction>()},
    {.name = "mirror_coupling",
     .type = Type::choice,
     .doc = "mirror supports: quadratic (support particles extrapolated from the body by the "
            "quadratics that vanish on the face: symmetric, exact for every quadratic field the "
            "clamp allows), consistent (odd images, forces sent back: symmetric) or copy (odd "
            "images, one-sided, not energy-conserving)",
     .choices = enum_words<MirrorCoupling>,
     .bind = field_with_default<&ModelSpec::mirror_coupling>()},
};

} // namespace

constinit const Section model_section{"under 'model'", model_keys};

void read_model_options(Reader& r, ModelSpec& model, Marks& marks) {
  for (const auto& [w, node] : r.names(marks.top, "effects")) {
    const auto& effect = effect_table[static_cast<std::size_t>(w)];
    model.effects.*effect.value = true;
    if (effect.value == &EffectSet::damping) {
      marks.damping_effect = node;
    }
  }

  const Fields f = r.section(marks.top, "model");
  marks.model = f;
  // Keys left out keep the values `model` holds: ModelSpec's defaults (model.hpp), so that an
  // empty scene builds the model a default ModelSpec does.
  r.read_bound(f, model);
}

void settle_mesh_corrections(Reader& r, ModelSpec& model, const Marks& marks) {
  if (!model.has_mesh_body() || model.effects.bond_model == BondModel::virtual_fibres) {
    return; // the fibre model gives a point cloud's particles weights of their own already
  }
  if (marks.model.find("surface_correction") == nullptr) {
    model.surface_correction = mesh_surface_correction;
  }
  const Entry* given = marks.model.find("volume_correction");
  if (given == nullptr) {
    model.volume_correction = mesh_volume_correction;
  } else if (const char* why = lattice_only(model.volume_correction)) {
    r.fail(given->at(),
           fmt::format("volume_correction '{}' needs a lattice ({}), and a mesh body is an "
                       "unstructured set",
                       name_of(model.volume_correction), why),
           fmt::format("remove 'volume_correction': with a mesh body it is '{}' (docs/scenes.md, "
                       "meshes)",
                       name_of(mesh_volume_correction)));
  }
}

void check_bond_model(Reader& r, const Scene& scene, const Marks& marks) {
  const ModelSpec& model = scene.model;
  if (model.effects.bond_model != BondModel::virtual_fibres) {
    for (std::size_t i = 0; i < model.bodies.size(); ++i) {
      if (model.bodies[i].points && !model.bodies[i].mesh) {
        r.fail(marks.body_box_nodes.at(i).front(),
               fmt::format("body '{}' is given as particles, which only the virtual-fibre model "
                           "runs (each particle its own size and horizon)",
                           model.bodies[i].name),
               "add 'bond_model: virtual-fibres' under 'model', or fill a box with the lattice");
      }
    }
    return;
  }
  const YAML::Node at = marks.model.find("bond_model")->at();
  if (model.dimension.dim == 1) {
    r.fail(at, "the virtual-fibre model needs dimension 2 or 3",
           "use the micro-elastic bond model in 1D");
  }
  if (model.effects.damage && !model.effects.plasticity) {
    r.fail(at,
           "fibre arms fail by plastic elongation (eq. 118): the 'damage' effect needs "
           "'plasticity' under the virtual-fibre model",
           "add 'plasticity' to 'effects' (and 'yield_stretch' to the materials)");
  }
  for (std::size_t i = 0; i < model.materials.size(); ++i) {
    if (model.effects.damage && !model.materials[i].elongation_limit) {
      r.fail(marks.material_nodes[i],
             fmt::format("effect 'damage' under the virtual-fibre model needs the arms' "
                         "elongation limit, but material '{}' has no elongation_limit",
                         model.materials[i].name),
             "add 'elongation_limit: δ_e' [m] to the material (eq. 118), or remove 'damage'");
    }
  }
  if (model.effects.stretch != StretchKind::exact) {
    r.fail(marks.model.find("stretch")->at(),
           "the virtual-fibre model uses the arms' engineering strain (eq. 110): 'stretch' must "
           "be 'exact'",
           "remove 'stretch' or set it to 'exact'");
  }
  if (model.surface_correction != SurfaceCorrection::none &&
      model.surface_correction != SurfaceCorrection::ghost) {
    r.fail(marks.model.find("surface_correction")->at(),
           fmt::format("surface correction '{}' is calibrated for bond-based bonds; the "
                       "virtual-fibre model takes 'ghost' or 'none'",
                       name_of(model.surface_correction)),
           "remove 'surface_correction' (ghost layers) or set it to 'none'");
  }
  const bool mirrors = std::any_of(model.supports.begin(), model.supports.end(),
                                   [](const SupportSpec& s) { return s.mirrors(); });
  if (mirrors && model.mirror_coupling == MirrorCoupling::consistent) {
    r.fail(marks.model.find("mirror_coupling")->at(),
           "mirror coupling 'consistent' weights bond-based bonds; the virtual-fibre model takes "
           "'quadratic' or 'copy'",
           "remove 'mirror_coupling' (quadratic) or set it to 'copy'");
  }
  if (scene.solver.integrator == IntegratorKind::static_solve) {
    const Fields& sol = marks.solver;
    r.fail(sol.has("integrator") ? sol.find("integrator")->at() : at,
           "the static solver assembles the bond-based linearised operator; the virtual-fibre "
           "model has no linearisation in libpd yet",
           "use 'integrator: adr' (adaptive dynamic relaxation) or damped-euler with a "
           "'steady:' section");
  }
}

} // namespace pd::scene
