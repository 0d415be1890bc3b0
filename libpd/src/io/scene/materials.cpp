// The `materials` map: engineering constants of each material, by name.
#include "bind.hpp"
#include "sections.hpp"

namespace pd::scene {

namespace {

constexpr Key material_keys[] = {
    {.name = "youngs_modulus",
     .type = Type::number,
     .doc = "Young's modulus E",
     .unit = "Pa",
     .range = positive,
     .example = "200e9",
     .need = Need::required,
     .range_hint = "E must be positive, e.g. 200e9 for steel",
     .bind = field<&Material::youngs_modulus>()},
    {.name = "poisson_ratio",
     .type = Type::number,
     .doc = "ν as measured; bond-based PD fixes ν (1/4 in 3D and plane strain, 1/3 in plane "
            "stress) and takes that value when none is given, other values only cause a "
            "warning (and `pd verify` refuses them: PD and FE would solve different "
            "problems); model.bond_model: virtual-fibres honours it",
     .range = {-1, 0.5, true, true},
     .range_hint = "a stable isotropic material has -1 < ν < 0.5",
     .bind = field_with_default<&Material::poisson_ratio>()},
    {.name = "density",
     .type = Type::number,
     .doc = "mass density ρ",
     .unit = "kg/m³",
     .range = positive,
     .example = "7850",
     .need = Need::required,
     .range_hint = "ρ must be positive, e.g. 7850 for steel",
     .bind = field<&Material::density>()},
    {.name = "fracture_energy",
     .type = Type::number,
     .doc = "critical energy release rate G0; the critical stretch follows from it (eq. 11)",
     .unit = "J/m²",
     .range = positive,
     .example = "100",
     .group = 1,
     .show = Show::commented,
     .bind = field<&Material::fracture_energy>()},
    {.name = "critical_stretch",
     .type = Type::number,
     .doc = "critical stretch s0, instead of fracture_energy",
     .range = positive,
     .example = "1e-3",
     .group = 1,
     .show = Show::commented,
     .bind = field<&Material::critical_stretch>()},
    {.name = "yield_stretch",
     .type = Type::number,
     .doc = "yield stretch s_Y of micro-plastic bonds (eq. 15)",
     .range = positive,
     .example = "5e-4",
     .show = Show::commented,
     .bind = field<&Material::yield_stretch>()},
    {.name = "elongation_limit",
     .type = Type::number,
     .doc = "virtual fibres with damage: plastic elongation δ_e at which an arm fails "
            "(Olsson et al. 2021, eq. 118)",
     .unit = "m",
     .range = positive,
     .example = "4e-5",
     .show = Show::commented,
     .bind = field<&Material::elongation_limit>()},
    {.name = "stiffness_factor",
     .type = Type::number,
     .doc = "multiplies the micromodulus (deliberately stiff regions)",
     .range = positive,
     .bind = field_with_default<&Material::stiffness_factor>()},
};

/// Bond-based PD represents one Poisson ratio per setting; another one is accepted (E is what
/// the model matches) but is worth a warning.
void warn_unrepresented_poisson_ratio(Reader& r, const Fields& f, const ModelDimension& d,
                                      double nu) {
  const auto represented = bond_based_poisson_ratio(d);
  if (represented && std::abs(nu - *represented) > 1e-9) {
    r.warn(f.find("poisson_ratio")->at(),
           fmt::format("bond-based PD fixes ν = {} here; E is matched{}; ν = {} is not "
                       "represented",
                       d.dim == 2 && d.plane == PlaneMode::plane_stress ? "1/3" : "1/4",
                       d.dim == 3 ? " (in 3D that equals matching the bulk "
                                    "modulus, Miranda eq. 8)"
                                  : "",
                       format_number(nu)));
  }
}

} // namespace

constinit const Section material_section{"in a material", material_keys};

/// Materials, in file order.
void read_materials(Reader& r, ModelSpec& model, Marks& marks) {
  const Entry* e = r.lookup(marks.top, "materials");
  if (!e->value.IsMap() || e->value.size() == 0) {
    r.fail(e->at(),
           fmt::format("'materials' must be a map of material name → properties, got {}",
                       e->value.IsMap() ? "an empty map" : describe(e->value)),
           "write e.g. 'materials:' then an indented 'steel:' with youngs_modulus and density "
           "under it");
  }
  if (e->value.size() > std::numeric_limits<std::uint16_t>::max()) {
    r.fail(e->value, "too many materials (at most 65535)", "merge materials with equal values");
  }
  for (auto it = e->value.begin(); it != e->value.end(); ++it) {
    const YAML::Node key = it->first;
    if (!key.IsScalar() || key.Scalar().empty()) {
      r.fail(key, "a material name must be a non-empty word, got " + describe(key),
             "write the name followed by ':', e.g. 'steel:'");
    }
    for (const YAML::Node& previous : marks.material_nodes) {
      if (previous.Scalar() == key.Scalar()) {
        r.fail(key, fmt::format("duplicate material name '{}'", key.Scalar()),
               fmt::format("material names must be unique; '{}' is already defined on line {}",
                           key.Scalar(), source_mark(previous).line));
      }
    }
    const std::string owner = fmt::format("material '{}'", key.Scalar());
    const Fields f = r.open(it->second, key, material_section, {}, owner, owner);
    Material mat;
    mat.name = key.Scalar();
    r.read_bound(f, mat);
    // The fibre model honours ν (physics/fibres.hpp); bond-based PD cannot. A bond-based
    // material without ν takes the one the model represents, so that every solver reading the
    // scene (PD, and pd-fem --scene for `pd verify`) solves the same problem.
    if (model.effects.bond_model == BondModel::micro_elastic) {
      if (f.has("poisson_ratio")) {
        warn_unrepresented_poisson_ratio(r, f, model.dimension, mat.poisson_ratio);
      } else if (const auto represented = bond_based_poisson_ratio(model.dimension)) {
        mat.poisson_ratio = *represented;
      }
    }
    model.materials.push_back(std::move(mat));
    marks.material_nodes.push_back(key);
    marks.material_fields.push_back(f);
  }
}

} // namespace pd::scene
