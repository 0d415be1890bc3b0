// The scene schema: how a key of a scene file is declared (type, unit, range, default,
// documentation) and bound to the field it fills, and the sections that group the keys.
//
// Each section's table lives beside the function that reads it (one file per section); this
// header only declares them, so that the reader can name a key's true section in a hint and the
// template writer can walk them all.
#pragma once

#include <limits>
#include <span>
#include <string>
#include <string_view>
#include <typeinfo>

namespace pd::scene {

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
  points,           ///< list of points
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

class Reader;
struct Fields;
struct Section;

/// Where a key's value goes: the field of a struct it is stored in (see bind.hpp), and the
/// field's default as the template writes it, taken from a default-constructed struct so that the
/// default is written once, in the struct. Keys whose reading has real logic have no `store` and
/// are read by hand.
struct Binder {
  const std::type_info* target = nullptr; ///< the struct `store` writes into
  void (*store)(const Reader&, const Fields&, std::string_view key, void* target) = nullptr;
  std::string (*default_text)() = nullptr;
};

struct Key {
  std::string_view name;
  Type type;
  std::string_view doc;
  std::string_view unit{};
  Range range{};
  std::span<const std::string_view> choices{}; ///< words of a choice or names key
  std::string_view fallback{}; ///< the default, as YAML, where no struct field holds it
  std::string_view example{};  ///< template value of keys without a default
  Need need = Need::optional;
  int group = 0;
  int only_dim = 0; ///< 0: any dimension
  Show show = Show::active;
  const Section* section = nullptr; ///< section, list, named_map
  std::string_view range_hint{};    ///< hint for out-of-range values; generic if empty
  Binder bind{};
};

/// The key's default as YAML text (empty: none).
inline std::string default_text(const Key& k) {
  return k.bind.default_text != nullptr ? k.bind.default_text() : std::string(k.fallback);
}

struct Section {
  std::string_view place; ///< "under 'lattice'", for messages
  std::span<const Key> keys;
};

extern const Section root_section;
extern const Section lattice_section;
extern const Section material_section;
extern const Section body_section;
extern const Section shape_section;
extern const Section crack_section;
extern const Section cylinder_section;
extern const Section sphere_section;
extern const Section half_space_section;
extern const Section surface_section;
extern const Section support_section;
extern const Section load_section;
extern const Section model_section;
extern const Section solver_section;
extern const Section steady_section;
extern const Section arkode_section;
extern const Section stop_when_section;
extern const Section initial_section;
extern const Section probe_section;
extern const Section output_section;

} // namespace pd::scene
