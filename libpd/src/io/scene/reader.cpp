// The scene reader: text helpers for messages and hints, and the typed reads of `Reader`.
#include "reader.hpp"

#include <algorithm>
#include <cctype>

namespace pd::scene {

std::string join(std::span<const std::string_view> words, std::string_view separator) {
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

std::optional<std::string_view> closest(std::string_view word,
                                        std::span<const std::string_view> candidates) {
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

std::string suggestion(std::string_view word, std::span<const std::string_view> candidates,
                       std::string_view allowed_label) {
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

SourceMark source_mark(const YAML::Node& n) {
  const YAML::Mark m = n.Mark();
  if (m.is_null()) {
    return {};
  }
  return {m.line + 1, m.column + 1};
}

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

std::string format_number(double v) {
  return fmt::format("{}", v);
}

std::string yaml_number(double v) {
  const std::string text = format_number(v);
  const auto e = text.find('e');
  if (e == std::string::npos) {
    return text;
  }
  std::string_view exponent = std::string_view(text).substr(e + 1);
  const bool negative = exponent.starts_with('-');
  if (negative || exponent.starts_with('+')) {
    exponent.remove_prefix(1);
  }
  while (exponent.size() > 1 && exponent.front() == '0') {
    exponent.remove_prefix(1);
  }
  return text.substr(0, e + 1) + (negative ? "-" : "") + std::string(exponent);
}

std::string example_line(const Key& k) {
  const std::string fallback = default_text(k);
  const std::string_view value = fallback.empty() ? k.example : std::string_view(fallback);
  if (k.type == Type::section || k.type == Type::list || k.type == Type::named_map) {
    return fmt::format("'{}:' with its keys", k.name);
  }
  return fmt::format("'{}: {}'", k.name, value);
}

const Key& key_of(const Section& s, std::string_view name) {
  for (const Key& k : s.keys) {
    if (k.name == name) {
      return k;
    }
  }
  throw std::logic_error(fmt::format("scene schema has no key '{}'", name));
}

void Reader::fail(const YAML::Node& at, const std::string& what, const std::string& hint) const {
  throw SceneError(file_, source_mark(at), what, hint);
}

void Reader::warn(const YAML::Node& at, const std::string& what) {
  const SourceMark m = source_mark(at);
  warnings_.push_back(fmt::format("{}:{}:{}: warning: {}", file_, m.line, m.column, what));
}

Fields Reader::open(const YAML::Node& node, const YAML::Node& anchor, const Section& schema,
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
    fail(node, fmt::format("{} must be a map of 'key: value' lines, got {}", what, describe(node)),
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
      fail(k, fmt::format("unknown key '{}' {}", name, f.where()), unknown_key_hint(name, schema));
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

const Entry* Reader::lookup(const Fields& f, std::string_view key) const {
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

Fields Reader::section(const Fields& parent, std::string_view key) const {
  const Key& spec = key_of(*parent.schema, key);
  const Entry* e = lookup(parent, key);
  const std::string prefix = parent.prefix + std::string(key) + ".";
  if (e == nullptr) {
    return open(YAML::Node(YAML::NodeType::Null), parent.anchor, *spec.section, prefix, {}, {});
  }
  return open(e->value, e->name, *spec.section, prefix, {}, parent.label(key));
}

std::vector<YAML::Node> Reader::items(const Fields& f, std::string_view key) const {
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

Fields Reader::item(const YAML::Node& node, const Section& schema, std::string_view kind,
                    std::string_view list, std::size_t index) const {
  std::string owner = fmt::format("{} #{} of '{}'", kind, index + 1, list);
  if (node.IsMap() && node["name"] && node["name"].IsScalar()) {
    owner = fmt::format("{} '{}'", kind, node["name"].Scalar());
  }
  return open(node, node, schema, {}, owner, fmt::format("item #{} of '{}'", index + 1, list));
}

std::optional<std::string> Reader::string(const Fields& f, std::string_view key) const {
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

double Reader::to_number(const YAML::Node& n, const std::string& label, std::string_view unit,
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

void Reader::check_range(const YAML::Node& n, const std::string& label, const Key& k,
                         double v) const {
  if (!k.range.contains(v)) {
    fail(n,
         fmt::format("{} must be {}{}, got {}", label, range_text(k.range), unit_suffix(k.unit),
                     n.Scalar()),
         k.range_hint.empty() ? fmt::format("give a value {}", range_text(k.range))
                              : std::string(k.range_hint));
  }
}

std::optional<double> Reader::number(const Fields& f, std::string_view key) const {
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

std::optional<double> Reader::number_or_auto(const Fields& f, std::string_view key) const {
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

std::optional<bool> Reader::boolean(const Fields& f, std::string_view key) const {
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

int Reader::word(const YAML::Node& n, const std::string& label,
                 std::span<const std::string_view> words) const {
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

std::optional<int> Reader::choice(const Fields& f, std::string_view key) const {
  const Entry* e = lookup(f, key);
  if (e == nullptr) {
    return std::nullopt;
  }
  return word(e->at(), f.label(key), e->key->choices);
}

Vec3 Reader::coordinates(const YAML::Node& n, const std::string& label,
                         std::string_view unit) const {
  const std::string count = dim == 3 ? "3" : fmt::format("{} to 3", dim);
  const std::string example = dim == 1 ? "[0]" : dim == 2 ? "[0, 0]" : "[0, 0, 0]";
  if (!n.IsSequence()) {
    fail(n,
         fmt::format("{} must be a list of {} numbers{}, got {}", label, count, unit_suffix(unit),
                     describe(n)),
         fmt::format("write it as {}", example));
  }
  if (n.size() < static_cast<std::size_t>(dim) || n.size() > 3) {
    fail(n, fmt::format("{} has {} coordinates; a {}D scene needs {}", label, n.size(), dim, count),
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

void Reader::check_in_space(const YAML::Node& n, const std::string& label, const Vec3& v) const {
  for (int c = dim; c < 3; ++c) {
    if (v[c] != 0) {
      fail(n,
           fmt::format("{} has a non-zero {} component in a {}D scene", label, axis_names[c], dim),
           fmt::format("set the {} component to 0 or leave it out", axis_names[c]));
    }
  }
}

std::optional<Vec3> Reader::vector(const Fields& f, std::string_view key) const {
  const Entry* e = lookup(f, key);
  if (e == nullptr) {
    return std::nullopt;
  }
  return coordinates(e->at(), f.label(key), e->key->unit);
}

std::optional<std::array<std::array<double, 3>, 3>> Reader::matrix(const Fields& f,
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

Box Reader::box(const YAML::Node& n, const std::string& label) const {
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
      fail(n, fmt::format("{} has lo > hi in {} ({} > {})", label, axis_names[c], b.lo[c], b.hi[c]),
           "the first corner must be the lower one in every coordinate: swap the values");
    }
  }
  return b;
}

Reader::RegionRead Reader::region(const Fields& f) const {
  RegionRead r;
  if (const Entry* e = f.has("group") ? f.find("group") : nullptr) {
    r.node = e->at();
    const std::string name = *string(f, "group");
    const auto found = mesh_groups.find(name);
    if (found == mesh_groups.end()) {
      std::string names;
      for (const auto& [n, points] : mesh_groups) {
        names += fmt::format("{}'{}'", names.empty() ? "" : ", ", n);
      }
      std::string files;
      for (const std::string& file : mesh_files) {
        files += fmt::format("{}{}", files.empty() ? "" : ", ", file);
      }
      fail(r.node,
           fmt::format("{}: no physical group '{}' in {}", f.label("group"), name,
                       files.empty() ? std::string("the scene (it has no mesh body)") : files),
           names.empty() ? std::string("groups come from 'mesh:' or 'geometry:' bodies' physical "
                                       "groups; this scene has none")
                         : "the mesh bodies' groups: " + names);
    }
    r.region.points = std::make_shared<const std::vector<Vec3>>(found->second);
    r.region.group = name;
    return r;
  }
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

int Reader::component(const YAML::Node& n, const std::string& label) const {
  const int c = word(n, label, axis_names);
  if (c >= dim) {
    fail(n, fmt::format("component '{}' does not exist in a {}D scene", n.Scalar(), dim),
         fmt::format("use {}", join(axes(dim), " or ")));
  }
  return c;
}

std::optional<std::array<bool, 3>> Reader::components(const Fields& f, std::string_view key) const {
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

std::array<std::optional<double>, 3>
Reader::component_values(const Fields& f, std::string_view key,
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

std::vector<std::pair<int, YAML::Node>> Reader::names(const Fields& f, std::string_view key) const {
  const Entry* e = lookup(f, key);
  std::vector<std::pair<int, YAML::Node>> out;
  if (e == nullptr || e->value.IsNull()) {
    return out;
  }
  const std::string label = f.label(key);
  if (!e->value.IsSequence()) {
    fail(e->value, fmt::format("{} must be a list, got {}", label, describe(e->value)),
         fmt::format("write it as [{}]", join(e->key->choices, ", ")));
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

void Reader::warn_foreign_keys(const Fields& f) {
  for (const Entry& e : f.entries) {
    if (e.key->only_dim != 0 && e.key->only_dim != dim) {
      warn(e.name, fmt::format("'{}' applies only to {}D scenes and is ignored in this {}D scene",
                               e.key->name, e.key->only_dim, dim));
    }
  }
}

namespace {

constexpr std::array<const Section*, 13> all_sections{
    &root_section,    &lattice_section, &material_section, &body_section,   &support_section,
    &load_section,    &model_section,   &solver_section,   &steady_section, &arkode_section,
    &initial_section, &probe_section,   &output_section};

} // namespace

std::string Reader::unknown_key_hint(const std::string& name, const Section& schema) {
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
      return fmt::format("did you mean '{}' (a key {})? keys allowed {}: {}", *guess, other->place,
                         schema.place, join(known, ", "));
    }
  }
  return fmt::format("keys allowed {}: {}", schema.place, join(known, ", "));
}

void Reader::check_alternatives(const Fields& f) const {
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

} // namespace pd::scene
