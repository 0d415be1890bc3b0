// The `output` section: which files a run writes, and how often.
#include "bind.hpp"
#include "sections.hpp"

namespace pd::scene {

namespace {

constexpr Key output_keys[] = {
    {.name = "vtu",
     .type = Type::boolean,
     .doc = "write VTU files of the particles",
     .bind = field_with_default<&OutputSpec::vtu>()},
    {.name = "vtu_every",
     .type = Type::integer,
     .doc = "steps between VTU files; 0 = final state only",
     .unit = "steps",
     .range = non_negative,
     .bind = field_with_default<&OutputSpec::vtu_every>()},
    {.name = "history_every",
     .type = Type::integer,
     .doc = "steps between rows of the probe history; 0 = no history",
     .unit = "steps",
     .range = non_negative,
     .bind = field_with_default<&OutputSpec::history_every>()},
};

} // namespace

constinit const Section output_section{"under 'output'", output_keys};

void read_output(Reader& r, OutputSpec& output, Marks& marks) {
  marks.output = r.section(marks.top, "output");
  r.read_bound(marks.output, output);
}

} // namespace pd::scene
