// Scene files: the schema tables, the YAML reader driven by them, and the template they generate.
//
// Every key of every section is declared once below (type, unit, range, default, documentation).
// The reader rejects keys that are not in the tables, takes ranges and hints from them, and
// `scene_template()` prints them, so documentation, checks and template cannot drift apart.
#include "libpd/io/scene.hpp"

#include "libpd/io/resources.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <span>
#include <sstream>
#include <string_view>
#include <system_error>
#include <utility>
#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

namespace pd {

namespace {

/// Messages quote the scene's text (and yaml-cpp quotes the offending character verbatim, e.g.
/// "unknown escape character: \0"); a NUL, newline or other control byte would cut or garble the
/// one-line message on a terminal, so it is shown as \xHH.
std::string printable(const std::string& text) {
  std::string out;
  for (const char ch : text) {
    const auto c = static_cast<unsigned char>(ch);
    if (c < 0x20 || c == 0x7f) {
      out += fmt::format("\\x{:02x}", c);
    } else {
      out += ch;
    }
  }
  return out;
}

std::string format_error(const std::string& file, SourceMark mark, const std::string& what,
                         const std::string& hint) {
  std::string out = file;
  if (mark.line > 0) {
    out += fmt::format(":{}:{}", mark.line, mark.column);
  }
  out += ": error: " + printable(what);
  if (!hint.empty()) {
    out += "\n  hint: " + printable(hint);
  }
  return out;
}

} // namespace

SceneError::SceneError(std::string file, SourceMark mark, const std::string& what,
                       const std::string& hint)
    : std::runtime_error(format_error(file, mark, what, hint)), file_(std::move(file)),
      mark_(mark) {}

namespace {

// ---------------------------------------------------------------------------------------------
// Schema
// ---------------------------------------------------------------------------------------------

constexpr double inf = std::numeric_limits<double>::infinity();

enum class Type {
  string,
  integer,
  number,
  number_or_auto, ///< `auto` or a number
  boolean,
  choice,           ///< one word of `choices`
  vector,           ///< [x, y, z] with `dimension` to 3 entries
  matrix,           ///< rows of vectors
  box,              ///< [[lo], [hi]]
  boxes,            ///< list of boxes (union)
  components,       ///< list of x | y | z
  component_values, ///< map x | y | z → number
  names,            ///< list of words of `choices`
  section,          ///< nested map
  list,             ///< list of maps
  named_map,        ///< map name → map
};

/// `one_of`: exactly one key of the key's group must be given. Keys sharing a group are
/// alternatives: at most one of them may be given.
enum class Need { optional, required, one_of };

/// Whether the template writes the key as a live line or as a comment to uncomment.
enum class Show { active, commented };

struct Range {
  double lo = -inf;
  double hi = inf;
  bool lo_open = false;
  bool hi_open = false;

  bool contains(double v) const {
    return (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi);
  }
  bool unbounded() const { return lo == -inf && hi == inf; }
};

constexpr Range positive{0, inf, true, false};
constexpr Range non_negative{0, inf, false, false};
constexpr Range at_least_one{1, inf, false, false};

struct Section;

struct Key {
  std::string_view name;
  Type type;
  std::string_view doc;
  std::string_view unit{};
  Range range{};
  std::string_view choices{};  ///< '|'-separated words, in the order of the enum they map to
  std::string_view fallback{}; ///< the default, as YAML; empty: none
  std::string_view example{};  ///< template value of keys without a default
  Need need = Need::optional;
  int group = 0;
  int only_dim = 0; ///< 0: any dimension
  Show show = Show::active;
  const Section* section = nullptr; ///< section, list, named_map
  std::string_view range_hint{};    ///< hint for out-of-range values; generic if empty
};

struct Section {
  std::string_view place; ///< "under 'lattice'", for messages
  std::span<const Key> keys;
};

constexpr Key steady_keys[] = {
    {.name = "kinetic_tolerance",
     .type = Type::number,
     .doc = "converged when kinetic energy ≤ this × strain energy",
     .range = positive,
     .fallback = "1e-10"},
    {.name = "force_tolerance",
     .type = Type::number,
     .doc = "and residual force ≤ this × reference force (loads, or support reactions)",
     .range = positive,
     .fallback = "1e-6"},
    {.name = "check_every",
     .type = Type::integer,
     .doc = "steps between convergence checks",
     .unit = "steps",
     .range = at_least_one,
     .fallback = "100"},
};
constexpr Section steady_section{"under 'solver.steady'", steady_keys};

constexpr Key arkode_keys[] = {
    {.name = "table",
     .type = Type::choice,
     .doc = "Butcher table of ERKStep (SUNDIALS 6.4.1): those that compute correctly with it; "
            "heun-euler and rk4 run with the issue-311 work-around",
     .choices = "heun-euler|bogacki-shampine|knoth-wolke|rk4|zonneveld|cash-karp|fehlberg|"
                "dormand-prince",
     .fallback = "rk4"},
    {.name = "adaptive",
     .type = Type::boolean,
     .doc = "false: fixed steps of solver.dt; true: error-controlled steps within each solver.dt "
            "(tables with an embedding only)",
     .fallback = "false"},
    {.name = "rtol",
     .type = Type::number,
     .doc = "relative tolerance of the adaptive error test",
     .range = positive,
     .fallback = "1e-6"},
    {.name = "atol",
     .type = Type::number,
     .doc = "absolute tolerance of the adaptive error test, on u [m] and v [m/s]",
     .range = positive,
     .fallback = "1e-12"},
};
constexpr Section arkode_section{"under 'solver.arkode'", arkode_keys};

constexpr Key solver_keys[] = {
    {.name = "integrator",
     .type = Type::choice,
     .doc = "time integrator; damped-euler and arkode apply kinematic damping, adr computes its "
            "own",
     .choices = "damped-euler|euler-cromer|verlet|adr|arkode",
     .fallback = "damped-euler"},
    {.name = "dt",
     .type = Type::number_or_auto,
     .doc = "time step; auto = safety × the stable time step (Miranda eq. 31)",
     .unit = "s",
     .range = positive,
     .fallback = "auto"},
    {.name = "safety",
     .type = Type::number,
     .doc = "factor on the stable time step when dt is auto",
     .range = {0, 1, true, false},
     .fallback = "0.8",
     .range_hint = "use a factor in (0, 1], e.g. 0.8; above 1 the explicit scheme is unstable"},
    {.name = "end_time",
     .type = Type::number,
     .doc = "simulated time at which the run stops (give end_time, steady or both)",
     .unit = "s",
     .range = positive,
     .example = "0.05"},
    {.name = "ramp_time",
     .type = Type::number,
     .doc = "loads and prescribed displacements grow linearly over this time (eq. 33)",
     .unit = "s",
     .range = non_negative,
     .fallback = "0"},
    {.name = "damping",
     .type = Type::number,
     .doc = "kinematic damping coefficient c_v (needs the damping effect)",
     .unit = "kg/(m³ s)",
     .range = non_negative,
     .fallback = "0"},
    {.name = "max_steps",
     .type = Type::integer,
     .doc = "hard limit on the number of steps",
     .unit = "steps",
     .range = at_least_one,
     .fallback = "100000000"},
    {.name = "blowup_displacement",
     .type = Type::number,
     .doc = "a larger displacement stops the run as unstable; 0 = bounding-box diagonal",
     .unit = "m",
     .range = non_negative,
     .fallback = "0"},
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
};
constexpr Section solver_section{"under 'solver'", solver_keys};

constexpr Key lattice_keys[] = {
    {.name = "spacing",
     .type = Type::number,
     .doc = "lattice spacing λ",
     .unit = "m",
     .range = positive,
     .example = "0.01",
     .need = Need::required},
    {.name = "horizon_factor",
     .type = Type::number,
     .doc = "m = δ/λ, the horizon in spacings (2√3 = 3.4641016151377544)",
     .range = at_least_one,
     .fallback = "3.4641016151377544",
     .range_hint = "a horizon below one spacing has no bonds; use m ≥ 1 (typically 3.015 or 2√3)"},
    {.name = "convention",
     .type = Type::choice,
     .doc = "particles at cell centres (surfaces λ/2 outside) or on lattice nodes",
     .choices = "cell-centered|node-based",
     .fallback = "cell-centered"},
    {.name = "origin",
     .type = Type::vector,
     .doc = "anchor of the lattice shared by all bodies",
     .unit = "m",
     .fallback = "[0, 0, 0]"},
    {.name = "horizon_rule",
     .type = Type::choice,
     .doc = "bonds of length exactly δ: kept (inclusive) or dropped (strict)",
     .choices = "inclusive|strict",
     .fallback = "inclusive"},
    {.name = "position_jitter",
     .type = Type::number,
     .doc = "random particle displacement, as a fraction of λ",
     .range = {0, 0.45, false, false},
     .fallback = "0"},
    {.name = "volume_variation",
     .type = Type::number,
     .doc = "random relative variation of particle volumes",
     .range = {0, 0.9, false, false},
     .fallback = "0"},
    {.name = "seed",
     .type = Type::integer,
     .doc = "seed of the jitter and volume variation",
     .range = non_negative,
     .fallback = "1"},
};
constexpr Section lattice_section{"under 'lattice'", lattice_keys};

constexpr Key material_keys[] = {
    {.name = "youngs_modulus",
     .type = Type::number,
     .doc = "Young's modulus E",
     .unit = "Pa",
     .range = positive,
     .example = "200e9",
     .need = Need::required,
     .range_hint = "E must be positive, e.g. 200e9 for steel"},
    {.name = "poisson_ratio",
     .type = Type::number,
     .doc = "ν as measured; bond-based PD fixes ν (1/4 in 3D and plane strain, 1/3 in plane "
            "stress), other values only cause a warning",
     .range = {-1, 0.5, true, true},
     .fallback = "0.25",
     .range_hint = "a stable isotropic material has -1 < ν < 0.5"},
    {.name = "density",
     .type = Type::number,
     .doc = "mass density ρ",
     .unit = "kg/m³",
     .range = positive,
     .example = "7850",
     .need = Need::required,
     .range_hint = "ρ must be positive, e.g. 7850 for steel"},
    {.name = "fracture_energy",
     .type = Type::number,
     .doc = "critical energy release rate G0; the critical stretch follows from it (eq. 11)",
     .unit = "J/m²",
     .range = positive,
     .example = "100",
     .group = 1,
     .show = Show::commented},
    {.name = "critical_stretch",
     .type = Type::number,
     .doc = "critical stretch s0, instead of fracture_energy",
     .range = positive,
     .example = "1e-3",
     .group = 1,
     .show = Show::commented},
    {.name = "yield_stretch",
     .type = Type::number,
     .doc = "yield stretch s_Y of micro-plastic bonds (eq. 15)",
     .range = positive,
     .example = "5e-4",
     .show = Show::commented},
    {.name = "stiffness_factor",
     .type = Type::number,
     .doc = "multiplies the micromodulus (deliberately stiff regions)",
     .range = positive,
     .fallback = "1"},
};
constexpr Section material_section{"in a material", material_keys};

constexpr Key body_keys[] = {
    {.name = "name",
     .type = Type::string,
     .doc = "unique name of the body",
     .example = "bar",
     .need = Need::required},
    {.name = "material",
     .type = Type::string,
     .doc = "name of one of the materials",
     .example = "steel",
     .need = Need::required},
    {.name = "box",
     .type = Type::box,
     .doc = "region [[lo], [hi]] filled with lattice particles",
     .unit = "m",
     .example = "[[0, 0, 0], [1, 0.1, 0.1]]",
     .need = Need::one_of,
     .group = 1},
    {.name = "boxes",
     .type = Type::boxes,
     .doc = "instead of box: a union of boxes",
     .unit = "m",
     .example = "[[[0, 0, 0], [0.5, 0.1, 0.1]], [[0.5, 0, 0], [1, 0.1, 0.1]]]",
     .need = Need::one_of,
     .group = 1,
     .show = Show::commented},
};
constexpr Section body_section{"in a body", body_keys};

constexpr Key support_keys[] = {
    {.name = "name",
     .type = Type::string,
     .doc = "unique name of the support",
     .example = "clamp",
     .need = Need::required},
    {.name = "box",
     .type = Type::box,
     .doc = "region whose particles (of any body) are supported",
     .unit = "m",
     .example = "[[0, 0, 0], [0.03, 0.1, 0.1]]",
     .need = Need::one_of,
     .group = 1},
    {.name = "boxes",
     .type = Type::boxes,
     .doc = "instead of box: a union of boxes",
     .unit = "m",
     .example = "[[[0, 0, 0], [0.03, 0.1, 0.1]]]",
     .need = Need::one_of,
     .group = 1,
     .show = Show::commented},
    {.name = "fixed",
     .type = Type::components,
     .doc = "components held at zero displacement",
     .example = "[x, y, z]"},
    {.name = "displacement",
     .type = Type::component_values,
     .doc = "prescribed displacement per component, ramped with the load; a component may not be "
            "both fixed and displaced",
     .unit = "m",
     .example = "{x: 0.001}",
     .show = Show::commented},
    {.name = "mirror",
     .type = Type::component_values,
     .doc = "instead of fixed: a clamped face at these planes (x = value, ...). The support's "
            "particles take the body's displacement mirrored across every plane, negated once "
            "per plane, so the displacement vanishes on the face with the strain continuous "
            "across it; fixed particles put the clamp about one spacing behind the face",
     .unit = "m",
     .example = "{x: 0}",
     .show = Show::commented},
};
constexpr Section support_section{"in a support", support_keys};

constexpr Key load_keys[] = {
    {.name = "name",
     .type = Type::string,
     .doc = "unique name of the load",
     .example = "pull",
     .need = Need::required},
    {.name = "box",
     .type = Type::box,
     .doc = "region whose particles (of any body) carry the load",
     .unit = "m",
     .example = "[[0.99, 0, 0], [1, 0.1, 0.1]]",
     .need = Need::one_of,
     .group = 1},
    {.name = "boxes",
     .type = Type::boxes,
     .doc = "instead of box: a union of boxes",
     .unit = "m",
     .example = "[[[0.99, 0, 0], [1, 0.1, 0.1]]]",
     .need = Need::one_of,
     .group = 1,
     .show = Show::commented},
    {.name = "type",
     .type = Type::choice,
     .doc = "total force [N] spread over the region, or a traction per_area [N/m²], per_length "
            "[N/m], or a body force density [N/m³]",
     .choices = "total|per_area|per_length|body",
     .fallback = "total"},
    {.name = "value",
     .type = Type::vector,
     .doc = "force vector, in the unit its type implies",
     .example = "[1000, 0, 0]",
     .need = Need::required},
    {.name = "measure",
     .type = Type::number,
     .doc = "loaded area [m²] (per_area) or length [m] (per_length); only for these types",
     .unit = "m² or m",
     .range = positive,
     .example = "0.01",
     .show = Show::commented},
};
constexpr Section load_section{"in a load", load_keys};

constexpr Key model_keys[] = {
    {.name = "stretch",
     .type = Type::choice,
     .doc = "stretch measure (exact eq. 6, modified eq. 17, fast: no square root)",
     .choices = "exact|modified|fast",
     .fallback = "exact"},
    {.name = "surface_correction",
     .type = Type::choice,
     .doc = "bond stiffness correction near free surfaces",
     .choices = "none|volume|energy|macek-silling|tensor",
     .fallback = "tensor"},
    {.name = "volume_correction",
     .type = Type::choice,
     .doc = "bond quadrature weights: partial volume of cut cells (linear, exact) or "
            "moment-matched lattice weights (moment)",
     .choices = "none|linear|exact|moment",
     .fallback = "moment"},
};
constexpr Section model_section{"under 'model'", model_keys};

constexpr Key initial_keys[] = {
    {.name = "displacement_gradient",
     .type = Type::matrix,
     .doc = "H of the initial displacement u0 = H (X - about), rows i, columns j = ∂u_i/∂X_j",
     .fallback = "[[0, 0, 0], [0, 0, 0], [0, 0, 0]]"},
    {.name = "about",
     .type = Type::vector,
     .doc = "point of zero initial displacement",
     .unit = "m",
     .fallback = "[0, 0, 0]"},
    {.name = "velocity",
     .type = Type::vector,
     .doc = "uniform initial velocity",
     .unit = "m/s",
     .fallback = "[0, 0, 0]"},
};
constexpr Section initial_section{"under 'initial'", initial_keys};

constexpr Key probe_keys[] = {
    {.name = "name",
     .type = Type::string,
     .doc = "unique name of the probe",
     .example = "tip",
     .need = Need::required},
    {.name = "point",
     .type = Type::vector,
     .doc = "records the particle nearest to this point (within one spacing of a body)",
     .unit = "m",
     .example = "[1, 0.05, 0.05]",
     .need = Need::one_of,
     .group = 1},
    {.name = "box",
     .type = Type::box,
     .doc = "instead of point: records the average over the particles in a box",
     .unit = "m",
     .example = "[[0.99, 0.04, 0.04], [1, 0.06, 0.06]]",
     .need = Need::one_of,
     .group = 1,
     .show = Show::commented},
    {.name = "boxes",
     .type = Type::boxes,
     .doc = "instead of point: the average over a union of boxes",
     .unit = "m",
     .example = "[[[0.99, 0.04, 0.04], [1, 0.06, 0.06]]]",
     .need = Need::one_of,
     .group = 1,
     .show = Show::commented},
    {.name = "component",
     .type = Type::choice,
     .doc = "displacement component recorded",
     .choices = "x|y|z",
     .fallback = "x"},
};
constexpr Section probe_section{"in a probe", probe_keys};

constexpr Key output_keys[] = {
    {.name = "vtu",
     .type = Type::boolean,
     .doc = "write VTU files of the particles",
     .fallback = "true"},
    {.name = "vtu_every",
     .type = Type::integer,
     .doc = "steps between VTU files; 0 = final state only",
     .unit = "steps",
     .range = non_negative,
     .fallback = "0"},
    {.name = "history_every",
     .type = Type::integer,
     .doc = "steps between rows of the probe history; 0 = no history",
     .unit = "steps",
     .range = non_negative,
     .fallback = "0"},
};
constexpr Section output_section{"under 'output'", output_keys};

constexpr Key root_keys[] = {
    {.name = "title",
     .type = Type::string,
     .doc = "free text shown in summaries and output files",
     .example = "\"Block in tension\""},
    {.name = "dimension",
     .type = Type::integer,
     .doc = "spatial dimension: 1, 2 or 3",
     .range = {1, 3, false, false},
     .example = "3",
     .need = Need::required,
     .range_hint = "use dimension: 1, 2 or 3"},
    {.name = "plane",
     .type = Type::choice,
     .doc = "2D assumption: plane stress (bond-based ν = 1/3) or plane strain (ν = 1/4)",
     .choices = "stress|strain",
     .fallback = "stress",
     .only_dim = 2,
     .show = Show::commented},
    {.name = "thickness",
     .type = Type::number,
     .doc = "out-of-plane thickness of a 2D model",
     .unit = "m",
     .range = positive,
     .fallback = "1",
     .only_dim = 2,
     .show = Show::commented},
    {.name = "cross_section",
     .type = Type::number,
     .doc = "cross-section area of a 1D model",
     .unit = "m²",
     .range = positive,
     .fallback = "1",
     .only_dim = 1,
     .show = Show::commented},
    {.name = "lattice",
     .type = Type::section,
     .doc = "the particle lattice shared by all bodies",
     .need = Need::required,
     .section = &lattice_section},
    {.name = "materials",
     .type = Type::named_map,
     .doc = "materials by name (at least one)",
     .example = "steel",
     .need = Need::required,
     .section = &material_section},
    {.name = "bodies",
     .type = Type::list,
     .doc = "bodies: regions of the lattice made of one material (at least one); where bodies "
            "overlap, their materials must agree",
     .need = Need::required,
     .section = &body_section},
    {.name = "supports",
     .type = Type::list,
     .doc = "fixed or prescribed displacements",
     .section = &support_section},
    {.name = "loads", .type = Type::list, .doc = "external forces", .section = &load_section},
    {.name = "effects",
     .type = Type::names,
     .doc = "effects to simulate; damage needs fracture_energy or critical_stretch, plasticity "
            "needs yield_stretch, damping needs solver.damping > 0",
     .choices = "damage|plasticity|damping",
     .fallback = "[]"},
    {.name = "model",
     .type = Type::section,
     .doc = "bond model options",
     .section = &model_section},
    {.name = "solver",
     .type = Type::section,
     .doc = "time integration and stopping",
     .section = &solver_section},
    {.name = "initial",
     .type = Type::section,
     .doc = "initial displacement and velocity",
     .section = &initial_section},
    {.name = "probes",
     .type = Type::list,
     .doc = "displacements recorded during the run",
     .section = &probe_section},
    {.name = "output",
     .type = Type::section,
     .doc = "files written by the run",
     .section = &output_section},
};
constexpr Section root_section{"at the top level", root_keys};

constexpr std::array<const Section*, 13> all_sections{
    &root_section,    &lattice_section, &material_section, &body_section,   &support_section,
    &load_section,    &model_section,   &solver_section,   &steady_section, &arkode_section,
    &initial_section, &probe_section,   &output_section};

// ---------------------------------------------------------------------------------------------
// Text helpers
// ---------------------------------------------------------------------------------------------

std::vector<std::string_view> split_choices(std::string_view text) {
  std::vector<std::string_view> out;
  while (!text.empty()) {
    const auto bar = text.find('|');
    out.push_back(text.substr(0, bar));
    if (bar == std::string_view::npos) {
      break;
    }
    text.remove_prefix(bar + 1);
  }
  return out;
}

std::string join(const std::vector<std::string_view>& words, std::string_view separator) {
  std::string out;
  for (std::size_t i = 0; i < words.size(); ++i) {
    out += (i > 0 ? std::string(separator) : std::string()) + std::string(words[i]);
  }
  return out;
}

std::string quoted_list(const std::vector<std::string_view>& words) {
  std::string out;
  for (std::size_t i = 0; i < words.size(); ++i) {
    out += (i == 0 ? "" : i + 1 == words.size() ? " or " : ", ") + fmt::format("'{}'", words[i]);
  }
  return out;
}

std::size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) {
    row[j] = j;
  }
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t above = row[j];
      const bool same = std::tolower(static_cast<unsigned char>(a[i - 1])) ==
                        std::tolower(static_cast<unsigned char>(b[j - 1]));
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (same ? 0 : 1)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

/// The candidate a typo most likely meant, if any is close enough to be a plausible typo.
std::optional<std::string_view> closest(std::string_view word,
                                        const std::vector<std::string_view>& candidates) {
  std::optional<std::string_view> best;
  std::size_t best_distance = std::numeric_limits<std::size_t>::max();
  const std::size_t limit = std::max<std::size_t>(2, word.size() / 3);
  for (std::string_view c : candidates) {
    std::size_t d = edit_distance(word, c);
    // "horizon" for "horizon_factor": a truncated name is a typo too.
    if (word.size() >= 3 && (c.starts_with(word) || word.starts_with(c))) {
      d = std::min(d, limit);
    }
    if (d <= limit && d < best_distance) {
      best = c;
      best_distance = d;
    }
  }
  return best;
}

/// "did you mean 'fast'? (allowed: exact, modified, fast)"
std::string suggestion(std::string_view word, const std::vector<std::string_view>& candidates,
                       std::string_view allowed_label = "allowed") {
  std::string out;
  if (const auto guess = closest(word, candidates)) {
    out = fmt::format("did you mean '{}'? ", *guess);
  }
  return out + fmt::format("({}: {})", allowed_label, join(candidates, ", "));
}

std::string describe(const YAML::Node& n) {
  switch (n.Type()) {
  case YAML::NodeType::Null:
    return "nothing";
  case YAML::NodeType::Scalar:
    return n.Tag() == "!" ? fmt::format("the quoted string \"{}\"", n.Scalar())
                          : fmt::format("'{}'", n.Scalar());
  case YAML::NodeType::Sequence:
    return "a list";
  case YAML::NodeType::Map:
    return "a map";
  default:
    return "nothing";
  }
}

std::string unit_suffix(std::string_view unit) {
  return unit.empty() ? std::string() : fmt::format(" [{}]", unit);
}

std::string range_text(const Range& r) {
  if (r.unbounded()) {
    return {};
  }
  if (r.hi == inf) {
    return fmt::format("{} {}", r.lo_open ? ">" : "≥", r.lo);
  }
  if (r.lo == -inf) {
    return fmt::format("{} {}", r.hi_open ? "<" : "≤", r.hi);
  }
  return fmt::format("in {}{}, {}{}", r.lo_open ? "(" : "[", r.lo, r.hi, r.hi_open ? ")" : "]");
}

constexpr std::array<std::string_view, 3> axis_names{"x", "y", "z"};

std::vector<std::string_view> axes(int dim) {
  return {axis_names.begin(), axis_names.begin() + dim};
}

SourceMark source_mark(const YAML::Node& n) {
  const YAML::Mark m = n.Mark();
  if (m.is_null()) {
    return {};
  }
  return {m.line + 1, m.column + 1};
}

enum class NumberText { ok, not_a_number, non_finite, out_of_range };

/// YAML spells NaN and infinity `.nan`, `.inf`; std::from_chars spells them `nan`, `inf`.
/// Both are recognised so that neither slips through as text or as a valid number.
NumberText parse_double(std::string_view text, double& value) {
  std::string lower(text);
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (lower == ".nan" || lower == ".inf" || lower == "+.inf" || lower == "-.inf") {
    return NumberText::non_finite;
  }
  std::string_view t = text;
  if (t.starts_with('+')) {
    t.remove_prefix(1);
  }
  const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), value);
  if (ec == std::errc::result_out_of_range) {
    return NumberText::out_of_range;
  }
  if (ec != std::errc{} || end != t.data() + t.size() || t.empty()) {
    return NumberText::not_a_number;
  }
  return std::isfinite(value) ? NumberText::ok : NumberText::non_finite;
}

// ---------------------------------------------------------------------------------------------
// Reader
// ---------------------------------------------------------------------------------------------

struct Entry {
  const Key* key = nullptr;
  YAML::Node name;
  YAML::Node value;

  /// A key without a value has no position of its own (yaml-cpp marks the next token).
  YAML::Node at() const { return value.IsNull() ? name : value; }
};

/// The keys of one map, checked against its section.
struct Fields {
  const Section* schema = nullptr;
  YAML::Node anchor;  ///< where "missing key" errors point: the map, or its key if it is empty
  std::string prefix; ///< "lattice." for sections
  std::string owner;  ///< "body 'bar'" for list items and materials
  std::vector<Entry> entries;

  const Entry* find(std::string_view key) const {
    for (const Entry& e : entries) {
      if (e.key->name == key) {
        return &e;
      }
    }
    return nullptr;
  }
  bool has(std::string_view key) const { return find(key) != nullptr; }
  std::string label(std::string_view key) const {
    return owner.empty() ? fmt::format("'{}{}'", prefix, key)
                         : fmt::format("'{}' of {}", key, owner);
  }
  std::string where() const {
    if (!owner.empty()) {
      return "in " + owner;
    }
    return prefix.empty() ? std::string("at the top level")
                          : fmt::format("in '{}'", prefix.substr(0, prefix.size() - 1));
  }
};

std::string example_line(const Key& k) {
  const std::string_view value = k.fallback.empty() ? k.example : k.fallback;
  if (k.type == Type::section || k.type == Type::list || k.type == Type::named_map) {
    return fmt::format("'{}:' with its keys", k.name);
  }
  return fmt::format("'{}: {}'", k.name, value);
}

/// A key of the given section, by name; the reader only asks for keys that the tables declare.
const Key& key_of(const Section& s, std::string_view name) {
  for (const Key& k : s.keys) {
    if (k.name == name) {
      return k;
    }
  }
  throw std::logic_error(fmt::format("scene schema has no key '{}'", name));
}

class Reader {
public:
  Reader(std::string file, std::vector<std::string>& warnings)
      : file_(std::move(file)), warnings_(warnings) {}

  int dim = 3;

  const std::string& file() const { return file_; }

  [[noreturn]] void fail(const YAML::Node& at, const std::string& what,
                         const std::string& hint) const {
    throw SceneError(file_, source_mark(at), what, hint);
  }

  void warn(const YAML::Node& at, const std::string& what) {
    const SourceMark m = source_mark(at);
    warnings_.push_back(fmt::format("{}:{}:{}: warning: {}", file_, m.line, m.column, what));
  }

  /// Check a map's keys against its section: unknown, duplicate and conflicting keys (missing
  /// ones are caught by `lookup` when read). `node` may be null (an empty section); `anchor` then
  /// stands in for it in messages.
  Fields open(const YAML::Node& node, const YAML::Node& anchor, const Section& schema,
              std::string prefix, std::string owner, const std::string& what) const {
    Fields f;
    f.schema = &schema;
    f.anchor = node.IsNull() ? anchor : node;
    f.prefix = std::move(prefix);
    f.owner = std::move(owner);
    if (node.IsNull()) {
      return f;
    }
    if (!node.IsMap()) {
      fail(node,
           fmt::format("{} must be a map of 'key: value' lines, got {}", what, describe(node)),
           "write one 'key: value' per line, indented under its parent");
    }
    for (auto it = node.begin(); it != node.end(); ++it) {
      const YAML::Node k = it->first;
      if (!k.IsScalar()) {
        fail(k, fmt::format("a key {} must be a plain name, got {}", f.where(), describe(k)),
             "write keys as plain words followed by ':'");
      }
      const std::string& name = k.Scalar();
      const Key* spec = nullptr;
      for (const Key& candidate : schema.keys) {
        if (candidate.name == name) {
          spec = &candidate;
        }
      }
      if (spec == nullptr) {
        fail(k, fmt::format("unknown key '{}' {}", name, f.where()),
             unknown_key_hint(name, schema));
      }
      if (const Entry* first = f.find(name)) {
        fail(k, fmt::format("duplicate key '{}' {}", name, f.where()),
             fmt::format("'{}' is already given on line {}; keep only one", name,
                         source_mark(first->name).line));
      }
      f.entries.push_back({spec, k, it->second});
    }
    check_alternatives(f);
    return f;
  }

  /// The entry of `key`, or nullptr if it is absent and may be. Required keys are checked here,
  /// when they are read, so that problems are reported in reading order rather than all
  /// missing keys first.
  const Entry* lookup(const Fields& f, std::string_view key) const {
    if (const Entry* e = f.find(key)) {
      return e;
    }
    const Key& k = key_of(*f.schema, key);
    if (k.need == Need::required) {
      fail(f.anchor, fmt::format("missing required key '{}' {}", k.name, f.where()),
           fmt::format("add {} ({}{})", example_line(k), k.doc, unit_suffix(k.unit)));
    }
    if (k.need == Need::one_of) {
      std::vector<std::string_view> group;
      bool given = false;
      for (const Key& other : f.schema->keys) {
        if (other.group == k.group) {
          group.push_back(other.name);
          given = given || f.has(other.name);
        }
      }
      if (!given) {
        fail(f.anchor, fmt::format("missing {} {}", quoted_list(group), f.where()),
             fmt::format("add exactly one of them, e.g. {}", example_line(k)));
      }
    }
    return nullptr;
  }

  Fields section(const Fields& parent, std::string_view key) const {
    const Key& spec = key_of(*parent.schema, key);
    const Entry* e = lookup(parent, key);
    const std::string prefix = parent.prefix + std::string(key) + ".";
    if (e == nullptr) {
      return open(YAML::Node(YAML::NodeType::Null), parent.anchor, *spec.section, prefix, {}, {});
    }
    return open(e->value, e->name, *spec.section, prefix, {}, parent.label(key));
  }

  /// Items of a list; an empty value is an empty list.
  std::vector<YAML::Node> items(const Fields& f, std::string_view key) const {
    const Entry* e = lookup(f, key);
    if (e == nullptr || e->value.IsNull()) {
      return {};
    }
    if (!e->value.IsSequence()) {
      fail(e->value, fmt::format("{} must be a list, got {}", f.label(key), describe(e->value)),
           fmt::format("write each item on its own line starting with '- ', under '{}:'", key));
    }
    return {e->value.begin(), e->value.end()};
  }

  /// A list item's fields; its owner label uses its name if it has one.
  Fields item(const YAML::Node& node, const Section& schema, std::string_view kind,
              std::string_view list, std::size_t index) const {
    std::string owner = fmt::format("{} #{} of '{}'", kind, index + 1, list);
    if (node.IsMap() && node["name"] && node["name"].IsScalar()) {
      owner = fmt::format("{} '{}'", kind, node["name"].Scalar());
    }
    return open(node, node, schema, {}, owner, fmt::format("item #{} of '{}'", index + 1, list));
  }

  std::optional<std::string> string(const Fields& f, std::string_view key) const {
    const Entry* e = lookup(f, key);
    if (e == nullptr) {
      return std::nullopt;
    }
    if (!e->value.IsScalar()) {
      fail(e->at(), fmt::format("{} must be a string, got {}", f.label(key), describe(e->value)),
           fmt::format("write e.g. {}", example_line(*e->key)));
    }
    return e->value.Scalar();
  }

  double to_number(const YAML::Node& n, const std::string& label, std::string_view unit,
                   const std::string& example) const {
    if (!n.IsScalar()) {
      fail(n, fmt::format("{} must be a number{}, got {}", label, unit_suffix(unit), describe(n)),
           fmt::format("write a number, e.g. {}", example));
    }
    if (n.Tag() == "!") {
      fail(n, fmt::format("{} must be a number{}, got {}", label, unit_suffix(unit), describe(n)),
           "remove the quotes");
    }
    double v = 0;
    switch (parse_double(n.Scalar(), v)) {
    case NumberText::ok:
      return v;
    case NumberText::non_finite:
      fail(n, fmt::format("{} is not a finite number (got {})", label, n.Scalar()),
           "NaN and infinite values are not allowed; give a finite number");
    case NumberText::out_of_range:
      fail(n, fmt::format("{} = {} is out of the range of double precision", label, n.Scalar()),
           "give a value between about 1e-300 and 1e300 in magnitude");
    case NumberText::not_a_number:
      break;
    }
    fail(n, fmt::format("{} must be a number{}, got {}", label, unit_suffix(unit), describe(n)),
         fmt::format("write a plain number, e.g. {}", example));
  }

  void check_range(const YAML::Node& n, const std::string& label, const Key& k, double v) const {
    if (!k.range.contains(v)) {
      fail(n,
           fmt::format("{} must be {}{}, got {}", label, range_text(k.range), unit_suffix(k.unit),
                       n.Scalar()),
           k.range_hint.empty() ? fmt::format("give a value {}", range_text(k.range))
                                : std::string(k.range_hint));
    }
  }

  std::optional<double> number(const Fields& f, std::string_view key) const {
    const Entry* e = lookup(f, key);
    if (e == nullptr) {
      return std::nullopt;
    }
    const Key& k = *e->key;
    const std::string label = f.label(key);
    const double v = to_number(e->at(), label, k.unit, example_line(k));
    check_range(e->at(), label, k, v);
    return v;
  }

  /// nullopt for `auto` or an absent key.
  std::optional<double> number_or_auto(const Fields& f, std::string_view key) const {
    const Entry* e = lookup(f, key);
    if (e == nullptr || (e->value.IsScalar() && e->value.Scalar() == "auto")) {
      return std::nullopt;
    }
    const Key& k = *e->key;
    const std::string label = f.label(key);
    if (e->value.IsScalar()) {
      double v = 0;
      if (parse_double(e->value.Scalar(), v) == NumberText::not_a_number) {
        fail(e->value,
             fmt::format("{} must be 'auto' or a number{}, got {}", label, unit_suffix(k.unit),
                         describe(e->value)),
             fmt::format("write '{}: auto' or a number {}", k.name, range_text(k.range)));
      }
    }
    const double v = to_number(e->at(), label, k.unit, fmt::format("'{}: auto'", k.name));
    check_range(e->at(), label, k, v);
    return v;
  }

  template <class T>
  std::optional<T> integer(const Fields& f, std::string_view key) const {
    const Entry* e = lookup(f, key);
    if (e == nullptr) {
      return std::nullopt;
    }
    const Key& k = *e->key;
    const std::string label = f.label(key);
    const YAML::Node n = e->at();
    const auto wrong = [&] {
      fail(n, fmt::format("{} must be an integer, got {}", label, describe(n)),
           fmt::format("write e.g. {}", example_line(k)));
    };
    if (!n.IsScalar() || n.Tag() == "!") {
      wrong();
    }
    const std::string& text = n.Scalar();
    T value{};
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (ec == std::errc{} && end == text.data() + text.size()) {
      check_range(n, label, k, static_cast<double>(value));
      return value;
    }
    // Integral numbers written like 1e8, and negative or huge values that miss T.
    const double v = to_number(n, label, k.unit, example_line(k));
    if (v != std::floor(v)) {
      wrong();
    }
    check_range(n, label, k, v);
    if (v < static_cast<double>(std::numeric_limits<T>::min()) ||
        v >= static_cast<double>(std::numeric_limits<T>::max())) {
      fail(n, fmt::format("{} = {} is too large", label, text),
           fmt::format("give a value below {}", std::numeric_limits<T>::max()));
    }
    return static_cast<T>(v);
  }

  std::optional<bool> boolean(const Fields& f, std::string_view key) const {
    const Entry* e = lookup(f, key);
    if (e == nullptr) {
      return std::nullopt;
    }
    const YAML::Node n = e->at();
    if (n.IsScalar() && n.Tag() != "!") {
      std::string t = n.Scalar();
      std::transform(t.begin(), t.end(), t.begin(),
                     [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
      if (t == "true" || t == "yes" || t == "on") {
        return true;
      }
      if (t == "false" || t == "no" || t == "off") {
        return false;
      }
    }
    fail(n, fmt::format("{} must be true or false, got {}", f.label(key), describe(n)),
         fmt::format("write '{}: true' or '{}: false'", key, key));
  }

  int word(const YAML::Node& n, const std::string& label, std::string_view choices) const {
    const auto words = split_choices(choices);
    if (n.IsScalar()) {
      for (std::size_t i = 0; i < words.size(); ++i) {
        if (words[i] == n.Scalar()) {
          return static_cast<int>(i);
        }
      }
      fail(n, fmt::format("unknown value '{}' for {}", n.Scalar(), label),
           suggestion(n.Scalar(), words));
    }
    fail(n, fmt::format("{} must be one of {}, got {}", label, join(words, ", "), describe(n)),
         fmt::format("write one word: {}", join(words, " | ")));
  }

  std::optional<int> choice(const Fields& f, std::string_view key) const {
    const Entry* e = lookup(f, key);
    if (e == nullptr) {
      return std::nullopt;
    }
    return word(e->at(), f.label(key), e->key->choices);
  }

  /// A point or vector: `dim` to 3 numbers, missing trailing ones are 0.
  Vec3 coordinates(const YAML::Node& n, const std::string& label, std::string_view unit) const {
    const std::string count = dim == 3 ? "3" : fmt::format("{} to 3", dim);
    const std::string example = dim == 1 ? "[0]" : dim == 2 ? "[0, 0]" : "[0, 0, 0]";
    if (!n.IsSequence()) {
      fail(n,
           fmt::format("{} must be a list of {} numbers{}, got {}", label, count, unit_suffix(unit),
                       describe(n)),
           fmt::format("write it as {}", example));
    }
    if (n.size() < static_cast<std::size_t>(dim) || n.size() > 3) {
      fail(
          n,
          fmt::format("{} has {} coordinates; a {}D scene needs {}", label, n.size(), dim, count),
          fmt::format("write it as {} (coordinates beyond the dimension may be omitted)", example));
    }
    Vec3 v{0, 0, 0};
    std::size_t i = 0;
    for (const YAML::Node& c : n) {
      v[i] = to_number(c, fmt::format("{} component of {}", axis_names[i], label), unit, "0.1");
      ++i;
    }
    return v;
  }

  /// Physical vectors (forces, velocities) may not point out of the modelled space.
  void check_in_space(const YAML::Node& n, const std::string& label, const Vec3& v) const {
    for (int c = dim; c < 3; ++c) {
      if (v[c] != 0) {
        fail(
            n,
            fmt::format("{} has a non-zero {} component in a {}D scene", label, axis_names[c], dim),
            fmt::format("set the {} component to 0 or leave it out", axis_names[c]));
      }
    }
  }

  std::optional<Vec3> vector(const Fields& f, std::string_view key) const {
    const Entry* e = lookup(f, key);
    if (e == nullptr) {
      return std::nullopt;
    }
    return coordinates(e->at(), f.label(key), e->key->unit);
  }

  std::optional<std::array<std::array<double, 3>, 3>> matrix(const Fields& f,
                                                             std::string_view key) const {
    const Entry* e = lookup(f, key);
    if (e == nullptr) {
      return std::nullopt;
    }
    const YAML::Node n = e->at();
    const std::string label = f.label(key);
    if (!n.IsSequence() || n.size() < static_cast<std::size_t>(dim) || n.size() > 3) {
      fail(n,
           fmt::format("{} must be a list of {} rows, got {}", label,
                       dim == 3 ? "3" : fmt::format("{} to 3", dim),
                       n.IsSequence() ? fmt::format("{} rows", n.size()) : describe(n)),
           "write it as [[H_xx, H_xy, H_xz], [H_yx, H_yy, H_yz], [H_zx, H_zy, H_zz]]");
    }
    std::array<std::array<double, 3>, 3> m{};
    std::size_t i = 0;
    for (const YAML::Node& row : n) {
      const std::string row_label = fmt::format("row {} of {}", i + 1, label);
      m[i] = coordinates(row, row_label, {});
      check_in_space(row, row_label, m[i]);
      if (static_cast<int>(i) >= dim && m[i] != std::array<double, 3>{0, 0, 0}) {
        fail(row, fmt::format("{} is non-zero in a {}D scene", row_label, dim),
             fmt::format("there is no {} displacement: set the row to zeros or leave it out",
                         axis_names[i]));
      }
      ++i;
    }
    return m;
  }

  Box box(const YAML::Node& n, const std::string& label) const {
    if (!n.IsSequence() || n.size() != 2) {
      fail(n,
           fmt::format("{} must be two corners [[lo], [hi]], got {}", label,
                       n.IsSequence() ? fmt::format("a list of {}", n.size()) : describe(n)),
           dim == 1   ? "write it as [[x0], [x1]]"
           : dim == 2 ? "write it as [[x0, y0], [x1, y1]]"
                      : "write it as [[x0, y0, z0], [x1, y1, z1]]");
    }
    Box b;
    b.lo = coordinates(n[0], "lower corner of " + label, "m");
    b.hi = coordinates(n[1], "upper corner of " + label, "m");
    for (int c = 0; c < 3; ++c) {
      if (b.lo[c] > b.hi[c]) {
        fail(n,
             fmt::format("{} has lo > hi in {} ({} > {})", label, axis_names[c], b.lo[c], b.hi[c]),
             "the first corner must be the lower one in every coordinate: swap the values");
      }
    }
    return b;
  }

  struct RegionRead {
    Region region;
    std::vector<YAML::Node> box_nodes; ///< one per box, for messages about a single box
    YAML::Node node;                   ///< the box or boxes value
  };

  /// The `box` or `boxes` key of a section that declares them (exactly one is present).
  RegionRead region(const Fields& f) const {
    RegionRead r;
    if (const Entry* e = lookup(f, "box")) {
      r.node = e->at();
      r.region.boxes.push_back(box(r.node, f.label("box")));
      r.box_nodes.push_back(r.node);
      return r;
    }
    const Entry* e = f.find("boxes");
    r.node = e->at();
    const std::string label = f.label("boxes");
    if (!r.node.IsSequence() || r.node.size() == 0) {
      fail(r.node,
           fmt::format("{} must be a non-empty list of boxes, got {}", label,
                       r.node.IsSequence() ? "an empty list" : describe(r.node)),
           "write it as [[[lo], [hi]], [[lo], [hi]], ...]");
    }
    std::size_t i = 0;
    for (const YAML::Node& b : r.node) {
      r.region.boxes.push_back(box(b, fmt::format("box {} of {}", ++i, label)));
      r.box_nodes.push_back(b);
    }
    return r;
  }

  int component(const YAML::Node& n, const std::string& label) const {
    const int c = word(n, label, "x|y|z");
    if (c >= dim) {
      fail(n, fmt::format("component '{}' does not exist in a {}D scene", n.Scalar(), dim),
           fmt::format("use {}", join(axes(dim), " or ")));
    }
    return c;
  }

  std::optional<std::array<bool, 3>> components(const Fields& f, std::string_view key) const {
    const Entry* e = lookup(f, key);
    if (e == nullptr) {
      return std::nullopt;
    }
    const YAML::Node n = e->at();
    const std::string label = f.label(key);
    if (!n.IsSequence()) {
      fail(n, fmt::format("{} must be a list of components, got {}", label, describe(n)),
           fmt::format("write it as [{}]", join(axes(dim), ", ")));
    }
    std::array<bool, 3> out{false, false, false};
    for (const YAML::Node& item : n) {
      const int c = component(item, "a component in " + label);
      if (out[c]) {
        fail(item, fmt::format("component '{}' is listed twice in {}", item.Scalar(), label),
             "list each component once");
      }
      out[c] = true;
    }
    return out;
  }

  std::array<std::optional<double>, 3> component_values(const Fields& f, std::string_view key,
                                                        std::array<YAML::Node, 3>& nodes) const {
    std::array<std::optional<double>, 3> out;
    const Entry* e = lookup(f, key);
    if (e == nullptr) {
      return out;
    }
    const YAML::Node n = e->at();
    const std::string label = f.label(key);
    if (!n.IsMap()) {
      fail(n, fmt::format("{} must be a map component → value, got {}", label, describe(n)),
           "write it as {x: 0.001} or {x: 0, y: -0.002}");
    }
    for (auto it = n.begin(); it != n.end(); ++it) {
      const int c = component(it->first, "a component in " + label);
      if (out[c]) {
        fail(it->first, fmt::format("component '{}' is given twice in {}", axis_names[c], label),
             "give each component once");
      }
      const YAML::Node v = it->second.IsNull() ? it->first : it->second;
      out[c] = to_number(v, fmt::format("{} component of {}", axis_names[c], label), e->key->unit,
                         "0.001");
      nodes[c] = it->first;
    }
    return out;
  }

  /// Words of a `names` key, each with its node.
  std::vector<std::pair<int, YAML::Node>> names(const Fields& f, std::string_view key) const {
    const Entry* e = lookup(f, key);
    std::vector<std::pair<int, YAML::Node>> out;
    if (e == nullptr || e->value.IsNull()) {
      return out;
    }
    const std::string label = f.label(key);
    if (!e->value.IsSequence()) {
      fail(e->value, fmt::format("{} must be a list, got {}", label, describe(e->value)),
           fmt::format("write it as [{}]", join(split_choices(e->key->choices), ", ")));
    }
    for (const YAML::Node& n : e->value) {
      const int w = word(n, "an entry of " + label, e->key->choices);
      for (const auto& [previous, node] : out) {
        if (previous == w) {
          fail(n, fmt::format("'{}' is listed twice in {}", n.Scalar(), label),
               "list each entry once");
        }
      }
      out.emplace_back(w, n);
    }
    return out;
  }

  /// Keys that only mean something in one dimension are ignored elsewhere; say so.
  void warn_foreign_keys(const Fields& f) {
    for (const Entry& e : f.entries) {
      if (e.key->only_dim != 0 && e.key->only_dim != dim) {
        warn(e.name, fmt::format("'{}' applies only to {}D scenes and is ignored in this {}D scene",
                                 e.key->name, e.key->only_dim, dim));
      }
    }
  }

private:
  std::string file_;
  std::vector<std::string>& warnings_;

  static std::string unknown_key_hint(const std::string& name, const Section& schema) {
    std::vector<std::string_view> known;
    for (const Key& k : schema.keys) {
      known.push_back(k.name);
    }
    if (const auto guess = closest(name, known)) {
      return fmt::format("did you mean '{}'?", *guess);
    }
    for (const Section* other : all_sections) {
      for (const Key& k : other->keys) {
        if (other != &schema && k.name == name) {
          return fmt::format("'{}' belongs {}, not {}", name, other->place, schema.place);
        }
      }
    }
    for (const Section* other : all_sections) {
      std::vector<std::string_view> there;
      for (const Key& k : other->keys) {
        there.push_back(k.name);
      }
      if (const auto guess = closest(name, there); guess && other != &schema) {
        return fmt::format("did you mean '{}' (a key {})? keys allowed {}: {}", *guess,
                           other->place, schema.place, join(known, ", "));
      }
    }
    return fmt::format("keys allowed {}: {}", schema.place, join(known, ", "));
  }

  void check_alternatives(const Fields& f) const {
    for (const Key& k : f.schema->keys) {
      if (k.group == 0) {
        continue;
      }
      const Entry* first = nullptr;
      for (const Entry& e : f.entries) {
        if (e.key->group != k.group) {
          continue;
        }
        if (first != nullptr) {
          std::vector<std::string_view> group;
          for (const Key& other : f.schema->keys) {
            if (other.group == k.group) {
              group.push_back(other.name);
            }
          }
          fail(e.name,
               fmt::format("'{}' and '{}' are alternatives {}", first->key->name, e.key->name,
                           f.where()),
               fmt::format("give only one of {}", quoted_list(group)));
        }
        first = &e;
      }
    }
  }
};

// ---------------------------------------------------------------------------------------------
// Scene
// ---------------------------------------------------------------------------------------------

/// A region that the scene must not leave empty, with what to say if it is.
struct RegionUse {
  Region region;
  YAML::Node node;
  std::string what;
};

/// Intersection of `region` with every body box. Lattice membership uses a tolerance of 1e-6 λ,
/// so boxes that miss each other by less than that may still share a lattice point: such slivers
/// are kept as degenerate boxes and the lattice count decides.
Region intersect_with_bodies(const Region& region, const std::vector<BodySpec>& bodies, int dim,
                             double spacing) {
  Region out;
  for (const Box& a : region.boxes) {
    for (const BodySpec& body : bodies) {
      for (const Box& b : body.region.boxes) {
        Box c = a;
        bool empty = false;
        for (int k = 0; k < dim; ++k) {
          c.lo[k] = std::max(a.lo[k], b.lo[k]);
          c.hi[k] = std::min(a.hi[k], b.hi[k]);
          if (c.lo[k] > c.hi[k]) {
            if (c.lo[k] - c.hi[k] > 2e-6 * spacing) {
              empty = true;
            }
            c.lo[k] = c.hi[k] = 0.5 * (c.lo[k] + c.hi[k]);
          }
        }
        if (!empty) {
          out.boxes.push_back(c);
        }
      }
    }
  }
  return out;
}

double distance_to_box(const Vec3& p, const Box& b, int dim) {
  double sum = 0;
  for (int k = 0; k < dim; ++k) {
    const double d = std::max({b.lo[k] - p[k], 0.0, p[k] - b.hi[k]});
    sum += d * d;
  }
  return std::sqrt(sum);
}

template <class Names>
void check_unique(const Reader& r, Names& seen, const std::string& name, const YAML::Node& node,
                  std::string_view kind) {
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

std::string format_number(double v) {
  return fmt::format("{}", v);
}

/// Whether a union of boxes holds a lattice point: some box does. Counted per axis in floating
/// point, so it needs no enumeration and cannot overflow, whatever the box.
bool holds_lattice_point(const ModelDimension& d, const LatticeSpec& lattice, const Region& r) {
  return std::any_of(r.boxes.begin(), r.boxes.end(),
                     [&](const Box& b) { return lattice_points_in_box(d, lattice, b) > 0; });
}

std::string format_count(double n) {
  return n < 1e6 ? fmt::format("{:.0f}", n) : fmt::format("{:.2g}", n);
}

/// Refuse a scene whose model cannot fit in the memory available (or whose particles cannot be
/// indexed with 32 bits), from the estimate alone: nothing is enumerated or allocated, so a
/// request for 10^12 particles fails in microseconds instead of being killed by the OOM killer.
void check_resources(const Reader& r, const Scene& scene, const YAML::Node& spacing) {
  const ResourceEstimate e = estimate_resources(scene.model, scene.solver);
  const int dim = scene.model.dimension.dim;
  const std::string shrink =
      fmt::format("coarsen 'lattice.spacing' (memory grows as λ^-{}), shrink the bodies or lower "
                  "'horizon_factor' (bonds grow as m^{}); 'pd info' shows the estimate",
                  dim, dim);
  constexpr double max_particles = std::numeric_limits<std::uint32_t>::max();
  if (!(e.particles <= max_particles)) {
    r.fail(spacing,
           fmt::format("this scene has about {} particles; libpd indexes particles with 32 bits "
                       "(at most {:.3g})",
                       std::isfinite(e.particles) ? format_count(e.particles) : "infinitely many",
                       max_particles),
           shrink);
  }
  std::optional<MemoryBudget> budget;
  try {
    budget = available_memory();
  } catch (const std::invalid_argument& ex) {
    throw SceneError(r.file(), {}, ex.what(),
                     "unset PD_MEMORY_LIMIT or give it in bytes, e.g. PD_MEMORY_LIMIT=2G");
  }
  if (budget && !(e.bytes <= budget->bytes)) {
    const bool grid = e.grid_bytes > 0.5 * e.bytes;
    r.fail(spacing,
           fmt::format("this scene needs about {} ({} particles, {} bonds{}); {} {}",
                       format_bytes(e.bytes), format_count(e.particles), format_count(e.bonds),
                       grid ? ", most of it for the neighbour-search grid over the bounding box "
                              "of the bodies"
                            : "",
                       format_bytes(budget->bytes),
                       budget->source == "PD_MEMORY_LIMIT" ? "are allowed by PD_MEMORY_LIMIT"
                                                           : "are available"),
           grid ? "move the bodies closer together (the grid spans their bounding box with cells "
                  "of one horizon), or " +
                      shrink
                : shrink);
  }
}

/// Lattice positions are origin + kλ in double precision: far from 0 (in spacings) they lose the
/// digits that bond lengths need, and lattice indices beyond 2^63 cannot even be formed. 10^9
/// spacings keep positions exact to 10^-7 λ.
constexpr double max_spacings_from_zero = 1e9;

void check_coordinate(const Reader& r, const YAML::Node& node, const std::string& what, double x,
                      double spacing) {
  if (!(std::abs(x) / spacing <= max_spacings_from_zero)) {
    r.fail(node,
           fmt::format("{} has a coordinate {} m, more than 10^9 spacings ({} m each) from 0: "
                       "lattice positions that far out lose the precision bond lengths need",
                       what, format_number(x), format_number(spacing)),
           "move the scene's coordinates closer to 0, or coarsen the spacing");
  }
}

Scene read_scene(const YAML::Node& root, Reader& r) {
  Scene scene;
  ModelSpec& model = scene.model;
  const Fields top = r.open(root, root, root_section, {}, {}, "the scene");

  if (auto title = r.string(top, "title")) {
    scene.title = *title;
  }
  model.dimension.dim = *r.integer<int>(top, "dimension");
  r.dim = model.dimension.dim;
  if (auto plane = r.choice(top, "plane")) {
    model.dimension.plane = *plane == 0 ? PlaneMode::plane_stress : PlaneMode::plane_strain;
  }
  if (auto t = r.number(top, "thickness")) {
    model.dimension.thickness = *t;
  }
  if (auto a = r.number(top, "cross_section")) {
    model.dimension.cross_section = *a;
  }
  r.warn_foreign_keys(top);

  // Lattice.
  const Fields lat = r.section(top, "lattice");
  LatticeSpec& lattice = model.lattice;
  lattice.spacing = *r.number(lat, "spacing");
  if (auto m = r.number(lat, "horizon_factor")) {
    lattice.horizon_factor = *m;
  }
  if (auto c = r.choice(lat, "convention")) {
    lattice.convention = *c == 0 ? LatticeConvention::cell_centered : LatticeConvention::node_based;
  }
  if (auto o = r.vector(lat, "origin")) {
    lattice.origin = *o;
  }
  if (auto rule = r.choice(lat, "horizon_rule")) {
    model.horizon_rule = *rule == 0 ? HorizonRule::inclusive : HorizonRule::strict;
  }
  if (auto j = r.number(lat, "position_jitter")) {
    lattice.position_jitter = *j;
  }
  if (auto v = r.number(lat, "volume_variation")) {
    lattice.volume_variation = *v;
  }
  if (auto s = r.integer<std::uint64_t>(lat, "seed")) {
    lattice.seed = *s;
  }

  // Materials, in file order.
  std::vector<YAML::Node> material_nodes;
  std::vector<Fields> material_fields;
  {
    const Entry* e = r.lookup(top, "materials");
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
      for (const YAML::Node& previous : material_nodes) {
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
      mat.youngs_modulus = *r.number(f, "youngs_modulus");
      if (auto nu = r.number(f, "poisson_ratio")) {
        mat.poisson_ratio = *nu;
        const auto represented = bond_based_poisson_ratio(model.dimension);
        if (represented && std::abs(*nu - *represented) > 1e-9) {
          r.warn(f.find("poisson_ratio")->at(),
                 fmt::format("bond-based PD fixes ν = {} here; E is matched{}; ν = {} is not "
                             "represented",
                             model.dimension.dim == 2 &&
                                     model.dimension.plane == PlaneMode::plane_stress
                                 ? "1/3"
                                 : "1/4",
                             model.dimension.dim == 3 ? " (in 3D that equals matching the bulk "
                                                        "modulus, Miranda eq. 8)"
                                                      : "",
                             format_number(*nu)));
        }
      }
      mat.density = *r.number(f, "density");
      mat.fracture_energy = r.number(f, "fracture_energy");
      mat.critical_stretch = r.number(f, "critical_stretch");
      mat.yield_stretch = r.number(f, "yield_stretch");
      if (auto k = r.number(f, "stiffness_factor")) {
        mat.stiffness_factor = *k;
      }
      model.materials.push_back(std::move(mat));
      material_nodes.push_back(key);
      material_fields.push_back(f);
    }
  }
  std::vector<std::string_view> material_names;
  for (const Material& m : model.materials) {
    material_names.push_back(m.name);
  }

  // Bodies.
  std::vector<RegionUse> must_have_particles;
  std::vector<std::vector<YAML::Node>> body_box_nodes;
  {
    const auto list = r.items(top, "bodies");
    if (list.empty()) {
      r.fail(top.find("bodies")->at(), "'bodies' is empty: a scene needs at least one body",
             "add a body: '- name: bar', 'material: <name>', 'box: [[lo], [hi]]'");
    }
    if (list.size() > std::numeric_limits<std::uint16_t>::max()) {
      r.fail(top.find("bodies")->value, "too many bodies (at most 65535)",
             "merge bodies of the same material into one body with 'boxes'");
    }
    std::map<std::string, YAML::Node> names;
    for (std::size_t i = 0; i < list.size(); ++i) {
      const Fields f = r.item(list[i], body_section, "body", "bodies", i);
      BodySpec body;
      body.name = *r.string(f, "name");
      check_unique(r, names, body.name, f.find("name")->at(), "body");
      const Entry* m = f.find("material");
      const std::string material = *r.string(f, "material");
      const auto found = std::find(material_names.begin(), material_names.end(), material);
      if (found == material_names.end()) {
        r.fail(m->at(), fmt::format("body '{}' names unknown material '{}'", body.name, material),
               suggestion(material, material_names, "materials defined"));
      }
      body.material = static_cast<int>(found - material_names.begin());
      Reader::RegionRead region = r.region(f);
      body.region = region.region;
      must_have_particles.push_back(
          {body.region, region.node,
           fmt::format("body '{}' contains no lattice point", body.name)});
      body_box_nodes.push_back(region.box_nodes);
      model.bodies.push_back(std::move(body));
    }
  }

  // Supports.
  std::vector<RegionUse> must_touch_bodies;
  std::vector<YAML::Node> support_nodes; ///< where a support's own errors point
  {
    std::map<std::string, YAML::Node> names;
    const auto list = r.items(top, "supports");
    for (std::size_t i = 0; i < list.size(); ++i) {
      const Fields f = r.item(list[i], support_section, "support", "supports", i);
      SupportSpec s;
      s.name = *r.string(f, "name");
      check_unique(r, names, s.name, f.find("name")->at(), "support");
      Reader::RegionRead region = r.region(f);
      s.region = region.region;
      if (auto fixed = r.components(f, "fixed")) {
        s.fixed = *fixed;
      }
      std::array<YAML::Node, 3> nodes;
      const auto displacement = r.component_values(f, "displacement", nodes);
      for (int c = 0; c < 3; ++c) {
        if (!displacement[c]) {
          continue;
        }
        if (s.fixed[c]) {
          r.fail(nodes[c],
                 fmt::format("support '{}' both fixes and displaces component {}", s.name,
                             axis_names[c]),
                 fmt::format("'fixed' means zero displacement: remove {} from 'fixed' or from "
                             "'displacement'",
                             axis_names[c]));
        }
        s.prescribed[c] = true;
        s.displacement[c] = *displacement[c];
      }
      std::array<YAML::Node, 3> mirror_nodes;
      const auto mirror = r.component_values(f, "mirror", mirror_nodes);
      support_nodes.push_back(f.has("mirror") ? f.find("mirror")->at() : f.anchor);
      for (int c = 0; c < 3; ++c) {
        if (mirror[c]) {
          s.mirror[c] = true;
          s.mirror_at[c] = *mirror[c];
        }
      }
      const bool holds =
          std::any_of(s.fixed.begin(), s.fixed.end(), [](bool b) { return b; }) ||
          std::any_of(s.prescribed.begin(), s.prescribed.end(), [](bool b) { return b; });
      if (s.mirrors() && holds) {
        r.fail(f.find("mirror")->at(),
               fmt::format("support '{}' both mirrors and fixes or displaces", s.name),
               "a mirror support moves all three components with the body: remove 'fixed' and "
               "'displacement', or 'mirror'");
      }
      if (!holds && !s.mirrors()) {
        r.fail(f.anchor,
               fmt::format("support '{}' neither fixes nor displaces any component", s.name),
               "add 'fixed: [x, ...]', 'displacement: {x: value}' or 'mirror: {x: value}'");
      }
      must_touch_bodies.push_back(
          {s.region, region.node,
           fmt::format("support '{}' selects no particle: its region holds no lattice point of "
                       "any body",
                       s.name)});
      model.supports.push_back(std::move(s));
    }
  }

  // Loads.
  {
    std::map<std::string, YAML::Node> names;
    const auto list = r.items(top, "loads");
    for (std::size_t i = 0; i < list.size(); ++i) {
      const Fields f = r.item(list[i], load_section, "load", "loads", i);
      LoadSpec l;
      l.name = *r.string(f, "name");
      check_unique(r, names, l.name, f.find("name")->at(), "load");
      Reader::RegionRead region = r.region(f);
      l.load.region = region.region;
      if (auto kind = r.choice(f, "type")) {
        l.load.kind = static_cast<BoxRegionLoad::Kind>(*kind);
      }
      l.load.value = *r.vector(f, "value");
      r.check_in_space(f.find("value")->at(), f.label("value"), l.load.value);
      const bool needs_measure = l.load.kind == BoxRegionLoad::Kind::per_area ||
                                 l.load.kind == BoxRegionLoad::Kind::per_length;
      if (auto measure = r.number(f, "measure")) {
        if (!needs_measure) {
          r.fail(f.find("measure")->name,
                 fmt::format("'measure' of load '{}' applies only to per_area and per_length loads",
                             l.name),
                 "remove it: total and body loads need no area or length");
        }
        l.load.measure = *measure;
      } else if (needs_measure) {
        r.fail(
            f.anchor,
            fmt::format("load '{}' of type {} needs 'measure', the loaded {}", l.name,
                        l.load.kind == BoxRegionLoad::Kind::per_area ? "per_area" : "per_length",
                        l.load.kind == BoxRegionLoad::Kind::per_area ? "area [m²]" : "length [m]"),
            "add e.g. 'measure: 0.01'");
      }
      if (l.load.kind == BoxRegionLoad::Kind::body) {
        model.effects.body_force = true;
      }
      must_touch_bodies.push_back(
          {l.load.region, region.node, fmt::format("load '{}' acts on no particle", l.name)});
      model.loads.push_back(std::move(l));
    }
  }

  // Effects.
  YAML::Node damping_effect;
  for (const auto& [w, node] : r.names(top, "effects")) {
    switch (w) {
    case 0:
      model.effects.damage = true;
      break;
    case 1:
      model.effects.plasticity = true;
      break;
    default:
      model.effects.damping = true;
      damping_effect = node;
      break;
    }
  }

  // Model options.
  const Fields mod = r.section(top, "model");
  if (auto s = r.choice(mod, "stretch")) {
    model.effects.stretch = static_cast<StretchKind>(*s);
  }
  // Scene files default to the pair picked from the block-tension measurements (tensor + moment:
  // +0.35 % elongation, +0.59 % lateral contraction); ModelSpec's own default stays the bare
  // model (none + none) for code that assembles models directly.
  const auto surface = r.choice(mod, "surface_correction");
  model.surface_correction =
      surface ? static_cast<SurfaceCorrection>(*surface) : SurfaceCorrection::tensor;
  const auto volume = r.choice(mod, "volume_correction");
  model.volume_correction =
      volume ? static_cast<VolumeCorrection>(*volume) : VolumeCorrection::moment;

  // Solver.
  const Fields sol = r.section(top, "solver");
  SolverSpec& solver = scene.solver;
  if (auto i = r.choice(sol, "integrator")) {
    solver.integrator = static_cast<IntegratorKind>(*i);
  }
  solver.dt = r.number_or_auto(sol, "dt");
  if (auto s = r.number(sol, "safety")) {
    solver.safety = *s;
  }
  solver.end_time = r.number(sol, "end_time");
  if (auto t = r.number(sol, "ramp_time")) {
    solver.ramp_time = *t;
  }
  if (auto c = r.number(sol, "damping")) {
    solver.damping = *c;
  }
  if (auto n = r.integer<std::size_t>(sol, "max_steps")) {
    solver.max_steps = *n;
  }
  if (auto b = r.number(sol, "blowup_displacement")) {
    solver.blowup_displacement = *b;
  }
  if (sol.has("steady")) {
    const Fields st = r.section(sol, "steady");
    solver.steady.enabled = true;
    if (auto k = r.number(st, "kinetic_tolerance")) {
      solver.steady.kinetic_tolerance = *k;
    }
    if (auto k = r.number(st, "force_tolerance")) {
      solver.steady.force_tolerance = *k;
    }
    if (auto n = r.integer<std::size_t>(st, "check_every")) {
      solver.steady.check_every = *n;
    }
  }
  if (sol.has("arkode")) {
    const Fields ak = r.section(sol, "arkode");
    if (auto t = r.choice(ak, "table")) {
      solver.arkode.table = static_cast<ArkodeTable>(*t);
    }
    if (auto a = r.boolean(ak, "adaptive")) {
      solver.arkode.adaptive = *a;
    }
    if (auto x = r.number(ak, "rtol")) {
      solver.arkode.rtol = *x;
    }
    if (auto x = r.number(ak, "atol")) {
      solver.arkode.atol = *x;
    }
  }

  // Initial state.
  const Fields ini = r.section(top, "initial");
  if (auto h = r.matrix(ini, "displacement_gradient")) {
    scene.initial.displacement_gradient = *h;
  }
  if (auto a = r.vector(ini, "about")) {
    scene.initial.about = *a;
  }
  if (auto v = r.vector(ini, "velocity")) {
    r.check_in_space(ini.find("velocity")->at(), ini.label("velocity"), *v);
    scene.initial.velocity = *v;
  }

  // Probes.
  std::vector<std::pair<Vec3, YAML::Node>> probe_points;
  std::vector<std::string> probe_point_names;
  {
    std::map<std::string, YAML::Node> names;
    const auto list = r.items(top, "probes");
    for (std::size_t i = 0; i < list.size(); ++i) {
      const Fields f = r.item(list[i], probe_section, "probe", "probes", i);
      ProbeSpec p;
      p.name = *r.string(f, "name");
      check_unique(r, names, p.name, f.find("name")->at(), "probe");
      if (auto point = r.vector(f, "point")) {
        p.kind = ProbeSpec::Kind::point;
        p.point = *point;
        probe_points.emplace_back(p.point, f.find("point")->at());
        probe_point_names.push_back(p.name);
      } else {
        p.kind = ProbeSpec::Kind::region;
        Reader::RegionRead region = r.region(f);
        p.region = region.region;
        must_touch_bodies.push_back(
            {p.region, region.node,
             fmt::format("probe '{}' averages over no particle: its region holds no lattice point "
                         "of any body",
                         p.name)});
      }
      if (const Entry* c = f.find("component")) {
        p.component = r.component(c->at(), f.label("component"));
      }
      scene.probes.push_back(std::move(p));
    }
  }

  // Output.
  const Fields out = r.section(top, "output");
  if (auto v = r.boolean(out, "vtu")) {
    scene.output.vtu = *v;
  }
  if (auto n = r.integer<std::size_t>(out, "vtu_every")) {
    scene.output.vtu_every = *n;
  }
  if (auto n = r.integer<std::size_t>(out, "history_every")) {
    scene.output.history_every = *n;
  }

  // ---- Consistency between sections.
  for (std::size_t i = 0; i < model.materials.size(); ++i) {
    const Material& m = model.materials[i];
    if (model.effects.damage && !m.fracture_energy && !m.critical_stretch) {
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
    const Fields& f = material_fields[i];
    for (const char* key : {"fracture_energy", "critical_stretch"}) {
      if (f.has(key) && !model.effects.damage) {
        r.warn(f.find(key)->name,
               fmt::format("'{}' of material '{}' is unused: the 'damage' effect is not listed",
                           key, m.name));
      }
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
  if (solver.damping > 0 && !model.effects.damping) {
    r.fail(sol.find("damping")->at(),
           fmt::format("'solver.damping' is {} but the 'damping' effect is not listed",
                       format_number(solver.damping)),
           top.has("effects") ? "add 'damping' to 'effects', or set 'damping: 0'"
                              : "add 'effects: [damping]', or set 'damping: 0'");
  }
  if (model.effects.damping && !(solver.damping > 0)) {
    r.fail(damping_effect, "effect 'damping' is listed but 'solver.damping' is 0",
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
  if (!solver.end_time && !solver.steady.enabled) {
    r.fail(sol.anchor,
           "neither 'solver.end_time' nor 'solver.steady' is given: the run would not "
           "stop",
           "add 'end_time: T' [s] or a 'steady:' section under 'solver'");
  }
  if (solver.end_time && solver.ramp_time > *solver.end_time) {
    r.warn(sol.find("ramp_time")->at(),
           fmt::format("'solver.ramp_time' ({} s) exceeds 'solver.end_time' ({} s): the full load "
                       "is never reached",
                       format_number(solver.ramp_time), format_number(*solver.end_time)));
  }
  if (scene.output.history_every > 0 && scene.probes.empty()) {
    r.warn(out.find("history_every")->at(),
           "'output.history_every' is set but there are no probes: no history is written");
  }

  // ---- Resources: before anything is enumerated or allocated.
  check_resources(r, scene, lat.find("spacing")->at());
  const ModelDimension& d = model.dimension;
  const int dim = d.dim;
  for (int a = 0; a < dim; ++a) {
    if (lat.has("origin")) {
      check_coordinate(r, lat.find("origin")->at(), "'lattice.origin'", lattice.origin[a],
                       lattice.spacing);
    }
  }
  for (std::size_t i = 0; i < model.bodies.size(); ++i) {
    const auto& boxes = model.bodies[i].region.boxes;
    for (std::size_t k = 0; k < boxes.size(); ++k) {
      for (int a = 0; a < dim; ++a) {
        for (double x : {boxes[k].lo[a], boxes[k].hi[a]}) {
          check_coordinate(r, body_box_nodes[i][k],
                           fmt::format("a box of body '{}'", model.bodies[i].name), x,
                           lattice.spacing);
        }
      }
    }
  }

  // ---- Regions, against the lattice.
  for (const RegionUse& use : must_have_particles) {
    if (!holds_lattice_point(d, lattice, use.region)) {
      r.fail(use.node, use.what + fmt::format(" (spacing {} m)", format_number(lattice.spacing)),
             "enlarge the box to at least one spacing in every direction, or refine the spacing");
    }
  }
  for (std::size_t i = 0; i < model.bodies.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      const BodySpec& a = model.bodies[j];
      const BodySpec& b = model.bodies[i];
      if (a.material == b.material) {
        continue;
      }
      for (std::size_t k = 0; k < b.region.boxes.size(); ++k) {
        const Region common =
            intersect_with_bodies(Region{{b.region.boxes[k]}}, {a}, dim, lattice.spacing);
        if (holds_lattice_point(d, lattice, common)) {
          r.fail(body_box_nodes[i][k],
                 fmt::format("bodies '{}' and '{}' overlap but have different materials ('{}' and "
                             "'{}')",
                             a.name, b.name, model.materials[a.material].name,
                             model.materials[b.material].name),
                 fmt::format("shared particles would silently belong to '{}' (listed first); "
                             "separate the boxes or use one material",
                             a.name));
        }
      }
    }
  }
  for (const RegionUse& use : must_touch_bodies) {
    const Region common = intersect_with_bodies(use.region, model.bodies, dim, lattice.spacing);
    if (!holds_lattice_point(d, lattice, common)) {
      r.fail(use.node, use.what,
             "move or enlarge the box so that it contains particles of a body (particles sit at "
             "lattice points inside the body boxes)");
    }
  }
  for (std::size_t i = 0; i < probe_points.size(); ++i) {
    const auto& [p, node] = probe_points[i];
    double nearest = inf;
    for (const BodySpec& b : model.bodies) {
      for (const Box& box : b.region.boxes) {
        nearest = std::min(nearest, distance_to_box(p, box, dim));
      }
    }
    if (nearest > lattice.spacing * (1 + 1e-9)) {
      r.fail(node,
             fmt::format("probe '{}' is {} m from the nearest body, farther than one spacing ({} "
                         "m)",
                         probe_point_names[i], fmt::format("{:.3g}", nearest),
                         format_number(lattice.spacing)),
             "put the point inside a body or on its surface");
    }
  }
  // Mirror supports need each image to be a free particle: only the lattice can tell (the memory
  // guard has passed, so generating the particles is affordable).
  if (std::any_of(model.supports.begin(), model.supports.end(),
                  [](const SupportSpec& s) { return s.mirrors(); })) {
    try {
      support_constraints(model, generate_lattice(model.dimension, lattice, model.bodies));
    } catch (const SupportError& e) {
      r.fail(support_nodes.at(e.support), e.what(),
             "a mirror support needs a regular lattice (no position_jitter), a plane on a cell "
             "face, and free body particles beyond the plane at least as far as the support "
             "reaches");
    }
  }
  return scene;
}

/// Records where the root node of each document starts.
class DocumentScan : public YAML::EventHandler {
public:
  std::vector<YAML::Mark> roots;

  void OnDocumentStart(const YAML::Mark&) override { pending_ = true; }
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark& m, YAML::anchor_t) override { root(m); }
  void OnAlias(const YAML::Mark& m, YAML::anchor_t) override { root(m); }
  void OnScalar(const YAML::Mark& m, const std::string&, YAML::anchor_t,
                const std::string&) override {
    root(m);
  }
  void OnSequenceStart(const YAML::Mark& m, const std::string&, YAML::anchor_t,
                       YAML::EmitterStyle::value) override {
    root(m);
  }
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark& m, const std::string&, YAML::anchor_t,
                  YAML::EmitterStyle::value) override {
    root(m);
  }
  void OnMapEnd() override {}

private:
  bool pending_ = false;
  void root(const YAML::Mark& m) {
    if (pending_) {
      roots.push_back(m);
      pending_ = false;
    }
  }
};

struct TextPosition {
  int line = 0; ///< 0: none
  int column = 0;
  char c = 0;
};

/// The first character outside comments, white space and document markers ('---', '...'),
/// 1-based, if any.
TextPosition first_content(const std::string& text) {
  std::istringstream lines(text);
  std::string l;
  for (int line = 1; std::getline(lines, l); ++line) {
    const std::size_t at = l.find_first_not_of(" \t\r");
    if (at == std::string::npos || l[at] == '#' || l.compare(at, 3, "---") == 0 ||
        l.compare(at, 3, "...") == 0) {
      continue;
    }
    return {line, static_cast<int>(at) + 1, l[at]};
  }
  return {};
}

std::string malformed_hint(const std::string& msg, const std::string& text, int line) {
  // yaml-cpp reports a tab as "illegal map value" or the like; the line itself tells.
  std::istringstream lines(text);
  std::string current;
  for (int i = 0; i <= line && std::getline(lines, current); ++i) {
    if (i >= line - 1 && current.find('\t') != std::string::npos) {
      return fmt::format("line {} contains a tab: YAML indentation must use spaces only", i + 1);
    }
  }
  // yaml-cpp's depth guard reports runaway nesting as "bad file".
  if (msg.find("bad file") != std::string::npos) {
    return "the brackets nest too deeply; a scene needs at most three levels ([[[x], [x]]])";
  }
  if (msg.find("sequence flow") != std::string::npos) {
    return "a '[' is not closed by a matching ']'";
  }
  if (msg.find("map flow") != std::string::npos) {
    return "a '{' is not closed by a matching '}'";
  }
  if (msg.find("anchor") != std::string::npos) {
    return "define an anchor with '&name' before referring to it with '*name'";
  }
  if (msg.find("tab") != std::string::npos || msg.find("block entry") != std::string::npos) {
    return "indent with spaces only, and align list items '-' under their key";
  }
  if (msg.find("map value") != std::string::npos) {
    return "check the indentation of this line, and quote values that contain ': '";
  }
  if (msg.find("quote") != std::string::npos || msg.find("end of") != std::string::npos) {
    return "close the quoted string or bracket that starts here";
  }
  return "check the indentation (spaces only) and that every bracket and quote is closed";
}

Scene parse(const std::string& text, const std::string& name) {
  Scene scene;
  std::vector<std::string> warnings;
  Reader r(name, warnings);
  try {
    // Not YAML::LoadAll: yaml-cpp 0.7 loops forever on some malformed streams (one starting
    // with ',', jbeder/yaml-cpp#1040, fixed upstream by PR #1319), appending empty documents
    // until memory runs out. Scan at most two documents with the event parser instead.
    std::istringstream stream(text);
    YAML::Parser parser(stream);
    DocumentScan scan;
    for (int documents = 0; documents < 2 && parser.HandleNextDocument(scan); ++documents) {
    }
    const YAML::Node root = YAML::Load(text);
    if (root.IsNull()) {
      const auto [line, column, c] = first_content(text);
      if (line > 0) {
        throw SceneError(
            name, {line, column},
            fmt::format("malformed YAML: unexpected '{}' where the scene should start", c),
            "a scene is a map of 'key: value' lines; remove the stray character");
      }
      throw SceneError(name, {1, 1}, "the scene is empty",
                       "start from the template printed by 'pd run --print-defaults'");
    }
    if (scan.roots.size() > 1) {
      const YAML::Mark& m = scan.roots[1];
      throw SceneError(name, {m.line + 1, m.column + 1},
                       "a scene file holds one YAML document, found a second one",
                       "remove the '---' separator and everything after it, or split the file");
    }
    scene = read_scene(root, r);
  } catch (const SceneError&) {
    throw;
  } catch (const YAML::Exception& e) {
    const SourceMark mark =
        e.mark.is_null() ? SourceMark{} : SourceMark{e.mark.line + 1, e.mark.column + 1};
    throw SceneError(name, mark, "malformed YAML: " + e.msg,
                     malformed_hint(e.msg, text, e.mark.line));
  } catch (const std::exception& e) {
    // Only a defect of the checks above gets here; still report it in the promised form.
    throw SceneError(name, {}, fmt::format("internal error while reading the scene: {}", e.what()),
                     "please report this scene to the libpd developers");
  }
  scene.warnings = std::move(warnings);
  return scene;
}

// ---------------------------------------------------------------------------------------------
// Template
// ---------------------------------------------------------------------------------------------

std::string key_summary(const Key& k, const Section& s) {
  std::string out(k.doc);
  std::vector<std::string> facts;
  if (!k.unit.empty() && k.type != Type::integer) {
    facts.push_back(fmt::format("[{}]", k.unit));
  }
  if ((k.type == Type::number || k.type == Type::integer || k.type == Type::number_or_auto) &&
      !k.range.unbounded()) {
    facts.push_back(range_text(k.range));
  }
  if (k.type == Type::choice || k.type == Type::names) {
    facts.push_back("one of: " + join(split_choices(k.choices), " | "));
  }
  if (k.only_dim != 0) {
    facts.push_back(fmt::format("{}D only", k.only_dim));
  }
  if (k.group != 0) {
    std::vector<std::string_view> others;
    for (const Key& o : s.keys) {
      if (o.group == k.group && o.name != k.name) {
        others.push_back(o.name);
      }
    }
    facts.push_back(fmt::format("alternative to {} ({})", quoted_list(others),
                                k.need == Need::one_of ? "give exactly one" : "give at most one"));
  }
  if (k.need == Need::required) {
    facts.emplace_back("required");
  } else if (k.need == Need::optional) {
    facts.push_back(k.fallback.empty() ? std::string("optional")
                                       : fmt::format("default {}", k.fallback));
  }
  for (std::size_t i = 0; i < facts.size(); ++i) {
    out += (i == 0 ? "; " : ", ") + facts[i];
  }
  return out;
}

/// Word-wrap `text` into lines of at most `width` characters (never breaking a word).
std::vector<std::string> wrap(const std::string& text, std::size_t width) {
  std::vector<std::string> lines;
  std::istringstream words(text);
  std::string w;
  std::string line;
  while (words >> w) {
    if (!line.empty() && line.size() + 1 + w.size() > width) {
      lines.push_back(line);
      line.clear();
    }
    line += (line.empty() ? "" : " ") + w;
  }
  if (!line.empty()) {
    lines.push_back(line);
  }
  return lines;
}

/// Lines are `lead + indent spaces + text`; a commented key moves its whole subtree behind "# ".
/// For list items the first key carries the "- ".
void write_section(std::string& out, const Section& s, const std::string& lead, std::size_t indent,
                   bool list_item) {
  bool first = true;
  for (const Key& k : s.keys) {
    if (lead.empty() && indent == 0) {
      out += "\n";
    }
    const std::string pad(indent, ' ');
    const std::size_t width = lead.size() + indent + 2 < 90 ? 98 - lead.size() - indent - 2 : 8;
    for (const std::string& line : wrap(key_summary(k, s), width)) {
      out += lead + pad + "# " + line + "\n";
    }
    std::string key_lead = lead;
    std::size_t key_indent = indent;
    if (k.show == Show::commented) {
      key_lead = lead + pad + "# ";
      key_indent = 0;
    }
    std::string head = key_lead + std::string(key_indent, ' ');
    if (list_item && first) {
      head = key_lead + std::string(key_indent - 2, ' ') + "- ";
    }
    first = false;
    switch (k.type) {
    case Type::section:
      out += head + std::string(k.name) + ":\n";
      write_section(out, *k.section, key_lead, key_indent + 2, false);
      break;
    case Type::list:
      out += head + std::string(k.name) + ":\n";
      write_section(out, *k.section, key_lead, key_indent + 4, true);
      break;
    case Type::named_map:
      out += head + std::string(k.name) + ":\n";
      out += key_lead + std::string(key_indent + 2, ' ') + std::string(k.example) + ":\n";
      write_section(out, *k.section, key_lead, key_indent + 4, false);
      break;
    default:
      out += head + fmt::format("{}: {}\n", k.name, k.fallback.empty() ? k.example : k.fallback);
      break;
    }
  }
}

} // namespace

Scene parse_scene(const std::string& text, const std::string& name) {
  return parse(text, name);
}

Scene load_scene(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    throw SceneError(path, {}, "cannot read the scene: it is a directory",
                     "give the path of a .yaml scene file");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    throw SceneError(path, {}, fmt::format("cannot open the scene file: {}", std::strerror(errno)),
                     "check the path and the file's permissions");
  }
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) {
    throw SceneError(path, {}, "cannot read the scene file", "check the file's permissions");
  }
  Scene scene = parse(text.str(), path);
  scene.path = path;
  return scene;
}

std::string scene_template() {
  std::string out =
      "# libpd scene template, generated from the scene schema (pd run --print-defaults).\n"
      "# Every key is listed with its meaning, unit, allowed range and default. Optional keys\n"
      "# and alternatives are commented out: remove the '# ' to use them. See SCENE_FORMAT.md.\n";
  write_section(out, root_section, {}, 0, false);
  return out;
}

} // namespace pd
