#include "libpd/io/particle_file.hpp"

#include "libpd/core/file_input.hpp"

#include <array>
#include <charconv>
#include <cmath>
#include <fmt/format.h>
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
        fail(fmt::format("'{}' in column '{}' is not a number", cell, what));
      }
      if (!std::isfinite(v)) {
        fail(fmt::format("'{}' in column '{}' is not finite", cell, what));
      }
      return v;
    };
    Vec3 p{0, 0, 0};
    for (int a = 0; a < dim; ++a) {
      const auto au = static_cast<std::size_t>(a);
      p[au] = value(*columns->x[au], a == 0 ? "x" : a == 1 ? "y" : "z");
    }
    double v = 0;
    if (columns->volume) {
      v = value(*columns->volume, "volume");
    } else {
      const double mass = value(*columns->mass, "mass");
      const double density = value(*columns->density, "density");
      if (!(density > 0)) {
        fail(fmt::format("density {} is not positive", density));
      }
      v = mass / density;
    }
    if (!(v > 0)) {
      fail(fmt::format("volume {} is not positive", v));
    }
    if (columns->h) {
      const double h = value(*columns->h, "h");
      if (!(h > 0)) {
        fail(fmt::format("size h {} is not positive", h));
      }
      cloud.size.push_back(h);
    }
    const auto [it, inserted] = seen.emplace(std::array<double, 3>{p[0], p[1], p[2]}, row);
    if (!inserted) {
      fail(fmt::format("duplicate point ({}, {}, {}): row {} has the same position", p[0], p[1],
                       p[2], it->second));
    }
    cloud.position.push_back(p);
    cloud.volume.push_back(v);
  }
  if (!columns) {
    throw ParticleFileError(fmt::format("{}: no header row (x, y[, z], volume …)", name));
  }
  if (cloud.count() == 0) {
    throw ParticleFileError(fmt::format("{}: no particle rows after the header", name));
  }
  return cloud;
}

PointCloud read_particle_csv(const std::string& path, int dim) {
  std::string text;
  try {
    text = read_regular_file(path, max_particle_file_bytes);
  } catch (const FileInputError& e) {
    throw ParticleFileError(fmt::format("{}: {}", path, e.what()));
  }
  return parse_particle_csv(text, path, dim);
}

} // namespace pd
