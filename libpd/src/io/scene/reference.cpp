// The scene reference (`pd run --print-scene-reference`, docs/scene-reference.md): one Markdown
// table per section with every key's type, unit, allowed values, default and meaning. Like the
// template it walks the schema tables the reader checks against, so the manual cannot drift from
// the reader; the prose around it (docs/scenes.md) says what the keys mean together.
#include "reader.hpp"

#include <cctype>
#include <utility>
#include <vector>

namespace pd {

namespace scene {

namespace {

std::string type_word(Type t) {
  switch (t) {
  case Type::string:
    return "string";
  case Type::integer:
    return "integer";
  case Type::number:
    return "number";
  case Type::number_or_auto:
    return "`auto` or number";
  case Type::boolean:
    return "boolean";
  case Type::choice:
    return "word";
  case Type::vector:
    return "vector";
  case Type::matrix:
    return "matrix (rows of vectors)";
  case Type::box:
    return "box `[[lo], [hi]]`";
  case Type::boxes:
    return "list of boxes";
  case Type::points:
    return "list of points";
  case Type::components:
    return "list of `x`, `y`, `z`";
  case Type::component_values:
    return "map `x`/`y`/`z` → number";
  case Type::names:
    return "list of words";
  case Type::section:
    return "map";
  case Type::list:
    return "list of maps";
  case Type::named_map:
    return "map name → map";
  }
  return "?";
}

/// A table cell: a `|` in the text would end the cell.
std::string cell(std::string_view text) {
  std::string out;
  for (const char c : text) {
    if (c == '|') {
      out += "\\|";
    } else {
      out += c;
    }
  }
  return out;
}

std::string code_list(std::span<const std::string_view> words) {
  std::string out;
  for (std::size_t i = 0; i < words.size(); ++i) {
    out += fmt::format("{}`{}`", i == 0 ? "" : ", ", words[i]);
  }
  return out;
}

/// The key's alternatives in its section (the other keys of its group).
std::vector<std::string_view> alternatives(const Key& k, const Section& s) {
  std::vector<std::string_view> names;
  for (const Key& o : s.keys) {
    if (k.group != 0 && o.group == k.group && o.name != k.name) {
      names.push_back(o.name);
    }
  }
  return names;
}

std::string allowed(const Key& k, const Section& s) {
  std::vector<std::string> facts;
  if ((k.type == Type::number || k.type == Type::integer || k.type == Type::number_or_auto) &&
      !k.range.unbounded()) {
    facts.push_back(range_text(k.range));
  }
  if (k.type == Type::choice || k.type == Type::names) {
    facts.push_back(code_list(k.choices));
  }
  if (k.only_dim != 0) {
    facts.push_back(fmt::format("{}D only", k.only_dim));
  }
  if (const auto others = alternatives(k, s); !others.empty()) {
    facts.push_back(fmt::format("instead of {}", code_list(others)));
  }
  std::string out;
  for (std::size_t i = 0; i < facts.size(); ++i) {
    out += (i == 0 ? "" : "; ") + facts[i];
  }
  return out;
}

std::string default_cell(const Key& k) {
  switch (k.need) {
  case Need::required:
    return "required";
  case Need::one_of:
    return "one of the group required";
  case Need::optional:
    break;
  }
  const std::string fallback = default_text(k);
  return fallback.empty() ? "—" : fmt::format("`{}`", fallback);
}

/// GitHub's anchor of a heading: lower case, spaces to '-', other punctuation dropped.
std::string anchor(std::string_view heading) {
  std::string out;
  for (const char c : heading) {
    if (std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '-' || c == '_') {
      out += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    } else if (c == ' ') {
      out += '-';
    }
  }
  return out;
}

/// The path under which a nested section's keys are written: `solver.steady`, `bodies[]`,
/// `materials.NAME`.
std::string child_path(const std::string& path, const Key& k) {
  const std::string base = path.empty() ? std::string(k.name) : path + "." + std::string(k.name);
  switch (k.type) {
  case Type::list:
    return base + "[]";
  case Type::named_map:
    return base + ".NAME";
  default:
    return base;
  }
}

struct Writer {
  std::string out;
  /// Sections already written, with their heading: a section met again (a cylinder in a body and
  /// in its `minus`) links to the first.
  std::vector<std::pair<const Section*, std::string>> written;

  std::string heading_of(const Section* s) const {
    for (const auto& [section, heading] : written) {
      if (section == s) {
        return heading;
      }
    }
    return {};
  }

  void section(const Section& s, const std::string& path) {
    const std::string heading = path.empty() ? "top level" : path;
    written.emplace_back(&s, heading);
    out += fmt::format("\n## {}\n\n", path.empty() ? heading : "`" + heading + "`");
    out += "| key | type | unit | allowed | default | meaning |\n";
    out += "|---|---|---|---|---|---|\n";
    std::vector<std::pair<const Section*, std::string>> nested;
    for (const Key& k : s.keys) {
      std::string type = type_word(k.type);
      if (k.section != nullptr) {
        const std::string child = child_path(path, k);
        std::string seen = heading_of(k.section);
        for (const auto& [section, p] : nested) {
          if (seen.empty() && section == k.section) {
            seen = p;
          }
        }
        const std::string target = seen.empty() ? child : seen;
        type += fmt::format(" ([`{}`](#{}))", target, anchor(target));
        if (seen.empty()) {
          nested.emplace_back(k.section, child);
        }
      }
      out += fmt::format("| `{}` | {} | {} | {} | {} | {} |\n", k.name, cell(type), cell(k.unit),
                         cell(allowed(k, s)), cell(default_cell(k)), cell(k.doc));
    }
    for (const auto& [child, child_heading] : nested) {
      if (heading_of(child).empty()) {
        section(*child, child_heading);
      }
    }
  }
};

} // namespace

} // namespace scene

std::string scene_reference() {
  scene::Writer w;
  w.out = "# Scene reference\n\n"
          "<!-- Generated from the scene schema (libpd/src/io/scene/) by `pd run "
          "--print-scene-reference`; do not edit by hand. -->\n\n"
          "Every key of a scene file, section by section: its type, unit, allowed values, default "
          "and meaning, written from the same tables the reader checks a scene against. What the "
          "keys mean together, and why the defaults are what they are, is in "
          "[scenes.md](scenes.md); `pd run --print-defaults` prints the same keys as a commented "
          "scene template.\n\n"
          "*default*: `required` if the key must be given, `one of the group required` if exactly "
          "one of the key and the keys it stands *instead of* must be given, — if the key is "
          "optional without a default. Keys with a dimension (`2D only`) are an error or a "
          "warning in the others.\n";
  w.section(scene::root_section, {});
  return w.out;
}

} // namespace pd
