// The reader of scene files: a YAML map checked against its section of the schema (`Fields`),
// and typed reads of its keys that report every problem as file:line:column with a hint
// (`Reader`). The section readers (one file per section) are written in terms of these.
#pragma once

#include "libpd/io/scene.hpp"
#include "schema.hpp"

#include <array>
#include <charconv>
#include <cmath>
#include <fmt/format.h>
#include <limits>
#include <map>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>
#include <yaml-cpp/yaml.h>

namespace pd::scene {

// ---- Text helpers

std::string join(std::span<const std::string_view> words, std::string_view separator);
/// "'a', 'b' or 'c'"
std::string quoted_list(const std::vector<std::string_view>& words);
/// The candidate a typo most likely meant, if any is close enough to be a plausible typo.
std::optional<std::string_view> closest(std::string_view word,
                                        std::span<const std::string_view> candidates);
/// "did you mean 'fast'? (allowed: exact, modified, fast)"
std::string suggestion(std::string_view word, std::span<const std::string_view> candidates,
                       std::string_view allowed_label = "allowed");
/// How a node reads in a message: "'abc'", "a list", "nothing", ...
std::string describe(const YAML::Node& n);
std::string unit_suffix(std::string_view unit);
std::string range_text(const Range& r);
std::string format_number(double v);
/// A default as YAML: numbers in their shortest form with a plain exponent (1e-6, not 1e-06).
std::string yaml_number(double v);

inline constexpr std::array<std::string_view, 3> axis_names{"x", "y", "z"};

inline std::span<const std::string_view> axes(int dim) {
  return std::span(axis_names).first(static_cast<std::size_t>(dim));
}

SourceMark source_mark(const YAML::Node& n);

enum class NumberText { ok, not_a_number, non_finite, out_of_range };
NumberText parse_double(std::string_view text, double& value);

// ---- Fields of one map

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

/// "'key: value'" as a hint writes it.
std::string example_line(const Key& k);

/// A key of the given section, by name; the reader only asks for keys that the tables declare.
const Key& key_of(const Section& s, std::string_view name);

// ---- Reader

class Reader {
public:
  Reader(std::string file, std::vector<std::string>& warnings)
      : file_(std::move(file)), warnings_(warnings) {}

  int dim = 3;

  const std::string& file() const { return file_; }

  [[noreturn]] void fail(const YAML::Node& at, const std::string& what,
                         const std::string& hint) const;

  void warn(const YAML::Node& at, const std::string& what);

  /// Check a map's keys against its section: unknown, duplicate and conflicting keys (missing
  /// ones are caught by `lookup` when read). `node` may be null (an empty section); `anchor` then
  /// stands in for it in messages.
  Fields open(const YAML::Node& node, const YAML::Node& anchor, const Section& schema,
              std::string prefix, std::string owner, const std::string& what) const;

  /// The entry of `key`, or nullptr if it is absent and may be. Required keys are checked here,
  /// when they are read, so that problems are reported in reading order rather than all
  /// missing keys first.
  const Entry* lookup(const Fields& f, std::string_view key) const;

  Fields section(const Fields& parent, std::string_view key) const;

  /// Items of a list; an empty value is an empty list.
  std::vector<YAML::Node> items(const Fields& f, std::string_view key) const;

  /// A list item's fields; its owner label uses its name if it has one.
  Fields item(const YAML::Node& node, const Section& schema, std::string_view kind,
              std::string_view list, std::size_t index) const;

  std::optional<std::string> string(const Fields& f, std::string_view key) const;

  double to_number(const YAML::Node& n, const std::string& label, std::string_view unit,
                   const std::string& example) const;

  void check_range(const YAML::Node& n, const std::string& label, const Key& k, double v) const;

  std::optional<double> number(const Fields& f, std::string_view key) const;

  /// nullopt for `auto` or an absent key.
  std::optional<double> number_or_auto(const Fields& f, std::string_view key) const;

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

  std::optional<bool> boolean(const Fields& f, std::string_view key) const;

  /// The index of the word `n` in `choices`.
  int word(const YAML::Node& n, const std::string& label,
           std::span<const std::string_view> choices) const;

  std::optional<int> choice(const Fields& f, std::string_view key) const;

  /// A point or vector: `dim` to 3 numbers, missing trailing ones are 0.
  Vec3 coordinates(const YAML::Node& n, const std::string& label, std::string_view unit) const;

  /// Physical vectors (forces, velocities) may not point out of the modelled space.
  void check_in_space(const YAML::Node& n, const std::string& label, const Vec3& v) const;

  std::optional<Vec3> vector(const Fields& f, std::string_view key) const;

  std::optional<std::array<std::array<double, 3>, 3>> matrix(const Fields& f,
                                                             std::string_view key) const;

  Box box(const YAML::Node& n, const std::string& label) const;

  struct RegionRead {
    Region region;
    std::vector<YAML::Node> box_nodes; ///< one per box, for messages about a single box
    YAML::Node node;                   ///< the box or boxes value
  };

  /// The `box`, `boxes` or `group` key of a section that declares them (exactly one is present).
  RegionRead region(const Fields& f) const;

  /// The physical groups of the mesh bodies read so far (name → their particles' positions,
  /// sorted): what a `group` key names. A name two bodies share names both bodies' particles.
  std::map<std::string, std::vector<Vec3>> mesh_groups;
  std::vector<std::string> mesh_files; ///< the files of the mesh bodies read so far, for messages

  int component(const YAML::Node& n, const std::string& label) const;

  std::optional<std::array<bool, 3>> components(const Fields& f, std::string_view key) const;

  std::array<std::optional<double>, 3> component_values(const Fields& f, std::string_view key,
                                                        std::array<YAML::Node, 3>& nodes) const;

  /// Words of a `names` key, each with its node.
  std::vector<std::pair<int, YAML::Node>> names(const Fields& f, std::string_view key) const;

  /// Store every key of `f` that the schema binds to a field of `target` (the others are read by
  /// hand), in table order: the order in which problems are found and reported.
  template <class Target>
  void read_bound(const Fields& f, Target& target) const {
    for (const Key& k : f.schema->keys) {
      if (k.bind.store == nullptr) {
        continue;
      }
      if (*k.bind.target != typeid(Target)) {
        throw std::logic_error(fmt::format("scene schema binds '{}' to another struct", k.name));
      }
      k.bind.store(*this, f, k.name, &target);
    }
  }

  /// Keys that only mean something in one dimension are ignored elsewhere; say so.
  void warn_foreign_keys(const Fields& f);

private:
  std::string file_;
  std::vector<std::string>& warnings_;

  static std::string unknown_key_hint(const std::string& name, const Section& schema);

  void check_alternatives(const Fields& f) const;
};

} // namespace pd::scene
