// The `initial` section: a homogeneous initial displacement and a uniform initial velocity.
#include "bind.hpp"
#include "sections.hpp"

namespace pd::scene {

namespace {

constexpr Key initial_keys[] = {
    {.name = "displacement_gradient",
     .type = Type::matrix,
     .doc = "H of the initial displacement u0 = H (X - about), rows i, columns j = ∂u_i/∂X_j",
     .bind = field_with_default<&InitialSpec::displacement_gradient>()},
    {.name = "about",
     .type = Type::vector,
     .doc = "point of zero initial displacement",
     .unit = "m",
     .bind = field_with_default<&InitialSpec::about>()},
    {.name = "velocity",
     .type = Type::vector,
     .doc = "uniform initial velocity",
     .unit = "m/s",
     .bind = field_with_default<&InitialSpec::velocity>()},
};

} // namespace

constinit const Section initial_section{"under 'initial'", initial_keys};

void read_initial(Reader& r, InitialSpec& initial, const Marks& marks) {
  const Fields f = r.section(marks.top, "initial");
  r.read_bound(f, initial);
  if (f.has("velocity")) {
    r.check_in_space(f.find("velocity")->at(), f.label("velocity"), initial.velocity);
  }
}

} // namespace pd::scene
