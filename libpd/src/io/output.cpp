#include "libpd/io/output.hpp"

#include <cmath>
#include <fmt/format.h>
#include <fstream>
#include <stdexcept>
#include <unistd.h>

namespace pd {

void write_vtu(const std::filesystem::path& path, const Simulation& sim) {
  const Model& m = sim.model();
  const State& st = sim.state();
  // The body particles this rank owns (all of them in one process); ghosts are not the body.
  std::vector<std::size_t> shown;
  for (std::size_t i = 0; i < m.body_particle_count(); ++i) {
    if (m.ownership.owns(i)) {
      shown.push_back(i);
    }
  }
  const std::size_t n = shown.size();
  auto check = [&](double v, const char* what) {
    if (!std::isfinite(v)) {
      throw std::runtime_error(
          fmt::format("refusing to write {}: non-finite {}", path.string(), what));
    }
  };
  std::string s;
  s.reserve(n * 180);
  s += "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" "
       "byte_order=\"LittleEndian\">\n<UnstructuredGrid>\n";
  s += fmt::format("<Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">\n", n, n);
  s += "<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n";
  for (const std::size_t i : shown) {
    const Vec3& x = m.particles.position[i];
    s += fmt::format("{} {} {}\n", x[0], x[1], x[2]);
  }
  s += "</DataArray></Points>\n<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" "
       "format=\"ascii\">\n";
  for (std::size_t k = 0; k < n; ++k) {
    s += fmt::format("{}\n", k);
  }
  s += "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n";
  for (std::size_t k = 0; k < n; ++k) {
    s += fmt::format("{}\n", k + 1);
  }
  s += "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n";
  for (std::size_t k = 0; k < n; ++k) {
    s += "1\n"; // VTK_VERTEX
  }
  s += "</DataArray>\n</Cells>\n<PointData Vectors=\"displacement\">\n";
  s += "<DataArray type=\"Float64\" Name=\"displacement\" NumberOfComponents=\"3\" "
       "format=\"ascii\">\n";
  for (const std::size_t i : shown) {
    const double u0 = sim.displacement(i, 0), u1 = sim.displacement(i, 1),
                 u2 = sim.displacement(i, 2);
    check(u0 + u1 + u2, "displacement");
    s += fmt::format("{} {} {}\n", u0, u1, u2);
  }
  s += "</DataArray>\n";
  s += "<DataArray type=\"Float64\" Name=\"velocity\" NumberOfComponents=\"3\" format=\"ascii\">\n";
  for (const std::size_t i : shown) {
    const double* v = &st.velocity[3 * i];
    check(v[0] + v[1] + v[2], "velocity");
    s += fmt::format("{} {} {}\n", v[0], v[1], v[2]);
  }
  s += "</DataArray>\n";
  if (!m.state.damage.empty()) {
    s += "<DataArray type=\"Float64\" Name=\"damage\" format=\"ascii\">\n";
    for (const std::size_t i : shown) {
      s += fmt::format("{}\n", m.state.damage[i]);
    }
    s += "</DataArray>\n";
  }
  s += "<DataArray type=\"Int32\" Name=\"material\" format=\"ascii\">\n";
  for (const std::size_t i : shown) {
    s += fmt::format("{}\n", m.particles.material[i]);
  }
  // The particle's index in the whole model: pieces of a run split over ranks join on it.
  s += "</DataArray>\n<DataArray type=\"Int64\" Name=\"global_id\" format=\"ascii\">\n";
  for (const std::size_t i : shown) {
    s += fmt::format("{}\n", m.ownership.global(i));
  }
  s += "</DataArray>\n</PointData>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n";
  write_file_atomically(path, s);
}

std::string pvtu_text(const std::vector<std::string>& pieces, bool damage) {
  std::string s = "<?xml version=\"1.0\"?>\n<VTKFile type=\"PUnstructuredGrid\" "
                  "version=\"0.1\" byte_order=\"LittleEndian\">\n"
                  "<PUnstructuredGrid GhostLevel=\"0\">\n"
                  "<PPoints><PDataArray type=\"Float64\" NumberOfComponents=\"3\"/></PPoints>\n"
                  "<PPointData Vectors=\"displacement\">\n"
                  "<PDataArray type=\"Float64\" Name=\"displacement\" NumberOfComponents=\"3\"/>\n"
                  "<PDataArray type=\"Float64\" Name=\"velocity\" NumberOfComponents=\"3\"/>\n";
  if (damage) {
    s += "<PDataArray type=\"Float64\" Name=\"damage\"/>\n";
  }
  s += "<PDataArray type=\"Int32\" Name=\"material\"/>\n"
       "<PDataArray type=\"Int64\" Name=\"global_id\"/>\n</PPointData>\n";
  for (const std::string& piece : pieces) {
    s += fmt::format("<Piece Source=\"{}\"/>\n", piece);
  }
  s += "</PUnstructuredGrid>\n</VTKFile>\n";
  return s;
}

} // namespace pd
