// Particle files: a body given as a list of particles (discretisation/point_cloud.hpp), in CSV
// or in VTU (ParaView's format: the points and their point data arrays of the same names).
//
// CSV with a header row naming the columns, in any order (unknown columns are ignored):
//   x, y[, z]          position [m] (z required in 3D, not read in 2D)
//   volume             [m³], or instead both
//   mass, density      [kg], [kg/m³]: volume = mass/density
//   h                  optional particle size [m] (default: eq. 115 from the neighbours)
// Empty lines and lines starting with '#' are skipped. Every value must be a finite number;
// volumes and sizes positive; no two particles at the same position. A problem is reported as
// "FILE:ROW: what" with the row counted from 1 at the header line.
#pragma once

#include "libpd/discretisation/point_cloud.hpp"

#include <cstddef>
#include <stdexcept>
#include <string>
#include <string_view>

namespace pd {

class ParticleFileError : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

/// Largest particle file read [bytes].
inline constexpr std::size_t max_particle_file_bytes = std::size_t{1} << 30;

/// Parse the CSV text of a particle file named `name` (for messages) in dimension `dim`.
PointCloud parse_particle_csv(std::string_view text, const std::string& name, int dim);

/// Parse the VTU text of a particle file: the first piece's points, and its point data arrays
/// `volume` (or `mass` and `density`) and optionally `h`, ascii or inline binary (base64, not
/// compressed); the same checks as CSV, a problem named "FILE: point K: what" (K from 1).
PointCloud parse_particle_vtu(std::string_view text, const std::string& name, int dim);

/// Read and parse the file at `path`: CSV (.csv) or VTU (.vtu), by its extension.
PointCloud read_particle_file(const std::string& path, int dim);

} // namespace pd
