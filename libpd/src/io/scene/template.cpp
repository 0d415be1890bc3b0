// The scene template (`pd run --print-defaults`): every key of the schema with its meaning, unit,
// range and default, optional keys and alternatives commented out. It is generated from the same
// tables the reader checks against, so it is always complete and always a valid scene.
#include "reader.hpp"

#include <sstream>

namespace pd {

namespace scene {

namespace {

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
    facts.push_back("one of: " + join(k.choices, " | "));
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
    const std::string fallback = default_text(k);
    facts.push_back(fallback.empty() ? std::string("optional")
                                     : fmt::format("default {}", fallback));
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
      const std::string fallback = default_text(k);
      out += head + fmt::format("{}: {}\n", k.name, fallback.empty() ? k.example : fallback);
      break;
    }
  }
}

} // namespace

} // namespace scene

std::string scene_template() {
  std::string out =
      "# libpd scene template, generated from the scene schema (pd run --print-defaults).\n"
      "# Every key is listed with its meaning, unit, allowed range and default. Optional keys\n"
      "# and alternatives are commented out: remove the '# ' to use them. See docs/scenes.md.\n";
  scene::write_section(out, scene::root_section, {}, 0, false);
  return out;
}

} // namespace pd