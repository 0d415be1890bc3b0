#include "libpd/io/particle_file.hpp"

#include "libpd/core/file_input.hpp"
#include "libpd/core/text.hpp"

#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fmt/format.h>
#include <functional>
#include <map>
#include <optional>
#include <vector>

namespace pd {

namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t' || s.front() == '\r')) {
    s.remove_prefix(1);
  }
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) {
    s.remove_suffix(1);
  }
  return s;
}

std::vector<std::string_view> split(std::string_view line) {
  std::vector<std::string_view> out;
  std::size_t start = 0;
  for (std::size_t i = 0; i <= line.size(); ++i) {
    if (i == line.size() || line[i] == ',') {
      out.push_back(trim(line.substr(start, i - start)));
      start = i + 1;
    }
  }
  return out;
}

/// Column indices of the header's names.
struct Columns {
  std::array<std::optional<std::size_t>, 3> x;
  std::optional<std::size_t> volume, mass, density, h;
};

Columns read_header(std::string_view line, const std::string& name, std::size_t row, int dim) {
  Columns c;
  const auto cells = split(line);
  for (std::size_t i = 0; i < cells.size(); ++i) {
    const std::string_view w = cells[i];
    if (w == "x" || w == "y" || w == "z") {
      c.x[static_cast<std::size_t>(w[0] - 'x')] = i;
    } else if (w == "volume") {
      c.volume = i;
    } else if (w == "mass") {
      c.mass = i;
    } else if (w == "density") {
      c.density = i;
    } else if (w == "h") {
      c.h = i;
    }
  }
  const auto fail = [&](const std::string& what) {
    throw ParticleFileError(fmt::format("{}:{}: {}", name, row, what));
  };
  for (int a = 0; a < dim; ++a) {
    if (!c.x[static_cast<std::size_t>(a)]) {
      fail(fmt::format("the header has no column '{}' (a {}D body needs x, y{})", "xyz"[a], dim,
                       dim == 3 ? ", z" : ""));
    }
  }
  if (!c.volume && !(c.mass && c.density)) {
    fail("the header has no column 'volume' (or both 'mass' and 'density')");
  }
  return c;
}

/// One particle as a file gives it, before the checks every format shares.
struct ParticleValues {
  Vec3 position{0, 0, 0};
  std::optional<double> volume, mass, density, h;
};

/// The checks every particle file passes, then the particle is appended. `fail` throws with the
/// file and the row (CSV) or point (VTU) named; `row_word` names the earlier one of a duplicate.
template <class Fail>
void add_checked(PointCloud& cloud, std::map<std::array<double, 3>, std::size_t>& seen,
                 std::size_t row, const char* row_word, const ParticleValues& in, Fail&& fail) {
  double v = 0;
  if (in.volume) {
    v = *in.volume;
  } else {
    if (!(*in.density > 0)) {
      fail(fmt::format("density {} is not positive", *in.density));
    }
    v = *in.mass / *in.density;
  }
  if (!(v > 0)) {
    fail(fmt::format("volume {} is not positive", v));
  }
  if (in.h) {
    if (!(*in.h > 0)) {
      fail(fmt::format("size h {} is not positive", *in.h));
    }
    cloud.size.push_back(*in.h);
  }
  const Vec3& p = in.position;
  const auto [it, inserted] = seen.emplace(std::array<double, 3>{p[0], p[1], p[2]}, row);
  if (!inserted) {
    fail(fmt::format("duplicate point ({}, {}, {}): {} {} has the same position", p[0], p[1], p[2],
                     row_word, it->second));
  }
  cloud.position.push_back(p);
  cloud.volume.push_back(v);
}

} // namespace

PointCloud parse_particle_csv(std::string_view text, const std::string& name, int dim) {
  PointCloud cloud;
  std::optional<Columns> columns;
  std::map<std::array<double, 3>, std::size_t> seen; // position → row
  std::size_t row = 0;
  std::size_t start = 0;
  while (start <= text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string_view::npos) {
      end = text.size();
    }
    const std::string_view line = trim(text.substr(start, end - start));
    start = end + 1;
    ++row;
    if (line.empty() || line.front() == '#') {
      continue;
    }
    if (!columns) {
      columns = read_header(line, name, row, dim);
      continue;
    }
    const auto fail = [&](const std::string& what) {
      throw ParticleFileError(fmt::format("{}:{}: {}", name, row, what));
    };
    const auto cells = split(line);
    const auto value = [&](std::size_t column, const char* what) {
      if (column >= cells.size() || cells[column].empty()) {
        fail(fmt::format("no value in column '{}'", what));
      }
      double v = 0;
      const std::string_view cell = cells[column];
      const auto [ptr, ec] = std::from_chars(cell.data(), cell.data() + cell.size(), v);
      if (ec != std::errc() || ptr != cell.data() + cell.size()) {
        fail(fmt::format("'{}' in column '{}' is not a number", printable(cell), what));
      }
      if (!std::isfinite(v)) {
        fail(fmt::format("'{}' in column '{}' is not finite", printable(cell), what));
      }
      return v;
    };
    ParticleValues values;
    for (int a = 0; a < dim; ++a) {
      const auto au = static_cast<std::size_t>(a);
      values.position[au] = value(*columns->x[au], a == 0 ? "x" : a == 1 ? "y" : "z");
    }
    if (columns->volume) {
      values.volume = value(*columns->volume, "volume");
    } else {
      values.mass = value(*columns->mass, "mass");
      values.density = value(*columns->density, "density");
    }
    if (columns->h) {
      values.h = value(*columns->h, "h");
    }
    add_checked(cloud, seen, row, "row", values, fail);
  }
  if (!columns) {
    throw ParticleFileError(fmt::format("{}: no header row (x, y[, z], volume …)", name));
  }
  if (cloud.count() == 0) {
    throw ParticleFileError(fmt::format("{}: no particle rows after the header", name));
  }
  return cloud;
}

namespace {

// VTU: just enough XML to read a piece's points and point data. The file is ours to read, not to
// validate as XML: a tag is `<Name attr="value" ...>`, a DataArray's values run to
// `</DataArray>`.

/// The value of attribute `key` in the tag text `tag` (from '<' to '>'), if present.
std::optional<std::string_view> attribute(std::string_view tag, std::string_view key) {
  std::size_t at = 0;
  while ((at = tag.find(key, at)) != std::string_view::npos) {
    const bool starts_word = at > 0 && (tag[at - 1] == ' ' || tag[at - 1] == '\n' ||
                                        tag[at - 1] == '\t' || tag[at - 1] == '\r');
    std::size_t eq = at + key.size();
    if (starts_word && eq < tag.size() && tag[eq] == '=' && eq + 1 < tag.size()) {
      const char quote = tag[eq + 1];
      const std::size_t close = tag.find(quote, eq + 2);
      if ((quote == '"' || quote == '\'') && close != std::string_view::npos) {
        return tag.substr(eq + 2, close - eq - 2);
      }
    }
    at = eq;
  }
  return std::nullopt;
}

struct Tag {
  std::string_view text; ///< from '<' to '>'
  std::size_t end = 0;   ///< offset just past '>'
};

std::optional<Tag> find_tag(std::string_view text, std::string_view name, std::size_t from,
                            std::size_t until = std::string_view::npos) {
  std::string open(1, '<'); // not "<" + name: GCC 12 warns falsely (-Wrestrict) on that
  open += name;
  for (std::size_t at = text.find(open, from); at != std::string_view::npos && at < until;
       at = text.find(open, at + 1)) {
    const std::size_t next = at + open.size();
    if (next < text.size() && (text[next] == ' ' || text[next] == '>' || text[next] == '\n' ||
                               text[next] == '\t' || text[next] == '\r' || text[next] == '/')) {
      const std::size_t close = text.find('>', next);
      if (close == std::string_view::npos) {
        return std::nullopt;
      }
      return Tag{text.substr(at, close - at + 1), close + 1};
    }
  }
  return std::nullopt;
}

std::vector<unsigned char> base64_decode(std::string_view in, const std::function<void()>& bad) {
  std::vector<unsigned char> out;
  std::uint32_t buffer = 0;
  int bits = 0;
  for (char ch : in) {
    int v = 0;
    if (ch >= 'A' && ch <= 'Z') {
      v = ch - 'A';
    } else if (ch >= 'a' && ch <= 'z') {
      v = ch - 'a' + 26;
    } else if (ch >= '0' && ch <= '9') {
      v = ch - '0' + 52;
    } else if (ch == '+') {
      v = 62;
    } else if (ch == '/') {
      v = 63;
    } else if (ch == '=' || ch == ' ' || ch == '\n' || ch == '\r' || ch == '\t') {
      continue;
    } else {
      bad();
    }
    buffer = (buffer << 6) | static_cast<std::uint32_t>(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(static_cast<unsigned char>((buffer >> bits) & 0xFF));
    }
  }
  return out;
}

template <class T>
double load_as_double(const unsigned char* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return static_cast<double>(v);
}

/// The values of one DataArray (tag `tag`, content up to `</DataArray>`), as doubles, checked to
/// be `expected` many and finite. `fail(what)` throws naming the file.
std::vector<double> read_data_array(std::string_view text, const Tag& tag, std::size_t points,
                                    std::size_t components, bool wide_header,
                                    const std::function<void(const std::string&)>& fail) {
  const std::size_t expected = points * components;
  const std::string name(attribute(tag.text, "Name").value_or("points"));
  const std::size_t close = text.find("</DataArray>", tag.end);
  if (close == std::string_view::npos) {
    fail(fmt::format("array '{}' has no closing </DataArray>", name));
  }
  const std::string_view body = text.substr(tag.end, close - tag.end);
  const std::string_view format = attribute(tag.text, "format").value_or("ascii");
  const std::string_view type = attribute(tag.text, "type").value_or("");
  std::vector<double> values;
  if (format == "ascii") {
    std::size_t at = 0;
    while (true) {
      while (at < body.size() && std::isspace(static_cast<unsigned char>(body[at]))) {
        ++at;
      }
      if (at >= body.size()) {
        break;
      }
      std::size_t end = at;
      while (end < body.size() && !std::isspace(static_cast<unsigned char>(body[end]))) {
        ++end;
      }
      double v = 0;
      const auto [ptr, ec] = std::from_chars(body.data() + at, body.data() + end, v);
      if (ec != std::errc() || ptr != body.data() + end) {
        fail(fmt::format("point {}: '{}' in array '{}' is not a number",
                         values.size() / components + 1, printable(body.substr(at, end - at)),
                         printable(name)));
      }
      values.push_back(v);
      at = end;
    }
  } else if (format == "binary") {
    const auto bytes = base64_decode(body, [&] { fail("array '" + name + "': not base64"); });
    const std::size_t header = wide_header ? 8 : 4;
    const std::map<std::string_view, std::size_t> widths{
        {"Float32", 4}, {"Float64", 8}, {"Int32", 4}, {"Int64", 8}, {"UInt32", 4}, {"UInt64", 8}};
    const auto width = widths.find(type);
    if (width == widths.end()) {
      fail(fmt::format("array '{}' has type '{}': Float32, Float64 or (U)Int32/64 expected",
                       printable(name), printable(type)));
    }
    const std::size_t count = bytes.size() < header ? 0 : (bytes.size() - header) / width->second;
    for (std::size_t i = 0; i < count; ++i) {
      const unsigned char* at = bytes.data() + header + i * width->second;
      values.push_back(type == "Float32"   ? load_as_double<float>(at)
                       : type == "Float64" ? load_as_double<double>(at)
                       : type == "Int32"   ? load_as_double<std::int32_t>(at)
                       : type == "Int64"   ? load_as_double<std::int64_t>(at)
                       : type == "UInt32"  ? load_as_double<std::uint32_t>(at)
                                           : load_as_double<std::uint64_t>(at));
    }
  } else {
    fail(fmt::format("array '{}' is stored as '{}': only ascii and inline binary (base64) arrays "
                     "are read (in ParaView: Save Data, Data Mode Ascii)",
                     printable(name), printable(format)));
  }
  if (values.size() != expected) {
    fail(fmt::format("array '{}' has {} values where its points need {}", name, values.size(),
                     expected));
  }
  return values;
}

} // namespace

PointCloud parse_particle_vtu(std::string_view text, const std::string& name, int dim) {
  const auto fail = [&](const std::string& what) {
    throw ParticleFileError(fmt::format("{}: {}", name, what));
  };
  const auto file = find_tag(text, "VTKFile", 0);
  if (!file) {
    fail("no <VTKFile> element: not a VTU file");
  }
  if (attribute(file->text, "compressor")) {
    fail("compressed VTU is not read: save it uncompressed (in ParaView: Compressor Type None)");
  }
  if (attribute(file->text, "byte_order").value_or("LittleEndian") != "LittleEndian") {
    fail("only little-endian VTU is read");
  }
  const bool wide_header = attribute(file->text, "header_type").value_or("UInt32") == "UInt64";
  const auto piece = find_tag(text, "Piece", file->end);
  if (!piece) {
    fail("no <Piece> element");
  }
  std::size_t n = 0;
  const std::string_view count = attribute(piece->text, "NumberOfPoints").value_or("");
  if (std::from_chars(count.data(), count.data() + count.size(), n).ptr !=
          count.data() + count.size() ||
      count.empty() || n == 0) {
    fail(fmt::format("<Piece> has no points (NumberOfPoints=\"{}\")", count));
  }
  const auto points = find_tag(text, "Points", piece->end);
  const auto coords = points ? find_tag(text, "DataArray", points->end) : std::nullopt;
  if (!coords) {
    fail("the piece has no <Points> array");
  }
  const std::vector<double> xyz = read_data_array(text, *coords, n, 3, wide_header, fail);
  std::map<std::string, std::vector<double>> fields;
  if (const auto data = find_tag(text, "PointData", piece->end)) {
    const std::size_t data_end = text.find("</PointData>", data->end);
    for (auto a = find_tag(text, "DataArray", data->end, data_end); a;
         a = find_tag(text, "DataArray", a->end, data_end)) {
      const std::string field(attribute(a->text, "Name").value_or(""));
      if (field == "volume" || field == "mass" || field == "density" || field == "h") {
        fields[field] = read_data_array(text, *a, n, 1, wide_header, fail);
      }
    }
  }
  if (!fields.count("volume") && !(fields.count("mass") && fields.count("density"))) {
    fail("no point data array 'volume' (or both 'mass' and 'density')");
  }
  PointCloud cloud;
  std::map<std::array<double, 3>, std::size_t> seen; // position → point (from 1)
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t point = i + 1;
    const auto fail_at = [&](const std::string& what) {
      fail(fmt::format("point {}: {}", point, what));
    };
    const auto value = [&](const std::string& field, double v) {
      if (!std::isfinite(v)) {
        fail_at(fmt::format("{} in '{}' is not finite", v, field));
      }
      return v;
    };
    ParticleValues values;
    for (int a = 0; a < dim; ++a) {
      values.position[static_cast<std::size_t>(a)] =
          value(a == 0   ? "x"
                : a == 1 ? "y"
                         : "z",
                xyz[3 * i + static_cast<std::size_t>(a)]);
    }
    for (auto [field, slot] : {std::pair{"volume", &values.volume}, std::pair{"mass", &values.mass},
                               std::pair{"density", &values.density}, std::pair{"h", &values.h}}) {
      if (const auto f = fields.find(field); f != fields.end()) {
        *slot = value(field, f->second[i]);
      }
    }
    if (values.volume) {
      values.mass.reset(); // volume wins, as in a CSV file with both
      values.density.reset();
    }
    add_checked(cloud, seen, point, "point", values, fail_at);
  }
  return cloud;
}

PointCloud read_particle_file(const std::string& path, int dim) {
  const std::string extension = std::filesystem::path(path).extension().string();
  if (extension != ".csv" && extension != ".vtu") {
    throw ParticleFileError(
        fmt::format("{}: a particle file is CSV (.csv) or VTU (.vtu), not '{}'", path, extension));
  }
  std::string text;
  try {
    text = read_regular_file(path, max_particle_file_bytes);
  } catch (const FileInputError& e) {
    throw ParticleFileError(fmt::format("{}: {}", path, e.what()));
  }
  return extension == ".vtu" ? parse_particle_vtu(text, path, dim)
                             : parse_particle_csv(text, path, dim);
}

} // namespace pd
