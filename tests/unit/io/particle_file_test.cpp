// Particle files (io/particle_file.hpp): what a good file gives, and each kind of bad content
// refused with the file and the row named.
#include "libpd/io/particle_file.hpp"

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <gtest/gtest.h>
#include <string>
#include <vector>

namespace {

/// The message of the ParticleFileError `text` raises, or "" if it parses.
std::string error_of(const std::string& text, int dim = 2) {
  try {
    pd::parse_particle_csv(text, "p.csv", dim);
  } catch (const pd::ParticleFileError& e) {
    return e.what();
  }
  return "";
}

TEST(ParticleFile, ReadsPositionsVolumesAndSizesInAnyColumnOrder) {
  const pd::PointCloud c = pd::parse_particle_csv("# graded plate\n"
                                                  "volume, y, x, h, note\n"
                                                  "1e-4, 0.5, 0.25, 0.01, a\n"
                                                  "\n"
                                                  "4e-4, 0.5, 0.75, 0.02, b\n",
                                                  "p.csv", 2);
  ASSERT_EQ(c.count(), 2U);
  EXPECT_EQ(c.position[1][0], 0.75);
  EXPECT_EQ(c.position[1][1], 0.5);
  EXPECT_EQ(c.volume[1], 4e-4);
  ASSERT_EQ(c.size.size(), 2U);
  EXPECT_EQ(c.size[0], 0.01);
  // Mass and density instead of volume; no h: sizes are derived later (eq. 115).
  const pd::PointCloud m =
      pd::parse_particle_csv("x,y,z,mass,density\n0,0,0,7.8,7800\n", "p.csv", 3);
  EXPECT_DOUBLE_EQ(m.volume[0], 1e-3);
  EXPECT_TRUE(m.size.empty());
}

TEST(ParticleFile, MissingColumnIsRefusedAtTheHeader) {
  EXPECT_EQ(error_of("# comment\nx,volume\n0,1\n"),
            "p.csv:2: the header has no column 'y' (a 2D body needs x, y)");
  EXPECT_EQ(error_of("x,y,z,volume\n0,0,0,1\n", 2), ""); // z is not read in 2D
  EXPECT_EQ(error_of("x,y,volume\n0,0,1\n", 3),
            "p.csv:1: the header has no column 'z' (a 3D body needs x, y, z)");
  EXPECT_EQ(error_of("x,y,mass\n0,0,1\n"),
            "p.csv:1: the header has no column 'volume' (or both 'mass' and 'density')");
  EXPECT_EQ(error_of("x,y,volume\n0,0.5\n"), "p.csv:2: no value in column 'volume'");
}

TEST(ParticleFile, NonFiniteOrNonNumericValueIsRefusedWithItsRow) {
  EXPECT_EQ(error_of("x,y,volume\n0,0,1\n1,nan,1\n"), "p.csv:3: 'nan' in column 'y' is not finite");
  EXPECT_EQ(error_of("x,y,volume\n0,0,1\n1,0,inf\n"),
            "p.csv:3: 'inf' in column 'volume' is not finite");
  EXPECT_EQ(error_of("x,y,volume\n0,0,1\n1,0,1e999\n"),
            "p.csv:3: '1e999' in column 'volume' is not a number");
  EXPECT_EQ(error_of("x,y,volume\n0,0,1\n1,abc,1\n"),
            "p.csv:3: 'abc' in column 'y' is not a number");
}

// Issue 38, item 11: a NUL byte in a cell cut the message there (what() is a C string).
TEST(ParticleFile, ANulByteInACellIsShownNotCutAt) {
  using namespace std::string_literals;
  EXPECT_EQ(error_of("x,y,volume\n0,0,1\n1,0\0junk,1\n"s),
            "p.csv:3: '0\\x00junk' in column 'y' is not a number");
}

TEST(ParticleFile, NegativeOrZeroVolumeAndSizeAreRefused) {
  EXPECT_EQ(error_of("x,y,volume\n0,0,1\n1,0,-2e-4\n"), "p.csv:3: volume -0.0002 is not positive");
  EXPECT_EQ(error_of("x,y,volume\n0,0,0\n"), "p.csv:2: volume 0 is not positive");
  EXPECT_EQ(error_of("x,y,mass,density\n0,0,1,-5\n"), "p.csv:2: density -5 is not positive");
  EXPECT_EQ(error_of("x,y,volume,h\n0,0,1,-0.1\n"), "p.csv:2: size h -0.1 is not positive");
}

TEST(ParticleFile, DuplicatePointIsRefusedNamingBothRows) {
  EXPECT_EQ(error_of("x,y,volume\n0,0,1\n1,0,1\n# again\n0,0,2\n"),
            "p.csv:5: duplicate point (0, 0, 0): row 2 has the same position");
}

TEST(ParticleFile, EmptyFilesAndUnreadablePathsAreRefused) {
  EXPECT_EQ(error_of("# nothing\n"), "p.csv: no header row (x, y[, z], volume …)");
  EXPECT_EQ(error_of("x,y,volume\n"), "p.csv: no particle rows after the header");
  EXPECT_THROW(pd::read_particle_file("/nonexistent/p.csv", 2), pd::ParticleFileError);
}

// VTU: ParaView's format, ascii or inline binary.

/// A VTU file of `n` points with the given Points array and PointData arrays (already formatted
/// DataArray elements).
std::string vtu(int n, const std::string& points, const std::string& point_data,
                const std::string& file_attributes = "") {
  return "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" "
         "byte_order=\"LittleEndian\"" +
         file_attributes + ">\n<UnstructuredGrid>\n<Piece NumberOfPoints=\"" + std::to_string(n) +
         "\" NumberOfCells=\"0\">\n<PointData>\n" + point_data + "</PointData>\n<Points>\n" +
         points + "</Points>\n<Cells></Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n";
}

std::string ascii_array(const std::string& name, int components, const std::string& values) {
  return "<DataArray type=\"Float64\" Name=\"" + name + "\" NumberOfComponents=\"" +
         std::to_string(components) + "\" format=\"ascii\">\n" + values + "\n</DataArray>\n";
}

/// An inline binary array as VTK writes it: base64 of a UInt32 byte count, then the values.
std::string binary_array(const std::string& name, int components,
                         const std::vector<double>& values) {
  std::vector<unsigned char> bytes(4 + 8 * values.size());
  const auto count = static_cast<std::uint32_t>(8 * values.size());
  std::memcpy(bytes.data(), &count, 4);
  std::memcpy(bytes.data() + 4, values.data(), 8 * values.size());
  static const char* digits = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string b64;
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    std::uint32_t v = static_cast<std::uint32_t>(bytes[i]) << 16;
    v |= i + 1 < bytes.size() ? static_cast<std::uint32_t>(bytes[i + 1]) << 8 : 0;
    v |= i + 2 < bytes.size() ? static_cast<std::uint32_t>(bytes[i + 2]) : 0;
    b64 += digits[(v >> 18) & 63];
    b64 += digits[(v >> 12) & 63];
    b64 += i + 1 < bytes.size() ? digits[(v >> 6) & 63] : '=';
    b64 += i + 2 < bytes.size() ? digits[v & 63] : '=';
  }
  return "<DataArray type=\"Float64\" Name=\"" + name + "\" NumberOfComponents=\"" +
         std::to_string(components) + "\" format=\"binary\">\n" + b64 + "\n</DataArray>\n";
}

std::string vtu_error_of(const std::string& text, int dim = 2) {
  try {
    pd::parse_particle_vtu(text, "p.vtu", dim);
  } catch (const pd::ParticleFileError& e) {
    return e.what();
  }
  return "";
}

const std::string two_points = ascii_array("Points", 3, "0.25 0.5 0  0.75 0.5 0");

TEST(ParticleFileVtu, ReadsAsciiAndInlineBinaryArrays) {
  const pd::PointCloud a = pd::parse_particle_vtu(
      vtu(2, two_points,
          ascii_array("h", 1, "0.01 0.02") + ascii_array("volume", 1, "1e-4 4e-4") +
              ascii_array("velocity", 3, "0 0 0 0 0 0")),
      "p.vtu", 2);
  ASSERT_EQ(a.count(), 2U);
  EXPECT_EQ(a.position[1][0], 0.75);
  EXPECT_EQ(a.volume[1], 4e-4);
  ASSERT_EQ(a.size.size(), 2U);
  EXPECT_EQ(a.size[1], 0.02);
  const pd::PointCloud b = pd::parse_particle_vtu(
      vtu(2, binary_array("Points", 3, {0.25, 0.5, 0.1, 0.75, 0.5, 0.2}),
          binary_array("mass", 1, {7.8, 15.6}) + binary_array("density", 1, {7800, 7800})),
      "p.vtu", 3);
  ASSERT_EQ(b.count(), 2U);
  EXPECT_EQ(b.position[1][2], 0.2);
  EXPECT_DOUBLE_EQ(b.volume[1], 2e-3);
  EXPECT_TRUE(b.size.empty());
}

TEST(ParticleFileVtu, BadContentIsRefusedNamingThePoint) {
  EXPECT_EQ(vtu_error_of(vtu(2, two_points, ascii_array("h", 1, "0.01 0.02"))),
            "p.vtu: no point data array 'volume' (or both 'mass' and 'density')");
  EXPECT_EQ(vtu_error_of(vtu(2, two_points, ascii_array("volume", 1, "1e-4 -2e-4"))),
            "p.vtu: point 2: volume -0.0002 is not positive");
  EXPECT_EQ(vtu_error_of(vtu(2, two_points, ascii_array("volume", 1, "1e-4 nan"))),
            "p.vtu: point 2: nan in 'volume' is not finite");
  EXPECT_EQ(vtu_error_of(vtu(2, two_points, ascii_array("volume", 1, "1e-4 x"))),
            "p.vtu: point 2: 'x' in array 'volume' is not a number");
  EXPECT_EQ(vtu_error_of(vtu(2, two_points, ascii_array("volume", 1, "1e-4"))),
            "p.vtu: array 'volume' has 1 values where its points need 2");
  EXPECT_EQ(vtu_error_of(
                vtu(2, ascii_array("Points", 3, "0 0 0 0 0 0"), ascii_array("volume", 1, "1 1"))),
            "p.vtu: point 2: duplicate point (0, 0, 0): point 1 has the same position");
  EXPECT_EQ(vtu_error_of(vtu(2, two_points, ascii_array("volume", 1, "1 1"),
                             " compressor=\"vtkZLibDataCompressor\"")),
            "p.vtu: compressed VTU is not read: save it uncompressed (in ParaView: Compressor "
            "Type None)");
  EXPECT_EQ(vtu_error_of(vtu(2, two_points,
                             "<DataArray type=\"Float64\" Name=\"volume\" format=\"appended\" "
                             "offset=\"0\"/>\n")),
            "p.vtu: array 'volume' is stored as 'appended': only ascii and inline binary (base64) "
            "arrays are read (in ParaView: Save Data, Data Mode Ascii)");
  EXPECT_EQ(vtu_error_of("x,y,volume\n0,0,1\n"), "p.vtu: no <VTKFile> element: not a VTU file");
}

TEST(ParticleFileVtu, TheFileTypeIsTheExtension) {
  const auto dir = std::filesystem::temp_directory_path();
  std::ofstream(dir / "libpd-particles.vtu")
      << vtu(2, two_points, ascii_array("volume", 1, "1e-4 4e-4"));
  EXPECT_EQ(pd::read_particle_file((dir / "libpd-particles.vtu").string(), 2).count(), 2U);
  std::ofstream(dir / "libpd-particles.txt") << "x,y,volume\n0,0,1\n";
  EXPECT_THROW(pd::read_particle_file((dir / "libpd-particles.txt").string(), 2),
               pd::ParticleFileError);
  std::filesystem::remove(dir / "libpd-particles.vtu");
  std::filesystem::remove(dir / "libpd-particles.txt");
}

} // namespace
