#include "libpd/output.hpp"

#include <cmath>
#include <fmt/format.h>
#include <fstream>
#include <stdexcept>
#include <unistd.h>

namespace pd {

void write_file_atomically(const std::filesystem::path& path, const std::string& content) {
  if (path.has_parent_path()) {
    std::filesystem::create_directories(path.parent_path());
  }
  const std::filesystem::path tmp =
      path.string() + fmt::format(".tmp-{}", static_cast<long>(::getpid()));
  try {
    {
      std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
      if (!out) {
        throw std::runtime_error("cannot write " + tmp.string());
      }
      out << content;
      out.flush();
      if (!out) {
        throw std::runtime_error("error while writing " + tmp.string());
      }
    }
    std::filesystem::rename(tmp, path);
  } catch (...) {
    std::error_code ignored;
    std::filesystem::remove(tmp, ignored); // never leave a stray temporary behind
    throw;
  }
}

Json& Json::operator[](const std::string& key) {
  if (std::holds_alternative<std::nullptr_t>(value_)) {
    value_ = Object{};
  }
  auto& obj = std::get<Object>(value_);
  for (auto& [k, v] : obj) {
    if (k == key) {
      return v;
    }
  }
  obj.emplace_back(key, Json{});
  return obj.back().second;
}

const Json* Json::find(const std::string& key) const {
  if (const Object* o = std::get_if<Object>(&value_)) {
    for (const auto& [k, v] : *o) {
      if (k == key) {
        return &v;
      }
    }
  }
  return nullptr;
}

std::optional<bool> Json::boolean() const {
  if (const bool* b = std::get_if<bool>(&value_)) {
    return *b;
  }
  return std::nullopt;
}

std::optional<double> Json::number() const {
  if (const double* d = std::get_if<double>(&value_)) {
    return *d;
  }
  if (const long long* i = std::get_if<long long>(&value_)) {
    return static_cast<double>(*i);
  }
  return std::nullopt;
}

void Json::push_back(Json v) {
  if (std::holds_alternative<std::nullptr_t>(value_)) {
    value_ = Array{};
  }
  std::get<Array>(value_).push_back(std::move(v));
}

namespace {
std::string quote(const std::string& s) {
  std::string out = "\"";
  for (char ch : s) {
    switch (ch) {
    case '"':
      out += "\\\"";
      break;
    case '\\':
      out += "\\\\";
      break;
    case '\n':
      out += "\\n";
      break;
    case '\t':
      out += "\\t";
      break;
    default:
      if (static_cast<unsigned char>(ch) < 0x20) {
        out += fmt::format("\\u{:04x}", static_cast<int>(ch));
      } else {
        out += ch;
      }
    }
  }
  return out + "\"";
}
} // namespace

void Json::dump_to(std::string& out, int indent, int depth) const {
  const std::string pad(static_cast<std::size_t>(indent * (depth + 1)), ' ');
  const std::string close_pad(static_cast<std::size_t>(indent * depth), ' ');
  const char* nl = indent > 0 ? "\n" : "";
  if (std::holds_alternative<std::nullptr_t>(value_)) {
    out += "null";
  } else if (const bool* b = std::get_if<bool>(&value_)) {
    out += *b ? "true" : "false";
  } else if (const double* d = std::get_if<double>(&value_)) {
    out += std::isfinite(*d) ? fmt::format("{}", *d) : "null";
  } else if (const long long* i = std::get_if<long long>(&value_)) {
    out += fmt::format("{}", *i);
  } else if (const std::string* s = std::get_if<std::string>(&value_)) {
    out += quote(*s);
  } else if (const Array* a = std::get_if<Array>(&value_)) {
    // Arrays of plain numbers stay on one line: deflection lines remain readable.
    bool flat = true;
    for (const Json& v : *a) {
      flat = flat && !v.is_object() && !std::holds_alternative<Array>(v.value_);
    }
    out += "[";
    for (std::size_t k = 0; k < a->size(); ++k) {
      if (!flat) {
        out += nl + pad;
      }
      (*a)[k].dump_to(out, indent, depth + 1);
      if (k + 1 < a->size()) {
        out += flat ? ", " : ",";
      }
    }
    if (!flat && !a->empty()) {
      out += nl + close_pad;
    }
    out += "]";
  } else if (const Object* o = std::get_if<Object>(&value_)) {
    out += "{";
    std::size_t k = 0;
    for (const auto& [key, member] : *o) {
      out += nl + pad + quote(key) + (indent > 0 ? ": " : ":");
      member.dump_to(out, indent, depth + 1);
      if (++k < o->size()) {
        out += ",";
      }
    }
    if (!o->empty()) {
      out += nl + close_pad;
    }
    out += "}";
  }
}

std::string Json::dump(int indent) const {
  std::string out;
  dump_to(out, indent, 0);
  return out + "\n";
}

void write_vtu(const std::filesystem::path& path, const Simulation& sim) {
  const Model& m = sim.model();
  const State& st = sim.state();
  const std::size_t n = m.size();
  auto check = [&](double v, const char* what) {
    if (!std::isfinite(v)) {
      throw std::runtime_error(
          fmt::format("refusing to write {}: non-finite {}", path.string(), what));
    }
  };
  std::string s;
  s.reserve(n * 160);
  s += "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" "
       "byte_order=\"LittleEndian\">\n<UnstructuredGrid>\n";
  s += fmt::format("<Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">\n", n, n);
  s += "<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n";
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3& x = m.particles.position[i];
    s += fmt::format("{} {} {}\n", x[0], x[1], x[2]);
  }
  s += "</DataArray></Points>\n<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" "
       "format=\"ascii\">\n";
  for (std::size_t i = 0; i < n; ++i) {
    s += fmt::format("{}\n", i);
  }
  s += "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n";
  for (std::size_t i = 0; i < n; ++i) {
    s += fmt::format("{}\n", i + 1);
  }
  s += "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n";
  for (std::size_t i = 0; i < n; ++i) {
    s += "1\n"; // VTK_VERTEX
  }
  s += "</DataArray>\n</Cells>\n<PointData Vectors=\"displacement\">\n";
  s += "<DataArray type=\"Float64\" Name=\"displacement\" NumberOfComponents=\"3\" "
       "format=\"ascii\">\n";
  for (std::size_t i = 0; i < n; ++i) {
    const double u0 = sim.displacement(i, 0), u1 = sim.displacement(i, 1),
                 u2 = sim.displacement(i, 2);
    check(u0 + u1 + u2, "displacement");
    s += fmt::format("{} {} {}\n", u0, u1, u2);
  }
  s += "</DataArray>\n";
  s += "<DataArray type=\"Float64\" Name=\"velocity\" NumberOfComponents=\"3\" format=\"ascii\">\n";
  for (std::size_t i = 0; i < n; ++i) {
    const double* v = &st.velocity[3 * i];
    check(v[0] + v[1] + v[2], "velocity");
    s += fmt::format("{} {} {}\n", v[0], v[1], v[2]);
  }
  s += "</DataArray>\n";
  if (!m.state.damage.empty()) {
    s += "<DataArray type=\"Float64\" Name=\"damage\" format=\"ascii\">\n";
    for (std::size_t i = 0; i < n; ++i) {
      s += fmt::format("{}\n", m.state.damage[i]);
    }
    s += "</DataArray>\n";
  }
  s += "<DataArray type=\"Int32\" Name=\"material\" format=\"ascii\">\n";
  for (std::size_t i = 0; i < n; ++i) {
    s += fmt::format("{}\n", m.particles.material[i]);
  }
  s += "</DataArray>\n</PointData>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n";
  write_file_atomically(path, s);
}

} // namespace pd
