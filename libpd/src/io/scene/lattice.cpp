// The `lattice` section: spacing, horizon and the lattice's anchor and irregularities.
#include "bind.hpp"
#include "sections.hpp"

namespace pd::scene {

namespace {

constexpr Key lattice_keys[] = {
    {.name = "spacing",
     .type = Type::number,
     .doc = "lattice spacing λ",
     .unit = "m",
     .range = positive,
     .example = "0.01",
     .need = Need::required,
     .bind = field<&ModelSpec::lattice, &LatticeSpec::spacing>()},
    {.name = "horizon_factor",
     .type = Type::number,
     .doc = "m = δ/λ, the horizon in spacings (2√3 = 3.4641016151377544)",
     .range = at_least_one,
     .range_hint = "a horizon below one spacing has no bonds; use m ≥ 1 (typically 3.015 or 2√3)",
     .bind = field_with_default<&ModelSpec::lattice, &LatticeSpec::horizon_factor>()},
    {.name = "convention",
     .type = Type::choice,
     .doc = "particles at cell centres (surfaces λ/2 outside) or on lattice nodes",
     .choices = enum_words<LatticeConvention>,
     .bind = field_with_default<&ModelSpec::lattice, &LatticeSpec::convention>()},
    {.name = "origin",
     .type = Type::vector,
     .doc = "anchor of the lattice shared by all bodies",
     .unit = "m",
     .bind = field_with_default<&ModelSpec::lattice, &LatticeSpec::origin>()},
    {.name = "horizon_rule",
     .type = Type::choice,
     .doc = "bonds of length exactly δ: kept (inclusive) or dropped (strict)",
     .choices = enum_words<HorizonRule>,
     .bind = field_with_default<&ModelSpec::horizon_rule>()},
    {.name = "position_jitter",
     .type = Type::number,
     .doc = "random particle displacement, as a fraction of λ",
     .range = {0, 0.45, false, false},
     .bind = field_with_default<&ModelSpec::lattice, &LatticeSpec::position_jitter>()},
    {.name = "volume_variation",
     .type = Type::number,
     .doc = "random relative variation of particle volumes",
     .range = {0, 0.9, false, false},
     .bind = field_with_default<&ModelSpec::lattice, &LatticeSpec::volume_variation>()},
    {.name = "seed",
     .type = Type::integer,
     .doc = "seed of the jitter and volume variation",
     .range = non_negative,
     .bind = field_with_default<&ModelSpec::lattice, &LatticeSpec::seed>()},
};

} // namespace

constinit const Section lattice_section{"under 'lattice'", lattice_keys};

void read_lattice(Reader& r, ModelSpec& model, Marks& marks) {
  marks.lattice = r.section(marks.top, "lattice");
  r.read_bound(marks.lattice, model);
}

} // namespace pd::scene
